from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from gaitpref import (
    CoSpar,
    Feature,
    FeedbackError,
    PreferenceGP,
    QueryError,
    Space,
    SquaredExponential,
    load_config,
)
from gaitpref.loop.cospar import Query


def _loop(space: Space, kernel: SquaredExponential, **kw: object) -> CoSpar:
    return CoSpar(space, kernel, 0.02, **kw)  # type: ignore[arg-type]


def _answer_by(loop: CoSpar, utility: np.ndarray, trials: int) -> None:
    for _ in range(trials):
        q = loop.ask()
        comps = []
        for i in q.actions:
            for j in q.buffer:
                if i != j:
                    comps.append((i, j, "first" if utility[i] > utility[j] else "second"))
        if len(q.actions) == 2 and q.actions[0] != q.actions[1]:
            a, b = q.actions
            comps.append((a, b, "first" if utility[a] > utility[b] else "second"))
        loop.tell(q, comps, [])


def test_same_seed_same_run(small_space: Space, small_kernel: SquaredExponential) -> None:
    utility = np.random.default_rng(0).normal(size=len(small_space))
    runs = []
    for _ in range(2):
        loop = _loop(small_space, small_kernel, n=1, buffer=1, seed=42)
        _answer_by(loop, utility, 25)
        runs.append((loop.executed, np.asarray(loop.posterior.mean).copy()))
    assert runs[0][0] == runs[1][0]
    assert np.array_equal(runs[0][1], runs[1][1])
    other = _loop(small_space, small_kernel, n=1, buffer=1, seed=43)
    _answer_by(other, utility, 25)
    assert other.executed != runs[0][0]


def test_query_shapes_and_buffer(small_space: Space, small_kernel: SquaredExponential) -> None:
    loop = _loop(small_space, small_kernel, n=2, buffer=0, seed=1)
    q = loop.ask()
    assert len(q.actions) == 2 and q.buffer == ()
    assert loop.ask() is q  # pending until told
    loop = _loop(small_space, small_kernel, n=1, buffer=2, seed=1)
    q1 = loop.ask()
    assert q1.buffer == ()
    loop.tell(q1)
    q2 = loop.ask()
    assert q2.buffer == q1.actions
    loop.tell(q2, [(q2.actions[0], q1.actions[0], "none")])
    q3 = loop.ask()
    assert q3.buffer == q1.actions + q2.actions
    loop.tell(q3)
    assert loop.buffer == q2.actions + q3.actions
    assert q3.id == 3 and loop.executed == [*q1.actions, *q2.actions, *q3.actions]


