"""``--db`` (or ``$GAITPREF_DB``) naming an in-memory database is refused by every ``session``
and ``db`` command, naming the option.

``sqlite:///`` with no path (as ``--db sqlite:///$UNSET`` gives), ``sqlite://``,
``sqlite:///:memory:`` and ``memory://`` were taken: ``session new`` wrote the session into a
database that was gone when the command ended, and printed its id and how to run it;
``db upgrade`` reported an upgraded schema.  Only ``db upgrade --db memory://`` was refused.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from gaitpref.cli import app
from gaitpref.storage import ENV_VAR

MEMORY = ["sqlite:///", "sqlite://", "sqlite:///:memory:", "sqlite+pysqlite:///", "memory://"]
NEW = ["session", "new", "--config", "exo-1d-step-length", "--subject", "S01"]


def _text(output: str) -> str:
    return " ".join(output.split())  # Rich wraps long lines


@pytest.mark.parametrize("url", MEMORY)
@pytest.mark.parametrize(
    "command",
    [
        NEW,
        ["db", "upgrade"],
        ["db", "check"],
        ["db", "backup", "copy.db"],
        ["session", "list"],
        ["session", "show", "1"],
    ],
)
def test_an_in_memory_database_is_refused_naming_db(url: str, command: list[str]) -> None:
    result = CliRunner().invoke(app, [*command, "--db", url])
    assert result.exit_code == 2, result.output
    text = _text(result.output)
    assert "Invalid value for '--db'" in text and "is an in-memory database" in text
    assert "session 1" not in text


def test_from_the_environment_too(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(ENV_VAR, "sqlite:///")
    result = CliRunner().invoke(app, NEW)
    assert result.exit_code == 2, result.output
    assert f"Invalid value for '${ENV_VAR}'" in _text(result.output)


def test_a_database_file_is_taken(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(ENV_VAR, raising=False)
    for db in (str(tmp_path / "a.db"), f"sqlite:///{tmp_path / 'b.db'}"):
        result = CliRunner().invoke(app, [*NEW, "--db", db])
        assert result.exit_code == 0, result.output
        assert "session 1" in result.output
    monkeypatch.chdir(tmp_path)  # no --db: ./gaitpref.db
    assert CliRunner().invoke(app, NEW).exit_code == 0
    assert (tmp_path / "gaitpref.db").is_file()
