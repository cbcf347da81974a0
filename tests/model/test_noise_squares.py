"""A noise whose square overflows is refused where it is given.

The likelihoods and predictive probabilities use ``noise**2``; on a Python float ``**`` raises
past ``sqrt(float max) ~ 1.34e154``, so a rating noise of 1e300 (accepted: finite, positive)
failed later with a bare ``OverflowError: (34, 'Numerical result out of range')`` from
``posterior(..., ratings=...)``, ``rating_probabilities`` or ``preference_probability``.  Found by
the property test of ``test_extreme_inputs.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import Feature, Ordinal, PreferenceGP, Space, SquaredExponential
from gaitpref.checks import MAX_NOISE
from gaitpref.model import OrdinalLikelihood, PopulationModel, Posterior

SPACE = Space([Feature.linspace("x", 0.0, 1.0, 4)])
KERNEL = SquaredExponential(0.3, 1.0, 1e-6)


@pytest.mark.parametrize("noise", [1e300, float(np.nextafter(MAX_NOISE, np.inf))])
def test_noises_with_an_infinite_square_are_refused(noise: float) -> None:
    with pytest.raises(ValueError, match="rating noise must be positive with a finite square"):
        Ordinal(3, noise=noise)
    with pytest.raises(ValueError, match="rating noise must be positive with a finite square"):
        OrdinalLikelihood(np.array([1]), np.array([0.0]), noise)
    with pytest.raises(ValueError, match="preference noise must be positive with a finite sq"):
        PreferenceGP(SPACE, KERNEL, noise)
    with pytest.raises(ValueError, match="preference noise must be positive with a finite sq"):
        PopulationModel(SPACE, KERNEL, 0.5, noise)
    engine = PreferenceGP(SPACE, KERNEL, 0.1).engine
    with pytest.raises(ValueError, match="preference noise must be None or positive with a"):
        Posterior(SPACE, KERNEL, None, engine, noise)


@pytest.mark.filterwarnings("ignore:overflow encountered in square:RuntimeWarning")
def test_the_largest_noise_works() -> None:
    scale = Ordinal(3, noise=MAX_NOISE)
    gp = PreferenceGP(SPACE, KERNEL, MAX_NOISE, ordinal=scale)
    post = gp.posterior([0], [1], ratings=[(2, 3)])
    assert post.preference_probability(0, 1) == pytest.approx(0.5)
    probs = post.rating_probabilities(np.arange(4))
    assert np.all(np.isfinite(probs)) and np.allclose(probs.sum(axis=1), 1.0)


def test_thresholds_from_an_overflowing_scale_are_refused() -> None:
    """``sqrt(v + s^2)`` past float max gave infinite thresholds (NaN for the middle one)."""
    with pytest.raises(ValueError, match="overflows: no thresholds"):
        Ordinal(2, noise=MAX_NOISE).thresholds_for(1e308)
    assert Ordinal(2, thresholds=(0.0,), noise=MAX_NOISE).thresholds_for(1e308) == (0.0,)
