"""The region of avoidance's rules (``loop/safety.py``): the probability of an avoided rating
(``risk``) against ROIAL's upper bound (``lambda``), and the thresholds the posterior carries."""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray
from scipy.special import ndtr

from gaitpref import Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.loop import Safety
from gaitpref.model.ordinal import Ordinal
from gaitpref.model.posterior import Posterior

SPACE = Space([Feature.linspace("x", 0.0, 1.0, 41)])
KERNEL = SquaredExponential(lengthscale=0.1, variance=1e-4, jitter=1e-8)
SCALE = Ordinal(["very bad", "bad", "okay", "good"], noise=0.01)  # as the model noise: default


def _rated(worst: list[int], good: list[int]) -> Posterior:
    gp = PreferenceGP(SPACE, KERNEL, 0.01, ordinal=SCALE)
    ratings = [(a, "very bad") for a in worst] + [(a, "good") for a in good]
    return gp.posterior([], [], ratings=ratings)


def _avoided(safety: Safety, post: Posterior) -> NDArray[np.bool_]:
    allowed = safety.allowed(post, SCALE, ())
    assert allowed is not None
    return ~allowed


def test_gaits_rated_very_bad_leave_the_region_under_risk_but_not_under_roials_bound() -> None:
    worst, good = [4, 5, 6], [30, 34, 38]
    post = _rated(worst, good)
    avoided_risk = _avoided(Safety(avoid=1, risk=0.35), post)
    avoided_roial = _avoided(Safety(avoid=1, lam=1.0), post)
    assert avoided_risk[worst].all() and not avoided_risk[good].any()
    assert not avoided_risk[20]  # far from every rating: still the prior's 1/4 < 0.35
    # the defect the risk rule fixes: one rating per gait never takes mu + sd below t_1
    assert not avoided_roial.any()
    many = _rated([2, 3, 4, 5, 6], good)
    assert _avoided(Safety(avoid=1, lam=1.0), many)[[3, 4, 5]].all()  # five neighbours do


def test_risk_is_the_predictive_probability_of_an_avoided_rating() -> None:
    post = _rated([1, 2, 8], [25, 40])
    t2 = SCALE.thresholds_for(KERNEL.variance)[1]
    var = np.asarray(post.variance)
    dense = ndtr((t2 - np.asarray(post.mean)) / np.sqrt(SCALE.noise**2 + var))
    probs = post.rating_probabilities(np.arange(len(SPACE)))
    np.testing.assert_allclose(probs[:, :2].sum(axis=1), dense, atol=1e-12)
    np.testing.assert_array_equal(_avoided(Safety(avoid=2, risk=0.6), post), dense > 0.6)
    assert 0 < np.sum(dense > 0.6) < len(SPACE)


def test_the_region_uses_the_posteriors_thresholds() -> None:
    post, safety = _rated([2, 3], [30]), Safety(avoid=1, risk=0.35)
    high = dataclasses.replace(post, ordinal=Ordinal(SCALE.categories, (0.5, 0.6, 0.7), 0.01))
    low = dataclasses.replace(post, ordinal=Ordinal(SCALE.categories, (-0.5, 0.6, 0.7), 0.01))
    assert safety.avoided(high, SCALE).all()  # every utility lies far below t_1 = 0.5
    assert not safety.avoided(low, SCALE).any()  # and far above t_1 = -0.5
    roial = Safety(avoid=1, lam=1.0)
    assert roial.avoided(high, SCALE).all() and not roial.avoided(low, SCALE).any()


def test_screening_by_the_variances_bounds_changes_no_decision() -> None:
    post = _rated([2, 3, 5, 9, 12], [25, 30, 31, 40])
    mean, var = np.asarray(post.mean), np.asarray(post.variance)  # the whole grid's, densely
    t1, t2 = SCALE.thresholds_for(KERNEL.variance)[:2]
    for lam in (0.0, 0.5, 1.0, 2.0):
        assert np.array_equal(
            _avoided(Safety(avoid=1, lam=lam), post), mean + lam * np.sqrt(var) < t1
        )
    for risk in (0.26, 0.35, 0.5, 0.9):
        dense = ndtr((t1 - mean) / np.sqrt(SCALE.noise**2 + var)) > risk
        assert np.array_equal(_avoided(Safety(avoid=1, risk=risk), post), dense)
    dense = ndtr((t2 - mean) / np.sqrt(SCALE.noise**2 + var)) > 0.6
    assert np.array_equal(_avoided(Safety(avoid=2, risk=0.6), post), dense)
