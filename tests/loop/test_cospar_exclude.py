"""CoSpar.exclude: preferences leave the model, the record stays, undo stays exact."""

from __future__ import annotations

from typing import Any, cast

import numpy as np
import pytest

from gaitpref import CoSpar, QueryError, load_config
from gaitpref.loop.cospar import Answer


def _loop(seed: int = 3) -> CoSpar:
    return load_config("exo-1d-step-length").make_loop(seed=seed)


def _answer(loop: CoSpar, k: int) -> Answer:
    q = loop.ask()
    comps = [(q.actions[0], b, "first" if (q.actions[0] + k) % 2 else "second") for b in q.buffer]
    comps = [c for c in comps if c[0] != c[1]]
    return loop.tell(q, comps, [(q.actions[0], "step_length", "+small")])


def _refit(loop: CoSpar, keep: list[tuple[int, int]]) -> np.ndarray:
    """The posterior mean fitted from scratch on the listed (query id, preference index)."""
    by_id = {a.query.id: a for a in loop.answers}
    prefs = [by_id[q].preferences[i] for q, i in keep]
    post = loop.gp.posterior(
        [p.winner for p in prefs], [p.loser for p in prefs], [p.noise for p in prefs]
    )
    return np.asarray(post.mean)


def test_exclude_equals_never_having_the_preferences() -> None:
    loop = _loop()
    for k in range(6):
        _answer(loop, k)
    target = loop.answers[2]
    loop.exclude({target.query.id: range(len(target.preferences))})
    keep = [
        (a.query.id, i) for a in loop.answers if a is not target for i in range(len(a.preferences))
    ]
    np.testing.assert_allclose(loop.posterior.mean, _refit(loop, keep), atol=1e-8)
    assert len(loop.answers) == 6  # the record stays
    assert target.preferences[0] not in loop.preferences
    assert loop.excluded == {target.query.id: frozenset(range(len(target.preferences)))}


def test_exclude_is_idempotent_and_checks_input() -> None:
    loop = _loop()
    for k in range(3):
        _answer(loop, k)
    qid = loop.answers[1].query.id
    first = loop.exclude({qid: [0]})
    assert loop.exclude({qid: [0]}) is first
    before = loop.posterior
    with pytest.raises(QueryError, match="no recorded answer"):
        loop.exclude({999: [0]})
    with pytest.raises(IndexError, match="cannot exclude index 7"):
        loop.exclude({qid: [7]})
    # 0.5 and True were read as indices 0 and 1, "0" as the characters of a string
    for bad, message in ((0.5, "must be integers, got 0.5"), (True, "must be integers, got True")):
        with pytest.raises(TypeError, match=message):
            loop.exclude({qid: [bad]})  # type: ignore[list-item]
    with pytest.raises(TypeError, match="must be indices, got '0'"):
        loop.exclude(cast(Any, {qid: "0"}))
    # an AttributeError ('list' object has no attribute 'items') before
    with pytest.raises(TypeError, match="preferences to exclude: expected a mapping"):
        loop.exclude([qid])  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="singles to exclude: expected a mapping"):
        loop.exclude({qid: [0]}, [0])  # type: ignore[arg-type]
    assert loop.posterior is before
    assert loop.excluded == {qid: frozenset({0})}


def test_undo_after_excluding_an_earlier_answer_refits_without_it() -> None:
    loop = _loop()
    for k in range(4):
        _answer(loop, k)
    early = loop.answers[0]
    loop.exclude({early.query.id: range(len(early.preferences))})
    loop.undo()  # the last answer's posterior_before still held the excluded preferences
    keep = [
        (a.query.id, i) for a in loop.answers if a is not early for i in range(len(a.preferences))
    ]
    np.testing.assert_allclose(loop.posterior.mean, _refit(loop, keep), atol=1e-8)


def test_undo_of_an_answer_with_its_own_exclusion_is_exact() -> None:
    loop = _loop()
    for k in range(3):
        _answer(loop, k)
    before = np.asarray(loop.posterior.mean).copy()
    answer = _answer(loop, 3)
    loop.exclude({answer.query.id: [0]})
    loop.undo()
    np.testing.assert_array_equal(loop.posterior.mean, before)
    assert loop.excluded == {}
    # answering the same query again starts with no exclusion
    again = loop.tell(loop.ask(), [], [])
    assert loop.excluded == {} and again.query == answer.query


def _run(ops: list[str], seed: int = 5) -> tuple[object, object, np.ndarray]:
    loop = load_config("exo-1d-step-length").make_loop(seed=seed)
    for op in ops:
        if op == "undo":
            loop.undo()
            continue
        q = loop.ask()
        loop.tell(q, [(q.actions[0], b, op) for b in q.buffer if b != q.actions[0]], [])
    return loop.ask(), loop.rng.bit_generator.state, np.asarray(loop.posterior.mean)


@pytest.mark.parametrize(
    "ops",
    [
        ["first", "second", "first", "undo", "undo", "second", "second"],
        ["first", "second", "first", "undo", "undo", "undo", "second", "second", "second"],
        ["first", "first", "undo", "undo", "second", "first", "undo", "second"],
    ],
)
def test_several_undos_in_a_row_go_back_exactly(ops: list[str]) -> None:
    """Undoing k answers and answering again equals never having given them (RNG included)."""
    kept: list[str] = []
    for op in ops:
        if op == "undo":
            kept.pop()
        else:
            kept.append(op)
    q1, rng1, mean1 = _run(ops)
    q2, rng2, mean2 = _run(kept)
    assert q1 == q2 and rng1 == rng2
    np.testing.assert_array_equal(mean1, mean2)
