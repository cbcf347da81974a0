"""A database written by gaitpref 0.1.0 (``tests/fixtures``) opens after ``db upgrade`` and replays
to what 0.1.0 recorded: the same posterior, trials, answers and pending query."""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from gaitpref import Session
from gaitpref.storage.sql import upgrade_database

FIXTURES = Path(__file__).resolve().parent.parent / "fixtures"
sys.path.insert(0, str(FIXTURES))
from make_db_0_1_0 import digest, summary  # noqa: E402

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
        np.testing.assert_array_equal(np.asarray(post.mean), np.asarray(want["mean"]))
        assert digest(post.variance) == want["variance_sha256"]
    for key in ("subject", "status", "last_seq", "trials", "comparisons", "suggestions"):
        assert got[key] == want[key], key
    for key in ("pending", "validations", "notes"):
        assert got[key] == want[key], key
