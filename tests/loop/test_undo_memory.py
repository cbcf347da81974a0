"""What an answer keeps for undo (``loop/cospar.py``, ``STRIP_FROM_VISITED``): on a large
visited set the posterior before it without its fit's ``m x m`` factors, which undo remakes the
same to the bit, so that a session run with the factors dropped proposes exactly what one that
kept them does, cold and warm, through undo and re-answer."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gaitpref.feedback import Rating
from gaitpref.loop import cospar
from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.learning import Learning
from gaitpref.loop.warm import WarmStart, warm_data
from gaitpref.model.ordinal import Ordinal
from gaitpref.simulate.users import SimulatedUser
from tests.loop.test_warm import KERNEL, SPACE, UTILITY, _earlier


def _loop(warm: bool, ratings: bool = False) -> CoSpar:
    ordinal = Ordinal(("bad", "okay", "good"), thresholds=(-0.3, 0.3), noise=0.2)
    loop = CoSpar(SPACE, KERNEL, 0.1, n=2, seed=4, ordinal=ordinal if ratings else None,
                  learning=Learning(fit="evidence", refit_every=3))  # fmt: skip
    if warm:
        data = warm_data(SPACE, _earlier())
        loop.warm_start(WarmStart(data, 0.6, 2, share=0.3, relearn_every=2, gate=0.0))
    return loop


def _answer(loop: CoSpar, user: SimulatedUser, ratings: bool) -> None:
    q = loop.ask()
    said: list[object] = list(user.answer(q))
    if ratings:
        said.append(Rating(q.actions[0], 1 + int(q.actions[0] % 3)))
    loop.tell(q, said)


def _run(loop: CoSpar, ratings: bool, plan: str) -> list[tuple[int, ...]]:
    """``plan``: ``a`` answers, ``u`` undoes; the actions of every query asked, in order."""
    user = SimulatedUser(SPACE, 10 * UTILITY, np.random.default_rng(7), noise=0.1)
    for step in plan:
        if step == "a":
            _answer(loop, user, ratings)
        else:
            loop.undo()
    return [a.query.actions for a in loop.answers]


@pytest.mark.parametrize(("warm", "ratings"), [(False, False), (True, False), (False, True)])
def test_dropping_the_factors_changes_nothing_the_loop_does(
    monkeypatch: pytest.MonkeyPatch, warm: bool, ratings: bool
) -> None:
    plan = "aaaaauuaaauaaa"
    kept = _loop(warm, ratings)
    kept_queries = _run(kept, ratings, plan)
    monkeypatch.setattr(cospar, "STRIP_FROM_VISITED", 0)
    dropped = _loop(warm, ratings)
    dropped_queries = _run(dropped, ratings, plan)
    assert dropped_queries == kept_queries
    # what the answers hold: no factors, where the loop that kept them holds them
    for a, b in zip(dropped.answers, kept.answers, strict=True):
        if a.posterior_before.fit is not None:
            assert a.posterior_before.fit.factors is None
            assert b.posterior_before.fit is not None and b.posterior_before.fit.factors is not None
    # the current posteriors are the same to the bit, and hold their factors
    fit, ref = dropped.posterior.fit, kept.posterior.fit
    assert fit is not None and ref is not None and fit.factors is not None
    for x, y in ((fit.chol_prior, ref.chol_prior), (fit.chol_hessian, ref.chol_hessian),
                 (fit.whitened_mode, ref.whitened_mode)):  # fmt: skip
        assert np.array_equal(x, y)
    assert np.array_equal(dropped.posterior.mean, kept.posterior.mean)
    assert dropped.ask().actions == kept.ask().actions


@pytest.mark.parametrize("warm", [False, True])
def test_undo_remakes_the_factors_the_answer_dropped_to_the_bit(
    monkeypatch: pytest.MonkeyPatch, warm: bool
) -> None:
    monkeypatch.setattr(cospar, "STRIP_FROM_VISITED", 0)
    loop = _loop(warm)
    _run(loop, False, "aaaa")
    before = loop.posterior
    assert before.fit is not None
    factors = before.fit.factors
    assert factors is not None
    _run(loop, False, "a")
    kept = loop.answers[-1].posterior_before
    assert kept.fit is not None and kept.fit.factors is None
    # read while stripped: remade on the spot, each time, never kept
    assert np.array_equal(kept.fit.chol_prior, factors[0])
    assert np.array_equal(kept.fit.chol_hessian, factors[1])
    assert kept.fit.factors is None
    assert np.array_equal(kept.mean, before.mean)
    assert np.array_equal(kept.variance, before.variance)
    loop.undo()
    fit = loop.posterior.fit
    assert fit is not None and fit.factors is not None
    assert np.array_equal(fit.factors[0], factors[0])
    assert np.array_equal(fit.factors[1], factors[1])


def test_small_visited_sets_keep_their_factors() -> None:
    loop = _loop(False)
    _run(loop, False, "aaa")
    assert loop.answers[-1].posterior_before.fit is not None
    assert all(
        a.posterior_before.fit is None or a.posterior_before.fit.factors is not None
        for a in loop.answers
    )
    assert cospar.STRIP_FROM_VISITED > 30  # the whole grid of this test: never dropped here


def test_a_fit_without_a_recipe_is_never_stripped() -> None:
    loop = _loop(False)
    _run(loop, False, "aa")
    fit = loop.posterior.fit
    assert fit is not None and fit.recipe is not None
    bare = dataclasses.replace(fit, recipe=None)
    assert bare.stripped is bare
    with pytest.raises(ValueError, match="factors or a recipe"):
        dataclasses.replace(fit, factors=None, recipe=None)
