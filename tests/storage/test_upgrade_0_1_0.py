"""A database written by gaitpref 0.1.0 (``tests/fixtures``) opens after ``db upgrade`` and replays
to what 0.1.0 recorded: the same posterior, trials, answers and pending query."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from gaitpref import Session
from gaitpref.storage.sql import upgrade_database
from tests.fixtures.make_db_0_1_0 import digest, summary

FIXTURES = Path(__file__).resolve().parent.parent / "fixtures"

EXPECTED = json.loads((FIXTURES / "gaitpref-0.1.0.json").read_text())


@pytest.fixture
def old_db(tmp_path: Path) -> str:
    path = tmp_path / "old.db"
    shutil.copy(FIXTURES / "gaitpref-0.1.0.db", path)
    return f"sqlite:///{path}"


def _upgrade(url: str) -> None:
    upgrade_database(url)


@pytest.mark.parametrize("index", [0, 1])
def test_replays_to_what_0_1_0_recorded(old_db: str, index: int) -> None:
    _upgrade(old_db)
    want = EXPECTED["sessions"][index]
    with Session.open(old_db, want["id"]) as session:
        got = summary(session)
        post = session.posterior()
        mean = np.asarray(post.mean)
        # the same numbers up to the rounding of this machine's BLAS (replay takes the refits'
        # numbers from the log, so nothing drifts further); bit for bit where it rounds alike
        np.testing.assert_allclose(mean, want["mean"], rtol=1e-9, atol=1e-15)
        if np.array_equal(mean, want["mean"]):
            assert digest(post.variance) == want["variance_sha256"]
    for key in ("subject", "status", "last_seq", "trials", "comparisons", "suggestions"):
        assert got[key] == want[key], key
    for key in ("pending", "validations", "notes"):
        assert got[key] == want[key], key


def _rows(path: str) -> list[tuple[object, ...]]:
    import sqlite3

    with sqlite3.connect(path) as conn:
        return conn.execute(
            "SELECT session_id, seq, kind, payload, at FROM events ORDER BY session_id, seq"
        ).fetchall()


def test_needs_db_upgrade_first_and_the_upgrade_rewrites_no_event(old_db: str) -> None:
    from gaitpref.storage import SchemaError

    path = old_db.removeprefix("sqlite:///")
    before = _rows(path)
    with pytest.raises(SchemaError, match="gaitpref db upgrade"):
        Session.open(old_db, 1)
    assert _rows(path) == before  # refusing to open wrote nothing
    _upgrade(old_db)
    assert _rows(path) == before  # every stored event byte for byte
    with Session.open(old_db, 1) as session:
        assert {e.version for e in session.events()} == {1}


def test_db_upgrade_from_the_cli(old_db: str) -> None:
    from typer.testing import CliRunner

    from gaitpref.cli import app

    result = CliRunner().invoke(app, ["db", "upgrade", "--db", old_db])
    assert result.exit_code == 0, result.output
    with Session.open(old_db, EXPECTED["sessions"][1]["id"]) as session:
        assert summary(session)["trials"] == EXPECTED["sessions"][1]["trials"]
