"""Remembered Laplace modes (``model/fit_memo.py``): a fit of a remembered problem is checked
at its mode and returns the numbers a fit from scratch returns, to the bit; anything not
remembered, or remembered wrongly, is fitted as without a memo."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gaitpref.model import fit_memo
from gaitpref.model.fit_memo import FitMemo, problem_key, remembering
from gaitpref.model.laplace import LaplaceMode, fit_laplace
from gaitpref.model.likelihood import Probit
from gaitpref.model.ordinal import Ordinal, rating_likelihood
from gaitpref.space import Feature, Space

SPACE = Space([Feature.linspace("x", 0.0, 1.0, 12), Feature.linspace("y", 0.0, 1.0, 12)])


def _problem(seed: int, singles: bool) -> tuple[object, ...]:
    """A fit's inputs: 40 random comparisons (and ratings) among 30 of the grid's actions."""
    from gaitpref.model.kernels import SquaredExponential

    rng = np.random.default_rng(seed)
    visited = np.sort(rng.choice(len(SPACE), 30, replace=False)).astype(np.intp)
    k_vv = SquaredExponential(0.3, 1.0, 1e-6).cross(SPACE, visited, rows=visited)
    first = rng.integers(0, 30, 40).astype(np.intp)
    second = ((first + 1 + rng.integers(0, 29, 40)) % 30).astype(np.intp)
    single = rng.integers(0, 30, 10).astype(np.intp) if singles else None
    ratings = rng.integers(1, 4, 10) if singles else None
    scale = Ordinal(("bad", "okay", "good"), thresholds=(-0.5, 0.5), noise=0.3)
    single_likelihood = None if ratings is None else rating_likelihood(scale, 1.0, ratings)
    return k_vv, visited, first, second, Probit(np.full(40, 0.2)), single, single_likelihood


def _fit(problem: tuple[object, ...]) -> LaplaceMode:
    k_vv, visited, first, second, likelihood, single, single_likelihood = problem
    return fit_laplace(
        k_vv, visited, first, second, likelihood,  # type: ignore[arg-type]
        single=single, single_likelihood=single_likelihood,  # type: ignore[arg-type]
    )  # fmt: skip


def _same(a: LaplaceMode, b: LaplaceMode) -> None:
    for x, y in ((a.chol_prior, b.chol_prior), (a.chol_hessian, b.chol_hessian),
                 (a.whitened_mode, b.whitened_mode), (a.visited, b.visited)):  # fmt: skip
        assert np.array_equal(x, y)
    assert a.gradient_norm == b.gradient_norm
    assert a.log_likelihood == b.log_likelihood


@pytest.fixture(autouse=True)
def _small_fits_remembered(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fit_memo, "MEMO_FROM", 1)


@pytest.mark.parametrize("singles", [False, True])
def test_a_remembered_fit_is_checked_at_its_mode_and_returns_the_same_bits(singles: bool) -> None:
    problem = _problem(3, singles)
    plain = _fit(problem)
    assert plain.iterations > 2
    memo = FitMemo()
    with remembering(memo):
        first = _fit(problem)  # fitted and remembered
        again = _fit(problem)  # checked at the remembered mode
    assert len(memo) == 1 and memo.dirty
    assert first.iterations == plain.iterations
    assert again.iterations == 1
    _same(first, plain)
    _same(again, plain)


def test_another_problem_or_a_wrong_entry_is_fitted_as_without_a_memo() -> None:
    memo = FitMemo()
    a, b = _problem(3, False), _problem(4, False)
    with remembering(memo):
        _fit(a)
        other = _fit(b)  # not remembered: a fit from scratch
    assert other.iterations > 2
    _same(other, _fit(b))
    # an entry off the mode (a damaged cache): one evaluation, then the fit from scratch
    memo = FitMemo()
    k_vv, _, first, second, likelihood, single, single_likelihood = a
    key = problem_key(k_vv, first, second, single, None, likelihood, single_likelihood,
                      np.float64(1e-11), np.int64(100))  # fmt: skip
    assert key is not None
    right = _fit(a)
    memo.put(key, fit_memo.Remembered(right.whitened_mode + 1e-6, right.gradient_norm))
    with remembering(memo):
        checked = _fit(a)
    assert checked.iterations == right.iterations
    _same(checked, right)


def test_no_memo_outside_a_block_and_small_fits_are_not_remembered(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    memo = FitMemo()
    _fit(_problem(3, False))
    assert fit_memo.active() is None and len(memo) == 0
    monkeypatch.setattr(fit_memo, "MEMO_FROM", 31)  # the problem visits 30 actions
    with remembering(memo):
        _fit(_problem(3, False))
    assert len(memo) == 0


def test_the_memo_holds_at_most_its_entries(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fit_memo, "MAX_ENTRIES", 2)
    memo = FitMemo()
    with remembering(memo):
        for seed in (1, 2, 3):
            _fit(_problem(seed, False))
    assert len(memo) == 2
    keys = [k for k, _ in memo.items()]
    k_vv, _, first, second, likelihood, single, single_likelihood = _problem(1, False)
    oldest = problem_key(k_vv, first, second, single, None, likelihood, single_likelihood,
                         np.float64(1e-11), np.int64(100))  # fmt: skip
    assert oldest not in keys  # the least recently used went first


def test_a_likelihood_that_cannot_be_pickled_is_not_remembered() -> None:
    k_vv, visited, first, second, *_ = _problem(3, False)

    @dataclasses.dataclass(frozen=True)
    class Local(Probit):  # a class local to a function cannot be pickled
        pass

    memo = FitMemo()
    with remembering(memo):
        fit_laplace(k_vv, visited, first, second, Local(np.full(40, 0.2)))  # type: ignore[arg-type]
    assert len(memo) == 0


def test_an_entry_whose_arithmetic_overflows_is_refitted_even_where_numpy_raises() -> None:
    problem = _problem(3, False)
    k_vv, _, first, second, likelihood, single, single_likelihood = problem
    key = problem_key(k_vv, first, second, single, None, likelihood, single_likelihood,
                      np.float64(1e-11), np.int64(100))  # fmt: skip
    assert key is not None
    right = _fit(problem)
    memo = FitMemo()
    memo.put(key, fit_memo.Remembered(np.full(30, 1e308), 0.0))
    with remembering(memo), np.errstate(all="raise"):
        checked = _fit(problem)
    _same(checked, right)
