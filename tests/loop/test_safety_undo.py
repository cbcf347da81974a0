"""An undo brings its query back only while that query proposes no gait flagged unsafe (or
avoided) after it was asked, nor one in the region of avoidance as the undo leaves the model (an
exclusion since moves it): otherwise the query is withdrawn, the generator goes back to before
it was drawn, and the next ask proposes under the flags, on the grid and on the line path."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gaitpref import CoSpar, Feature, Space, SquaredExponential
from gaitpref.errors import NoSafeGaitError, QueryError
from gaitpref.feedback import Comparison, Rating
from gaitpref.loop import Safety
from gaitpref.loop.cospar import Query
from gaitpref.loop.line import LineCoSpar
from gaitpref.loop.lines import LineSettings
from gaitpref.loop.safety import near
from gaitpref.model.ordinal import Ordinal
from tests.sessions import regionkit

GRID = Space([Feature.linspace("x", 0.0, 1.0, 21), Feature.linspace("y", 0.0, 1.0, 5)])
UNIT = Space([Feature.interval("x", 0.0, 1.0), Feature.interval("y", 0.0, 1.0)])
KERNEL = SquaredExponential(0.3, 1.0, 1e-6)
RADIUS = 0.3


def _loop(line: bool, seed: int) -> CoSpar:
    safety = Safety(unsafe_radius=RADIUS)
    if line:
        return LineCoSpar(UNIT, KERNEL, 0.05, n=1, buffer=1, seed=seed, safety=safety)
    return CoSpar(GRID, KERNEL, 0.05, n=1, buffer=1, seed=seed, safety=safety)


def _tell(loop: CoSpar) -> None:
    q = loop.ask()
    a, b = q.actions[0], (q.buffer or (None,))[0]
    loop.tell(q, [] if b is None or b == a else [Comparison(a, b, "first")])


def _banned(loop: CoSpar) -> np.ndarray:
    banned = near(loop.space, loop.unsafe, RADIUS)
    for action, radius in loop.avoided.items():
        banned |= near(loop.space, [action], radius)
    return banned


@settings(max_examples=30, deadline=None)
@given(
    line=st.booleans(),
    seed=st.integers(0, 10_000),
    ops=st.lists(st.sampled_from(["tell", "flag", "avoid", "undo", "unflag"]), max_size=14),
)
def test_no_pending_query_ever_proposes_a_flagged_gait(
    line: bool, seed: int, ops: list[str]
) -> None:
    loop = _loop(line, seed)
    rng = np.random.default_rng(seed)
    for op in ["tell", "tell", *ops]:
        try:
            if op == "tell":
                _tell(loop)
            elif op == "flag" and loop.executed:
                loop.flag_unsafe(int(rng.choice(loop.executed)))
            elif op == "avoid" and loop.executed and not line:
                loop.avoid(int(rng.choice(loop.executed)), 0.1)
            elif op == "unflag" and loop.unsafe:
                loop.unflag_unsafe(min(loop.unsafe))
            elif op == "undo" and loop.answers:
                loop.ask()  # a query is pending when the undo comes, as in a session
                loop.undo()
        except (NoSafeGaitError, QueryError):
            return  # every gait banned, or nothing left to undo: nothing to check further
        if loop.pending is not None:
            banned = _banned(loop)
            assert not any(banned[a] for a in loop.pending.actions), (op, loop.pending)


def test_an_undone_query_near_a_later_flag_is_withdrawn_and_proposed_anew() -> None:
    for line in (False, True):
        for seed in range(40):
            loop = _loop(line, seed)
            _tell(loop)
            _tell(loop)
            first, second = loop.answers[0].query.actions[0], loop.answers[1].query.actions[0]
            if near(loop.space, [first], RADIUS)[second] and first != second:
                break
        else:
            raise AssertionError("no seed puts the second gait near the first")
        state = loop.rng.bit_generator.state
        loop.flag_unsafe(first)
        undone = loop.undo()
        assert loop.pending is None, "the restored query proposes a gait near the flag"
        assert loop.rng.bit_generator.state != state  # back to before the second query
        again = loop.ask()
        assert again.points != undone.query.points
        assert not near(loop.space, loop.unsafe, RADIUS)[list(again.actions)].any()
        loop.unflag_unsafe(first)
        loop.tell(again, [])


def test_an_undone_query_far_from_every_flag_is_pending_again() -> None:
    loop = _loop(False, 3)
    _tell(loop)
    _tell(loop)
    q = loop.answers[1].query
    far = int(np.argmax(np.sum((GRID.points - GRID.points[q.actions[0]]) ** 2, axis=1)))
    loop.flag_unsafe(far)
    assert not near(GRID, [far], RADIUS)[q.actions[0]]
    loop.undo()
    assert loop.pending == q


def test_on_the_grid_an_undo_whose_own_gait_is_flagged_withdraws_its_query() -> None:
    """A session flags trials, the loop gaits: the same gait walked in an earlier trial and
    flagged there is the last answer's too; the undo must not fail after its event is written."""
    loop = _loop(False, 3)
    _tell(loop)
    _tell(loop)
    own = loop.answers[1].query.actions[0]
    loop.flag_unsafe(own)
    loop.undo()
    assert loop.pending is None
    assert own not in loop.ask().actions


