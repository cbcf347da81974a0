"""Hyperparameters from the evidence: recovery on GP-sampled objectives, and no silent failure."""

from __future__ import annotations

import numpy as np
import pytest

import gaitpref.model.hyperfit as hf
from gaitpref import Feature, Space, SquaredExponential
from gaitpref.errors import ConvergenceError
from gaitpref.model import KroneckerPriorSampler
from gaitpref.model.evidence import Hyperparameters, PairData
from gaitpref.model.hyperfit import LogNormal, default_prior, fit_hyperparameters

SPACE = Space([Feature.linspace("x", 0.0, 1.0, 12), Feature.linspace("y", 0.0, 2.0, 12)])


def _answers(lengthscale: tuple[float, float], seed: int, n: int = 400) -> PairData:
    """Noisy probit answers to random pairs about one GP sample with ``lengthscale``."""
    rng = np.random.default_rng(seed)
    f = KroneckerPriorSampler(SPACE, SquaredExponential(lengthscale, 1.0, 1e-6)).sample(rng, 1)[0]
    first, second = rng.integers(0, len(SPACE), n), rng.integers(0, len(SPACE), n)
    keep = first != second
    first, second = first[keep], second[keep]
    sigma = 0.2
    y = f[first] - f[second] + rng.normal(0.0, np.sqrt(2) * sigma, first.size)
    w, l = np.where(y > 0, first, second), np.where(y > 0, second, first)
    return PairData(w, l, np.full(w.size, sigma), np.ones(w.size, bool), np.zeros(w.size, bool))


@pytest.mark.parametrize(("lengthscale", "seed"), [((0.12, 0.8), 0), ((0.3, 0.25), 1)])
def test_fitted_lengthscales_recover_the_generating_ones(
    lengthscale: tuple[float, float], seed: int
) -> None:
    data = _answers(lengthscale, seed, n=300)
    start = Hyperparameters((0.5, 0.5), 0.5, 5e-7)  # wrong by 1.6-4x
    prior = default_prior(SPACE, 0.5, 0.2, variance_sd=1.0)
    fit = fit_hyperparameters(SPACE, start, data, prior)
    assert fit.accepted and fit.converged and fit.failed_evaluations == 0
    assert fit.objective_after > fit.objective_before
    ratio = np.array(fit.after.lengthscale) / np.array(lengthscale)
    assert np.all((ratio > 1 / 1.4) & (ratio < 1.4)), fit.after.lengthscale
    assert 0.5 < fit.after.variance < 2.0  # generated with s^2 = 1 (sigma fixed at 0.2)
    assert fit.after.jitter / fit.after.variance == pytest.approx(1e-6)


def test_held_parameters_and_bounds_are_respected() -> None:
    data = _answers((0.12, 0.8), 2, n=150)
    prior = default_prior(SPACE, 0.5, 0.2, variance_sd=0.0)
    prior = hf.HyperPrior((prior.lengthscale[0], LogNormal(0.3, 0.0)), prior.variance)
    start = Hyperparameters((0.5, 0.7), 0.5, 5e-7)
    fit = fit_hyperparameters(SPACE, start, data, prior)
    assert fit.accepted
    assert fit.after.lengthscale[1] == 0.7 and fit.after.variance == 0.5  # held (sd 0)
    lo, hi = 0.25 * np.exp(-3 * 0.7), 0.25 * np.exp(3 * 0.7)
    assert lo * (1 - 1e-9) <= fit.after.lengthscale[0] <= hi * (1 + 1e-9)


def test_a_fit_that_cannot_be_evaluated_keeps_the_previous_values_and_says_so(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    data = _answers((0.12, 0.8), 3, n=60)

    def broken(*args: object, **kwargs: object) -> None:
        raise ConvergenceError("stalled")

    monkeypatch.setattr(hf, "laplace_evidence", broken)
    start = Hyperparameters((0.5, 0.5), 0.5, 5e-7)
    fit = fit_hyperparameters(SPACE, start, data, default_prior(SPACE, 0.5, 0.2))
    assert not fit.accepted and not fit.converged
    assert fit.after == fit.before == start
    assert "cannot be evaluated" in fit.message and fit.failed_evaluations == 1
    assert "kept the previous" in fit.message
    assert fit.to_json()["accepted"] is False


def test_evaluations_that_fail_midway_are_counted_and_avoided(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    data = _answers((0.12, 0.8), 4, n=120)
    from gaitpref.model.evidence import laplace_evidence as real

    def fragile(space: Space, hyper: Hyperparameters, *args: object, **kw: object) -> object:
        if hyper.lengthscale[1] > 0.55:  # pretend long y-lengthscales break the Laplace fit
            raise ConvergenceError("stalled")
        return real(space, hyper, *args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(hf, "laplace_evidence", fragile)
    start = Hyperparameters((0.5, 0.5), 0.5, 5e-7)
    fit = fit_hyperparameters(SPACE, start, data, default_prior(SPACE, 0.5, 0.2))
    assert fit.accepted and fit.after.lengthscale[1] <= 0.55
    assert fit.objective_after >= fit.objective_before