def test_preferences_and_coactive_enter_the_model_with_their_noise(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    loop = _loop(small_space, small_kernel, n=2, buffer=0, coactive_weight=0.5, seed=3)
    q = loop.ask()
    while q.actions[0] == q.actions[1]:
        loop.tell(q)
        q = loop.ask()
    a, b = q.actions
    loop.tell(q, [(a, b, "second")], [(a, "step_length", "+big")])
    target = small_space.coactive_move(a, "step_length", "+big")
    prefs = loop.preferences
    assert (prefs[0].winner, prefs[0].loser, prefs[0].noise) == (b, a, 0.02)
    if target is not None:
        assert (prefs[1].winner, prefs[1].loser, prefs[1].noise) == (target, a, 0.04)
        winners, losers, noise = [b, target], [a, a], [0.02, 0.04]
    else:
        winners, losers, noise = [b], [a], [0.02]
    ref = PreferenceGP(small_space, small_kernel, 0.02).posterior(winners, losers, noise)
    assert np.allclose(loop.posterior.mean, ref.mean, rtol=1e-9, atol=1e-13)


def test_ties_are_stored_not_modelled_and_self_comparisons_dropped(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    loop = _loop(small_space, small_kernel, n=1, buffer=1, seed=0)
    q1 = loop.ask()
    loop.tell(q1)
    q2 = loop.ask()
    other = q1.actions[0]
    answer = loop.tell(q2, [(q2.actions[0], other, "none")])
    assert loop.preferences == []
    if q2.actions[0] != other:
        assert [(t.first, t.second) for t in answer.ties] == [(q2.actions[0], other)]
    assert np.all(loop.posterior.mean == 0)


def test_suggestion_that_clips_is_ignored(small_kernel: SquaredExponential) -> None:
    space = Space([Feature.linspace("step_length", 0.08, 0.18, 7), Feature("mode", [1.0])])
    loop = CoSpar(space, SquaredExponential((0.03, 1.0), 0.005, 1e-7), 0.02, n=1, buffer=1)
    q = loop.ask()
    a = q.actions[0]
    answer = loop.tell(q, [], [(a, "mode", "+big")])
    assert answer.ignored_suggestions == answer.suggestions
    assert answer.preferences == () and loop.preferences == []


def _state(loop: CoSpar) -> tuple[object, ...]:
    return (
        list(loop.preferences),
        loop.executed,
        loop.pending,
        loop.buffer,
        loop.rng.bit_generator.state,
        np.asarray(loop.posterior.mean).copy().tobytes(),
    )


@pytest.mark.parametrize(
    ("make_bad", "error", "message"),
    [
        (lambda q: (999, [], []), QueryError, "unknown query id 999"),
        (lambda q: ("x", [], []), QueryError, "Query or its integer id"),
        (lambda q: (q, [(q.actions[0], 35, "first")], []), FeedbackError, "off the grid"),
        (lambda q: (q, [(q.actions[0], -1, "first")], []), FeedbackError, "off the grid"),
        (lambda q: (q, [(q.actions[0], q.buffer[0], "better")], []), FeedbackError, "outcome"),
        (lambda q: (q, [(q.actions[0],)], []), FeedbackError, "expected \\(i, j, outcome\\)"),
        (
            lambda q: (q, [(q.actions[0], (q.actions[0] + 1) % 35, "first")], []),
            FeedbackError,
            "not in this query",
        ),
        (
            lambda q: (
                q,
                [(q.actions[0], q.buffer[0], "first"), (q.buffer[0], q.actions[0], "first")],
                [],
            ),
            FeedbackError,
            "compared twice",
        ),
        (lambda q: (q, [], [(q.buffer[0], "step_length", "+big")]), FeedbackError, "not executed"),
        (lambda q: (q, [], [(q.actions[0], "width", "+big")]), FeedbackError, "unknown feature"),
        (lambda q: (q, [], [(q.actions[0], "step_length", "up")]), FeedbackError, "move must be"),
        (
            lambda q: (q, [], [(q.actions[0], "step_length", "+big")] * 2),
            FeedbackError,
            "two suggestions",
        ),
    ],
)
def test_bad_input_raises_and_changes_nothing(
    small_space: Space,
    small_kernel: SquaredExponential,
    make_bad: Callable[[Query], tuple[Any, ...]],
    error: type[Exception],
    message: str,
) -> None:
    loop = _loop(small_space, small_kernel, n=1, buffer=1, seed=5)
    q1 = loop.ask()
    loop.tell(q1)
    q = loop.ask()
    if q.actions[0] == q.buffer[0]:  # make the buffered action differ for these cases
        loop.tell(q)
        q = loop.ask()
    before = _state(loop)
    with pytest.raises(error, match=message):
        loop.tell(*make_bad(q))
    assert _state(loop) == before


def test_answering_twice_and_stale_queries(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    loop = _loop(small_space, small_kernel, n=2, buffer=0, seed=5)
    q1 = loop.ask()
    loop.tell(q1)
    with pytest.raises(QueryError, match="already answered"):
        loop.tell(q1)
    q2 = loop.ask()
    forged = type(q2)(q2.id, (0, 1), ())
    with pytest.raises(QueryError, match="does not match"):
        loop.tell(forged)


def test_undo_restores_the_state_before_the_answer(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    utility = np.random.default_rng(2).normal(size=len(small_space))
    loop = _loop(small_space, small_kernel, n=1, buffer=1, seed=9)
    _answer_by(loop, utility, 6)
    q = loop.ask()
    snapshot = _state(loop)
    comps = [(q.actions[0], q.buffer[0], "first")] if q.actions[0] != q.buffer[0] else []
    loop.tell(q, comps)
    loop.ask()  # a new query was issued after the answer; undo takes it back too
    loop.undo()
    assert _state(loop) == snapshot
    assert loop.ask() == q
    with pytest.raises(QueryError, match="nothing to undo"):
        _loop(small_space, small_kernel, n=1, buffer=1).undo()


def test_answer_undo_answer_differently_equals_answering_differently(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    utility = np.random.default_rng(4).normal(size=len(small_space))
    a = _loop(small_space, small_kernel, n=1, buffer=1, seed=11)
    b = _loop(small_space, small_kernel, n=1, buffer=1, seed=11)
    for loop in (a, b):
        _answer_by(loop, utility, 5)
    qa, qb = a.ask(), b.ask()
    assert qa == qb
    pair = (qa.actions[0], qa.buffer[0])
    a.tell(qa, [(*pair, "first")] if pair[0] != pair[1] else [])
    a.ask()
    a.undo()
    a.tell(qa, [(*pair, "second")] if pair[0] != pair[1] else [])
    b.tell(qb, [(*pair, "second")] if pair[0] != pair[1] else [])
    assert _state(a) == _state(b)
    assert a.ask() == b.ask()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"n": 0}, "n \\(actions per query\\)"),
        ({"buffer": -1}, "buffer"),
        ({"coactive_weight": 0.0}, "coactive_weight"),
    ],
)
def test_bad_settings(
    small_space: Space, small_kernel: SquaredExponential, kwargs: dict[str, object], message: str
) -> None:
    kwargs.setdefault("n", 2)
    with pytest.raises(ValueError, match=message):
        _loop(small_space, small_kernel, **kwargs)


def test_loop_learns_the_optimum_of_a_smooth_objective() -> None:
    cfg = load_config("exo-1d-step-length")
    x = cfg.space.points[:, 0]
    utility = -((x - 0.13) ** 2)
    loop = cfg.make_loop(seed=0)
    _answer_by(loop, utility, 30)
    assert abs(x[loop.posterior.argmax] - 0.13) <= 0.1 / 14 + 1e-12
