"""Property tests of the public numerics on valid but extreme inputs.

Scales from 1e-300 to 1e300 (tiny and huge lengthscales, signal variances, jitters and noises),
one action, duplicated and contradictory comparisons, ratings of one gait in every category,
all ties, and the strategies' proposals on what comes out.  Every call either answers with
finite numbers or raises a named model error (``ConvergenceError``: the likelihood is nearly
deterministic; ``PriorNotPositiveDefiniteError``: visited gaits indistinguishable without
jitter); never an IndexError, LinAlgError, ZeroDivisionError, OverflowError or NaN.

Found with these: a noise whose square overflows (``test_noise_squares.py``), a grid whose size
wrapped (``test_grid_limits.py``), and a ConvergenceError that counted no ratings (below).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gaitpref import (
    STRATEGIES,
    Feature,
    Ordinal,
    PreferenceGP,
    Space,
    SquaredExponential,
    make_strategy,
)
from gaitpref.errors import ConvergenceError, PriorNotPositiveDefiniteError
from gaitpref.model import (
    Hyperparameters,
    PairData,
    default_prior,
    fit_hyperparameters,
    laplace_evidence,
)
from gaitpref.model.posterior import Posterior
from gaitpref.strategies import AskContext

NAMED = (ConvergenceError, PriorNotPositiveDefiniteError)
SCALES = [1e-300, 1e-12, 1e-3, 0.3, 1e3, 1e15, 1e300]
NOISES = [1e-300, 1e-8, 0.02, 1.0, 1e150, 1e300]


def _space(sizes: list[int]) -> Space:
    return Space([Feature.linspace(f"f{k}", 0.0, 1.0, n) for k, n in enumerate(sizes)])


@st.composite
def _pairs(draw: st.DrawFn, size: int) -> tuple[list[int], list[int]]:
    if size < 2:
        return [], []
    pair = st.tuples(st.integers(0, size - 1), st.integers(0, size - 1))
    pairs = draw(st.lists(pair.filter(lambda p: p[0] != p[1]), max_size=10))
    w, l_ = [p[0] for p in pairs], [p[1] for p in pairs]
    how = draw(st.sampled_from(["as given", "duplicated", "contradictory"]))
    if how == "duplicated":
        return w * 20, l_ * 20
    if how == "contradictory":
        return w + l_, l_ + w
    return w, l_


@st.composite
def _posteriors(draw: st.DrawFn) -> Posterior | None:
    """A posterior from extreme settings, or None where a constructor refuses a setting by name
    (a noise whose square overflows) or the fit says it cannot (``NAMED``)."""
    space = _space(draw(st.lists(st.integers(1, 5), min_size=1, max_size=3)))
    kernel = SquaredExponential(
        draw(st.sampled_from(SCALES)),
        draw(st.sampled_from(SCALES)),
        draw(st.sampled_from([0.0, 1e-300, 1e-6, 1.0, 1e300])),
    )
    rating_noise, noise = draw(st.sampled_from(NOISES)), draw(st.sampled_from(NOISES))
    sampler = draw(st.sampled_from(["dense", "scalable"]))
    w, l_ = draw(_pairs(len(space)))
    rating = st.tuples(st.integers(0, len(space) - 1), st.integers(1, 3))
    ratings = draw(st.lists(rating, max_size=5))
    try:
        gp = PreferenceGP(space, kernel, noise, sampler, Ordinal(3, noise=rating_noise))
    except ValueError as exc:
        assert "with a finite square" in str(exc) and max(noise, rating_noise) > 1e154
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # under/overflow on the way is fine
        try:
            return gp.posterior(w, l_, ratings=ratings or None)
        except NAMED:
            return None


@settings(max_examples=80)
@given(post=_posteriors())
def test_posteriors_of_extreme_settings_read_finite(post: Posterior | None) -> None:
    if post is None:
        return
    size = len(post.space)
    rng = np.random.default_rng(0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # under/overflow on the way is fine
        outputs = [
            post.mean,
            post.variance,
            post.variance_at(np.arange(size)),
            post.sample(rng, 2),
            post.sample(rng, 2, nugget=False),
            post.covariance(),
            np.array(post.preference_probability(0, size - 1)),
            post.rating_probabilities(np.arange(size)),
            np.array(post.log_evidence),
        ]
        picks = post.argmax_samples(rng, 3)
    for out in outputs:
        assert np.all(np.isfinite(out))
    assert np.all((picks >= 0) & (picks < size))
    assert np.all(post.variance >= 0)


@settings(max_examples=60)
@given(post=_posteriors(), strategy=st.sampled_from(STRATEGIES), data=st.data())
def test_strategies_propose_allowed_actions_on_extreme_posteriors(
    post: Posterior | None, strategy: str, data: st.DataObject
) -> None:
    if post is None:
        return
    size = len(post.space)
    n = data.draw(st.integers(1, size))
    buffer = tuple(data.draw(st.lists(st.integers(0, size - 1), max_size=2)))
    allowed = None
    if data.draw(st.booleans()):
        allowed = np.array(data.draw(st.lists(st.booleans(), min_size=size, max_size=size)))
        allowed[data.draw(st.integers(0, size - 1))] = True
    context = AskContext(post, n, buffer, data.draw(st.integers(0, 40)), np.random.default_rng(1))
    context = AskContext(post, n, buffer, context.trial, context.rng, allowed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        picks = make_strategy(strategy).propose(context)
    assert len(picks) == n
    for a in picks:
        assert 0 <= a < size and (allowed is None or allowed[a])


@settings(max_examples=40)
@given(
    sizes=st.lists(st.integers(2, 5), min_size=1, max_size=2),
    scale=st.sampled_from([1e-6, 0.3, 1e6]),
    band=st.sampled_from([1e-6, 0.1, 10.0]),
    sigma=st.sampled_from([1e-4, 0.1, 10.0]),
    data=st.data(),
)
def test_all_ties_give_a_finite_evidence_and_fit(
    sizes: list[int], scale: float, band: float, sigma: float, data: st.DataObject
) -> None:
    space = _space(sizes)
    w, l_ = data.draw(_pairs(len(space)))
    if not w:
        return
    n = len(w)
    ties = PairData(
        np.array(w), np.array(l_), np.full(n, sigma), np.ones(n, bool), np.ones(n, bool)
    )
    hyper = Hyperparameters((scale,) * space.ndim, scale, 1e-6 * scale, band)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            ev = laplace_evidence(space, hyper, ties)
        except NAMED:
            return
        assert np.isfinite(ev.value) and np.all(np.isfinite(ev.gradient))
        prior = default_prior(space, scale, sigma, fit_band=True)
        fit = fit_hyperparameters(space, hyper, ties, prior, max_evaluations=10)
    after = fit.after
    assert np.all(np.isfinite([*after.lengthscale, after.variance, after.band]))


def test_a_convergence_error_counts_the_ratings() -> None:
    """It said "0 observations over 1 actions" for three ratings (pairs only were counted)."""
    gp = PreferenceGP(
        _space([1]), SquaredExponential(1e8, 1e8, 1e-12), 1e4, ordinal=Ordinal(3, noise=1e-6)
    )
    with (
        warnings.catch_warnings(),
        pytest.raises(ConvergenceError, match="3 observations over 1 actions"),
    ):
        warnings.simplefilter("ignore", RuntimeWarning)
        gp.posterior([], [], ratings=[(0, 2), (0, 1), (0, 1)])
