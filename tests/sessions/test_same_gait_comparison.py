"""A comparison of a gait with itself, as the console asked it until its pairs followed the
terminal's rule (``SessionQuery.pairs``): no query asks it now, but ``Session.answer`` still
takes it (stored, not modelled), so a log that holds one replays as it was written."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.storage import MemoryStorage

SHIPPED = Path(__file__).parents[2] / "src/gaitpref/config/shipped/exo-2d-rated.toml"


def _gait_twice(storage: MemoryStorage) -> Session:
    """A session (n = 2) whose pending query proposes one gait for both of its trials."""
    text = SHIPPED.read_text(encoding="utf-8").replace("n = 1\nbuffer = 1", "n = 2\nbuffer = 0")
    session = Session.create(storage, parse_config(text), "S01", seed=0)
    for _ in range(40):
        q = session.next_query()
        if q.actions[0] == q.actions[1]:
            return session
        session.answer(q.id, [(q.actions[0], q.actions[1], "first")], [])
    raise AssertionError("no query proposed a gait twice")


def test_no_pair_is_asked_but_an_answer_to_it_is_kept_unmodelled_and_replays() -> None:
    storage = MemoryStorage()
    session = _gait_twice(storage)
    q = session.next_query()
    a, (t1, _) = q.actions[0], q.trials
    assert q.compared == () and [p.same_gait for p in q.pairs] == [True]
    session.answer(q.id, [(a, a, "first")], [])  # as the console posted it
    last = session.comparisons()[-1]
    assert (last.first, last.second, last.outcome) == (a, a, "first")
    assert last.first_trial == last.second_trial == t1  # as its event logged it
    # not modelled: the posterior is the one the query's answer without it gives
    twin = _gait_twice(MemoryStorage())
    twin.answer(twin.next_query().id, [], [])
    np.testing.assert_array_equal(session.posterior().mean, twin.posterior().mean)
    nxt = session.next_query()
    again = Session.open(storage, session.id)
    assert again.comparisons() == session.comparisons()
    np.testing.assert_array_equal(again.posterior().mean, session.posterior().mean)
    assert again.pending == nxt
