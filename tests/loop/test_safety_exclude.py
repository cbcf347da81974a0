"""An exclusion made while a query is pending checks that query against the region of avoidance
of the model it leaves: a query proposing a gait in it now is withdrawn (the generator back to
before it was drawn) and the next ask proposes anew; ``region=False`` keeps it, as a session's
exclusion events of payload version 1 replay."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from gaitpref.config import parse_config
from gaitpref.feedback import Rating
from gaitpref.loop.cospar import CoSpar, Query
from tests.loop.test_safety_undo import RATED


def _pending() -> tuple[CoSpar, Query, Mapping[str, Any]]:
    """Seed 2 runs gaits 2, 4, 0, 14, 14, then asks for gait 1: gait 2 rated "good" (so gait 1
    may be proposed), the others below 5 "very bad".  Also returns the generator's state from
    before that ask."""
    loop = parse_config(RATED).make_loop(seed=2)
    for trial in range(1, 6):
        q = loop.ask()
        a = q.actions[0]
        loop.tell(q, [Rating(a, "good" if trial == 1 else "very bad" if a < 5 else "okay")])
    before = loop.rng.bit_generator.state
    q = loop.ask()
    assert loop.executed == [2, 4, 0, 14, 14] and q.actions == (1,)  # the case under test
    return loop, q, before


def test_an_exclusion_withdraws_the_pending_query_it_puts_in_the_region() -> None:
    loop, q, before = _pending()
    loop.exclude({}, {loop.answers[0].query.id: [0]})  # the "good" rating leaves the model
    assert loop.pending is None, "the pending query proposes a gait in the region"
    assert loop.rng.bit_generator.state == before  # back to before it was drawn
    assert not loop.proposable()[1]
    again = loop.ask()
    assert again.actions != q.actions and loop.proposable()[list(again.actions)].all()


def test_an_exclusion_with_region_false_keeps_the_pending_query() -> None:
    loop, q, _ = _pending()
    loop.exclude({}, {loop.answers[0].query.id: [0]}, region=False)
    assert loop.pending == q
    assert not loop.proposable()[1]


def test_an_exclusion_that_changes_nothing_keeps_the_pending_query() -> None:
    loop, q, _ = _pending()
    qid = loop.answers[1].query.id
    loop.exclude({}, {qid: [0]})  # gait 4 "very bad": gait 1 stays proposable
    assert loop.pending == q
    loop.exclude({}, {qid: [0]})  # again: nothing moves
    assert loop.pending == q and loop.ask() == q
