"""A log written on another machine replays: re-derived numbers are compared within rounding,
and a refit's numbers are then taken from the log, so nothing after drifts from the recording.

Another machine's BLAS (summation order, SIMD width) rounds the last bits differently; the
0.1.0 fixture database, written on one machine, differed in the 16th digit of a fitted
lengthscale on another and did not open.  Here the other machine is simulated by nudging a
logged refit by a few units in the last place.
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gaitpref import Session
from gaitpref.errors import ReplayError
from gaitpref.sessions.events import same_value
from tests.sessions.test_refit_log import FITTED, _answered


@pytest.mark.parametrize(
    ("logged", "derived", "same"),
    [
        (0.025095872673254308, 0.02509587267325432, True),  # the 0.1.0 fixture's difference
        (1.0, 1.0 + 1e-12, True),
        (1.0, 1.0 + 1e-6, False),
        (0.0, 1e-13, True),
        (0.0, 1e-9, False),
        (3, 3, True),
        (3, 4, False),
        (True, 1, False),  # a flag is not a number
        ([0.1, [0.2, 0.3]], [0.1, [0.2, 0.3 + 1e-14]], True),
        ([0.1, 0.2], [0.1], False),
        ({"a": 1.0}, {"a": 1.0 + 1e-13}, True),
        ({"a": 1.0}, {"b": 1.0}, False),
        ("first", "first", True),
        ("first", "second", False),
        (None, 0.0, False),
    ],
)
def test_numbers_agree_within_rounding_and_nothing_else_does(
    logged: object, derived: object, same: bool
) -> None:
    assert same_value(logged, derived) is same


def rewrite_logged(
    db: Path, session_id: int, kind: str, change: Callable[[dict[str, Any]], None], last: bool
) -> dict[str, Any]:
    """Change the payload of the session's first (or ``last``) logged event of ``kind`` in the
    database file, as another machine's rounding would have left it; the changed payload."""
    with sqlite3.connect(db) as raw:
        raw.execute("DROP TRIGGER IF EXISTS events_no_update")
        seq, text = raw.execute(
            "SELECT seq, payload FROM events WHERE session_id = ? AND kind = ? "
            f"ORDER BY seq {'DESC' if last else 'ASC'} LIMIT 1",
            (session_id, kind),
        ).fetchone()
        payload: dict[str, Any] = json.loads(text)
        change(payload)
        raw.execute(
            "UPDATE events SET payload = ? WHERE session_id = ? AND seq = ?",
            (json.dumps(payload), session_id, seq),
        )
    return payload


def _nudge(db: Path, session_id: int, factor: float) -> list[float]:
    """Multiply the first lengthscale of the session's first logged refit by ``factor``; the
    nudged ``after`` values."""

    def change(payload: dict[str, Any]) -> None:
        payload["after"]["lengthscale"][0] *= factor

    after: list[float] = rewrite_logged(db, session_id, "hyperparameters_refit", change, False)[
        "after"
    ]["lengthscale"]
    return after


def test_a_refit_rounded_elsewhere_replays_and_its_logged_numbers_are_used(
    tmp_path: Path,
) -> None:
    url, session, subject = _answered(tmp_path, FITTED, 7)  # refits after answers 3 and 6
    trials = [e.payload["action"] for e in session.events() if e.kind == "trial_executed"]
    mean = np.asarray(session.posterior().mean).copy()
    session.close()
    nudged = _nudge(tmp_path / "refit.db", session.id, 1 + 4e-16)
    assert nudged[0] != session._state.loop.refits[0].after.lengthscale[0]

    again = Session.open(url, session.id)  # replays; the first refit differs in the last bits
    first = again._state.loop.refits[0]
    assert list(first.after.lengthscale) == nudged  # the log's numbers, bit for bit
    assert again._state.loop.refits[1].before == first.after  # the next refit started there
    np.testing.assert_allclose(again.posterior().mean, mean, rtol=1e-9, atol=1e-15)
    q = again.next_query()
    again.answer(q.id, *subject.respond(q))
    assert [e.payload["action"] for e in again.events() if e.kind == "trial_executed"][
        :-1
    ] == trials
    again.undo()  # undoing past the adopted refit goes back to what it started from
    again.undo()
    again.undo()
    assert again._state.loop.hyper == first.after
    again.close()


def test_a_refit_that_differs_beyond_rounding_still_stops_replay(tmp_path: Path) -> None:
    url, session, _ = _answered(tmp_path, FITTED, 4)
    session.close()
    nudged = _nudge(tmp_path / "refit.db", session.id, 1 + 1e-6)
    with pytest.raises(ReplayError, match="lengthscale") as err:
        Session.open(url, session.id)
    assert repr(nudged[0]) in str(err.value)
