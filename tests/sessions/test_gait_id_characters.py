"""A new session refuses gait ids holding control, format or line-break characters.

A gait id is shown with each trial by the terminal loop and the console and written to exports.
``session new --gait-ids FILE`` (or ``Session.create(..., library=[...])``) took an id such as
``"G\\x1b[2J"`` (ESC: clears the operator's terminal) as it was.  Now the id is refused naming
it and its action (as a config name is, ``config/parse.py``); a session stored with one by an
earlier release reopens as it was.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner, Result

from gaitpref import Session
from gaitpref.cli import app
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG

IDS = [f"G{a}" for a in range(15)]  # the config's 15 step lengths


@pytest.mark.parametrize("bad", ["G\x1b[2J", "G\x00", "G\tx", "G\u202ex", "G\u2028x", "G\n"])
def test_a_new_session_refuses_hidden_characters_in_a_gait_id(bad: str) -> None:
    db = MemoryStorage()
    with pytest.raises(ValueError, match=r"\(action 14\) holds U\+") as err:
        Session.create(db, CONFIG, "S01", library=[*IDS[:14], bad])
    assert bad not in str(err.value)  # shown escaped
    assert Session.list_sessions(db) == []


def test_printable_ids_are_taken() -> None:
    ids = [*IDS[:13], "Übung 2 – 步长", "exo (v2)"]
    with Session.create(MemoryStorage(), CONFIG, "S01", library=ids) as s:
        assert s.gait_ids == ids


def test_session_new_refuses_it(tmp_path: Path) -> None:
    path = tmp_path / "ids.txt"
    path.write_text("\n".join([*IDS[:14], "G\x1b[2J"]) + "\n", encoding="utf-8")
    db = tmp_path / "lab.db"
    args = ["session", "new", "--config", CONFIG, "--subject", "S01", "--db", str(db)]
    result = CliRunner().invoke(app, [*args, "--gait-ids", str(path)])
    assert result.exit_code == 2, result.output
    assert "gait ids must not hold control" in " ".join(result.output.split())
    assert "\x1b" not in result.output


def test_a_session_stored_with_such_an_id_reopens(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import gaitpref.sessions.stored_config

    url = f"sqlite:///{tmp_path / 'old.db'}"
    ids = [*IDS[:14], "G\x1b[2J"]
    with monkeypatch.context() as m:  # as earlier releases took it
        m.setattr(gaitpref.sessions.stored_config, "hidden_in", lambda text, name=False: [])
        s = Session.create(url, CONFIG, "S01", library=ids)
    s.close()
    with Session.open(url, s.id) as again:
        assert again.gait_ids == ids


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"G0\n\xff\n", "is not UTF-8 text (byte 3: invalid start byte)"),
        (None, "is a folder; give a text file"),
        ("missing", "does not exist; give a text file"),
    ],
)
def test_session_new_names_a_gait_id_file_it_cannot_read(
    tmp_path: Path, content: bytes | str | None, message: str
) -> None:
    """A file not in UTF-8 was refused as "'utf-8' codec can't decode byte 0xff ...", naming
    neither the option nor the file; a folder as a file that "does not exist"."""
    path = tmp_path / "ids.txt"
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif content is None:
        path.mkdir()
    _refused(tmp_path, path, message)


def test_a_gait_id_given_twice_is_refused_naming_it() -> None:
    """Two gaits under one id were taken: answers, flags and exports named either."""
    db = MemoryStorage()
    with pytest.raises(ValueError, match=r"gait id 'G3' is given twice \(actions 3 and 14\)"):
        Session.create(db, CONFIG, "S01", library=[*IDS[:14], "G3"])
    assert Session.list_sessions(db) == []


def test_a_gait_id_over_the_limit_is_refused_naming_its_action() -> None:
    """A 5,000 character id was taken, and shown whole with every trial."""
    from gaitpref.gaits.library import MAX_GAIT_ID

    db = MemoryStorage()
    Session.create(db, CONFIG, "S01", library=[*IDS[:14], "g" * MAX_GAIT_ID]).close()
    with pytest.raises(ValueError, match=r"\(action 14\) has 201 characters: .* at most 200"):
        Session.create(db, CONFIG, "S01", library=[*IDS[:14], "g" * (MAX_GAIT_ID + 1)])
    assert len(Session.list_sessions(db)) == 1


def test_session_new_refuses_a_gait_id_file_over_the_limit(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The --gait-ids file was read whole, whatever its size."""
    from gaitpref.gaits import library_io

    path = tmp_path / "ids.txt"
    path.write_text("\n".join(IDS) + "\n", encoding="utf-8")
    monkeypatch.setattr(library_io, "MAX_LIBRARY_BYTES", path.stat().st_size - 1)
    _refused(tmp_path, path, "is larger than")
    monkeypatch.setattr(library_io, "MAX_LIBRARY_BYTES", path.stat().st_size)
    result = _session_new(tmp_path, path)
    assert result.exit_code == 0, result.output


def _session_new(tmp_path: Path, ids: Path) -> Result:
    db = tmp_path / "lab.db"
    args = ["session", "new", "--config", CONFIG, "--subject", "S01", "--db", str(db)]
    return CliRunner().invoke(app, [*args, "--gait-ids", str(ids)])


def _refused(tmp_path: Path, ids: Path, message: str) -> None:
    """``session new --gait-ids IDS`` is a usage error naming the option, the file and
    ``message``, and no database is made."""
    result = _session_new(tmp_path, ids)
    assert result.exit_code == 2, result.output
    assert f"--gait-ids {str(ids)!r} {message}" in " ".join(result.output.split())
    assert not (tmp_path / "lab.db").exists()
