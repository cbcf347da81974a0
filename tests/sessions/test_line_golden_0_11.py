"""Line-path sessions written by commit 1c54533 (config defaults 0.11, ``tests/fixtures/
line-0.11.db``, ``make_db_line_0_11.py``) replay to what it recorded: the same queries, lines,
point tables and posteriors, after defaults 0.12 (``[cospar] line_coactive``) and the tables'
shared buffer (``PointSet.extended(share=True)``); and they go on."""

from __future__ import annotations

import json
import shutil
import sqlite3
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gaitpref import ReplayError, Session
from gaitpref.config import schema
from tests.fixtures.make_db_line_0_11 import (
    CONTINUOUS,
    CORNER,
    RATED_UTILITY,
    answer_next,
    digest,
    summary,
)

FIXTURES = Path(__file__).resolve().parent.parent / "fixtures"
EXPECTED: dict[str, Any] = json.loads((FIXTURES / "line-0.11.json").read_text())
SESSIONS = list(EXPECTED["sessions"])
#: each session's defaults version as recorded, and the line settings it replays with
RECORDED = {
    "coactive": ("0.11", "fold"),
    "clipped": ("0.10", "clip"),
    "rated": ("0.11", "fold"),
}


@pytest.fixture
def old_db(tmp_path: Path) -> str:
    path = tmp_path / "line.db"
    shutil.copy(FIXTURES / "line-0.11.db", path)
    return f"sqlite:///{path}"


def _rows(url: str) -> list[tuple[object, ...]]:
    with sqlite3.connect(url.removeprefix("sqlite:///")) as conn:
        return conn.execute(
            "SELECT session_id, seq, kind, payload, at FROM events ORDER BY session_id, seq"
        ).fetchall()


def test_the_fixture_was_written_by_the_0_11_defaults() -> None:
    assert EXPECTED["defaults_version"] == "0.11" and list(RECORDED) == SESSIONS
    assert (FIXTURES / "line-0.11.db").stat().st_size < 1_000_000


@pytest.mark.parametrize("name", SESSIONS)
def test_replays_to_what_0_11_recorded(old_db: str, name: str) -> None:
    want = EXPECTED["sessions"][name]
    version, boundary = RECORDED[name]
    before = _rows(old_db)
    with Session.open(old_db, want["id"]) as s:  # replay re-derives and checks every event
        assert s.record.meta == want["meta"]
        assert s.record.meta["config_defaults"] == version
        assert s.config.defaults_version == version
        assert s.config.subspace == "line"
        assert s.config.line.coactive == "recorded"  # every suggestion, as before 0.12
        assert s.config.line.boundary == boundary
        got = summary(s)
        post = s.posterior()
    assert _rows(old_db) == before  # replaying wrote nothing
    for key in ("subject", "status", "last_seq", "queries", "trials", "pending"):
        assert got[key] == want[key], key
    table = np.asarray(got["table"])  # the points the lines added, row for row, to the bit
    assert table.shape == np.asarray(want["table"]).shape
    assert np.array_equal(table, want["table"])
    # the same numbers up to the rounding of this machine's BLAS (as for the 0.1.0 fixture);
    # bit for bit, the variance and the confidence too, where it rounds alike (as where written)
    mean = np.asarray(post.mean)
    np.testing.assert_allclose(mean, want["mean"], rtol=1e-9, atol=1e-15)
    assert got["confidence"]["recommended"] == want["confidence"]["recommended"]
    if np.array_equal(mean, want["mean"]):
        assert digest(post.variance) == want["variance_sha256"]
        assert got["confidence"] == want["confidence"]
    else:
        assert got["confidence"]["probability"] == pytest.approx(
            want["confidence"]["probability"], abs=0.01
        )


def test_the_sessions_cover_what_changed(old_db: str) -> None:
    """What the fixture holds: excluded trials whose suggestion steered the next line (the
    coactive session), an answer undone, ratings, refits and a region of avoidance that holds a
    gait tried (the rated session)."""
    coactive = EXPECTED["sessions"]["coactive"]
    assert [t[2] for t in coactive["trials"] if t[2]] == ["stumble", "device_fault"]
    assert sum(t[3] for t in coactive["trials"]) == 1  # one undone
    assert coactive["pending"] is not None
    with Session.open(old_db, EXPECTED["sessions"]["rated"]["id"]) as s:
        kinds = {e.kind for e in s.events()}
        assert {"rating_given", "hyperparameters_refit"} <= kinds
        assert s.config.safety.avoid == 1  # "very bad": a region of avoidance
        allowed = s._state.loop.allowed()  # one gait tried is in it
        assert allowed is not None and allowed.sum() == len(allowed) - 1


@pytest.mark.parametrize(
    ("name", "version", "settings", "seq", "what"),
    [
        ("coactive", "0.11", {}, 19, "line.direction"),
        ("clipped", "0.10", {"line_coactive": "recorded"}, 2, "points"),
        ("clipped", "0.10", {"line_boundary": "clip"}, 26, "points"),
    ],
    ids=["coactive-kept", "clipped-fold", "clipped-kept"],
)
def test_with_the_0_12_line_defaults_the_sessions_would_not_replay(
    old_db: str,
    monkeypatch: pytest.MonkeyPatch,
    name: str,
    version: str,
    settings: dict[str, str],
    seq: int,
    what: str,
) -> None:
    """The fixture depends on both settings: read with the new default for either
    (``line_coactive = "kept"``, ``line_boundary = "fold"``) the log and replay part."""
    monkeypatch.setitem(schema.EARLIER_DEFAULTS[version], "cospar", settings)
    with pytest.raises(ReplayError, match=rf"event {seq} \(query_issued\):\n  {what}"):
        Session.open(old_db, EXPECTED["sessions"][name]["id"])


UTILITIES = {"coactive": CONTINUOUS, "clipped": CORNER, "rated": RATED_UTILITY}
FEATURES = {
    "coactive": ("step_length", "step_duration", "step_width"),
    "clipped": tuple(f"f{k}" for k in range(7)),
    "rated": (),
}


@pytest.mark.parametrize("name", SESSIONS)
def test_the_current_code_goes_on_with_a_recorded_session(old_db: str, name: str) -> None:
    """Two more answers (the pending query first, where there is one) and a query after them,
    under the recorded line settings; the session then replays again to the same state."""
    want = EXPECTED["sessions"][name]
    with Session.open(old_db, want["id"]) as s:
        for k in range(2):
            answer_next(s, UTILITIES[name], 9 + k, FEATURES[name], rated=name == "rated")
        q = s.next_query()
        issued = [e.payload for e in s.events() if e.kind == "query_issued"]
        assert len(issued) == len(want["queries"]) + (3 if want["pending"] is None else 2)
        n = len(want["queries"])
        assert [(p["actions"], p["line"]["seed"]) for p in issued[:n]] == [
            (w["actions"], w["line_seed"]) for w in want["queries"]
        ]
        mean = np.asarray(s.posterior().mean)
        assert len(s.space) > len(want["table"]) and q.points
    with Session.open(old_db, want["id"]) as again:
        assert again.pending == q and again.pending is not None
        assert again.pending.points == q.points
        assert np.array_equal(np.asarray(again.posterior().mean), mean)
        assert again.config.line.coactive == "recorded"
