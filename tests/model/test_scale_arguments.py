"""The model's low-level entry points refuse a negative, zero, NaN or infinite scale by name
where it is given (noise sigma, band, rating noise, signal variance, jitter, lengthscales).

Before, each was accepted: a negative probit sigma flipped every preference (``z = d / (sqrt(2)
sigma)``), a zero one made NaN terms, a negative signal variance gave NaN thresholds, a negative
noise on a posterior read as the positive one (only its square is used)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from gaitpref import Feature, Ordinal, Space, SquaredExponential
from gaitpref.model import (
    Hyperparameters,
    OrderedProbit,
    OrdinalLikelihood,
    PairData,
    PopulationModel,
    Posterior,
    PreferenceGP,
    Probit,
    rating_likelihood,
    rating_probabilities,
)

SPACE = Space([Feature.linspace("a", 0, 1, 5)])
KERNEL = SquaredExponential(0.3, 1.0, 1e-6)
ONE = np.ones(1)
NO = np.zeros(1, dtype=bool)
BAD = [-1.0, np.nan, np.inf, -np.inf]


def _pairs(sigma: float) -> PairData:
    return PairData(np.array([0]), np.array([1]), np.array([sigma]), NO, NO)


POSITIVE: dict[str, tuple[Callable[[float], object], str]] = {
    "Probit": (lambda x: Probit(np.array([0.1, x])), "probit noise sigma"),
    "OrderedProbit sigma": (
        lambda x: OrderedProbit(np.array([x]), np.array([0.1]), NO),
        "probit noise sigma",
    ),
    "OrdinalLikelihood noise": (
        lambda x: OrdinalLikelihood(np.array([1]), np.array([0.0]), x),
        "rating noise",
    ),
    "rating_likelihood": (lambda x: rating_likelihood(Ordinal(3), x, [1]), "signal_variance"),
    "rating_probabilities": (
        lambda x: rating_probabilities(Ordinal(3), x, np.zeros(1), ONE),
        "signal_variance",
    ),
    "thresholds_for": (lambda x: Ordinal(3).thresholds_for(x), "signal_variance"),
    "Hyperparameters variance": (lambda x: Hyperparameters((0.3,), x, 0.0), "variance"),
    "Hyperparameters lengthscale": (lambda x: Hyperparameters((0.3, x), 1.0, 0.0), "lengthscale"),
    "PairData sigma": (_pairs, "sigma"),
    "PopulationModel noise": (lambda x: PopulationModel(SPACE, KERNEL, 0.5, x), "noise"),
    "Posterior noise": (
        lambda x: Posterior(SPACE, KERNEL, None, PreferenceGP(SPACE, KERNEL, 0.1).engine, x),
        "noise",
    ),
}

NON_NEGATIVE: dict[str, tuple[Callable[[float], object], str]] = {
    "OrderedProbit band": (
        lambda x: OrderedProbit(np.array([0.1]), np.array([x]), NO),
        "indifference band",
    ),
    "Hyperparameters jitter": (lambda x: Hyperparameters((0.3,), 1.0, x), "jitter"),
    "Hyperparameters band": (lambda x: Hyperparameters((0.3,), 1.0, 0.0, x), "band"),
}


@pytest.mark.parametrize("value", [*BAD, 0.0])
@pytest.mark.parametrize("name", sorted(POSITIVE))
def test_positive_scales_are_refused_by_name(name: str, value: float) -> None:
    build, message = POSITIVE[name]
    with pytest.raises(ValueError, match=message):
        build(value)


@pytest.mark.parametrize("value", BAD)
@pytest.mark.parametrize("name", sorted(NON_NEGATIVE))
def test_non_negative_scales_are_refused_by_name(name: str, value: float) -> None:
    build, message = NON_NEGATIVE[name]
    with pytest.raises(ValueError, match=message):
        build(value)
    build(0.0)  # zero is a valid band and jitter


@pytest.mark.parametrize("name", sorted(POSITIVE))
def test_valid_scales_are_accepted(name: str) -> None:
    POSITIVE[name][0](0.5)


def test_the_bad_entry_is_named() -> None:
    with pytest.raises(ValueError, match=r"got -0\.2 at entry 2"):
        Probit(np.array([0.1, 0.1, -0.2]))
    with pytest.raises(ValueError, match="finite numbers"):
        Probit(np.array([True]))


def test_rating_probabilities_moments() -> None:
    scale = Ordinal(3)
    # a variance below zero by rounding only (a posterior covariance's diagonal) is read as is
    out = rating_probabilities(scale, 1.0, np.zeros(2), np.array([-1e-17, 0.5]))
    assert np.all(np.isfinite(out)) and np.allclose(out.sum(axis=1), 1.0)
    for variance in (np.array([-1.0]), np.array([np.nan]), np.array([np.inf])):
        with pytest.raises(ValueError, match="variance must be finite and >= 0"):
            rating_probabilities(scale, 1.0, np.zeros(1), variance)
    for mean in (np.array([np.nan]), np.array([np.inf])):
        with pytest.raises(ValueError, match="mean must be finite"):
            rating_probabilities(scale, 1.0, mean, ONE)
    with pytest.raises(ValueError, match="1-D arrays of numbers of one length"):
        rating_probabilities(scale, 1.0, np.zeros(2), ONE)


def test_a_posterior_with_a_negative_noise_was_read_as_positive() -> None:
    """The regression behind the Posterior check: only ``noise**2`` is used downstream."""
    engine = PreferenceGP(SPACE, KERNEL, 0.1).engine
    good = Posterior(SPACE, KERNEL, None, engine, 0.1)
    assert good.preference_probability(0, 1) == 0.5
    with pytest.raises(ValueError, match="noise"):
        Posterior(SPACE, KERNEL, None, engine, -0.1)


def test_a_posteriors_own_moments_are_not_second_guessed() -> None:
    """``Posterior.rating_probabilities`` reads its own covariance diagonal, which may fall
    below 0 by the rounding of a prior variance the public function cannot see (a jitter far
    above the signal variance): it goes through unchecked, as before the check."""
    from gaitpref.model.ordinal import predictive_probabilities

    scale = Ordinal(3, noise=0.5)
    mean, variance = np.zeros(1), np.array([-1e-6])
    with pytest.raises(ValueError, match="variance must be finite and >= 0"):
        rating_probabilities(scale, 1.0, mean, variance)
    out = predictive_probabilities(scale, scale.thresholds_for(1.0), mean, variance)
    assert np.all(np.isfinite(out)) and out.sum() == pytest.approx(1.0)
    gp = PreferenceGP(SPACE, KERNEL, 0.1, ordinal=scale)
    post = gp.posterior([0, 2], [1, 3], ratings=[(4, 3)])
    idx = np.arange(len(SPACE))
    want = predictive_probabilities(
        scale, scale.thresholds_for(1.0), post.mean_at(idx), np.diag(post.covariance_at(idx))
    )
    assert np.array_equal(post.rating_probabilities(idx), want)