def test_on_the_line_path_a_flag_on_a_point_the_undone_query_added_is_refused() -> None:
    loop = _loop(True, 3)
    _tell(loop)
    _tell(loop)
    added = loop.answers[1].query.actions[0]
    loop.flag_unsafe(added)
    state = (loop.pending, len(loop.answers), loop.space)
    try:
        loop.undo()
    except QueryError as e:
        assert "take the flag back" in str(e)
    else:
        raise AssertionError("the undo took a flagged point out of the table")
    assert (loop.pending, len(loop.answers), loop.space) == state  # nothing moved
    loop.unflag_unsafe(added)
    loop.undo()
    assert loop.pending is not None


RATED = regionkit.CONFIG  # the sessions' scenario, run on the loop (seed 2)


def _rated_then_excluded(region: bool) -> tuple[CoSpar, Query]:
    """Seed 2 runs gaits 2, 4, 0, 14, 14, 1; gait 2 rated "good" (so gait 1 may be proposed),
    the others below 5 "very bad"; then the good rating excluded and the last answer undone."""
    from gaitpref.config import parse_config

    loop = parse_config(RATED).make_loop(seed=2)
    for trial in range(1, 7):
        q = loop.ask()
        a = q.actions[0]
        loop.tell(q, [Rating(a, "good" if trial == 1 else "very bad" if a < 5 else "okay")])
    assert loop.executed == [2, 4, 0, 14, 14, 1]  # the case under test
    last = loop.answers[-1].query
    loop.exclude({}, {loop.answers[0].query.id: [0]})
    loop.undo(region=region)
    return loop, last


def test_an_undo_withdraws_its_query_when_an_exclusion_since_puts_its_gait_in_the_region() -> None:
    loop, last = _rated_then_excluded(region=True)
    assert loop.pending is None, "the restored query proposes a gait in the region"
    assert not loop.proposable()[last.actions[0]]
    again = loop.ask()
    assert again.actions != last.actions and loop.proposable()[list(again.actions)].all()
    # the flags alone (a session's undo of payload version 1): restored as it was
    old, last = _rated_then_excluded(region=False)
    assert old.pending == last


@pytest.mark.parametrize("line", [False, True])
def test_an_undo_with_nothing_between_restores_its_query_under_a_cautious_region(
    line: bool,
) -> None:
    """The region an ask reads (on the line path: along its line, whose known-safe gaits the
    cautious level weighs) is the one an undo reads when nothing moved the model since."""
    scale = Ordinal(["very bad", "bad", "okay", "good"], noise=0.01)
    safety = Safety(avoid=1, risk=0.35, cautious=0.6)
    kernel = SquaredExponential(0.2, 1e-4, 1e-8)
    for seed in range(4):
        if line:
            loop: CoSpar = LineCoSpar(
                UNIT, kernel, 0.01, n=1, buffer=1, seed=seed, ordinal=scale, safety=safety,
                line=LineSettings(40),
            )  # fmt: skip
        else:
            loop = CoSpar(
                GRID, kernel, 0.01, n=1, buffer=1, seed=seed, ordinal=scale, safety=safety
            )
        for trial in range(6):
            q = loop.ask()
            rating = Rating(q.actions[0], ("okay", "good", "very bad")[trial % 3])
            loop.tell(q, [rating])
            loop.undo()
            assert loop.pending == q and loop.pending.points == q.points, (seed, trial)
            loop.tell(q, [rating])
