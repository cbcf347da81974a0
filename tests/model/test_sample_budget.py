"""Joint samples are bounded by ``size x points`` values, not by a fixed count.

``Posterior.sample(rng, k)`` and everything that draws through it (``argmax_samples``, the
strategies, a warm start's mixture, the prior samplers) built ``k x A`` arrays for any ``k``:
``k = 10**9`` asked NumPy for petabytes (a MemoryError, or on a smaller grid an allocation that
ran the machine out of memory).  Now ``k x A`` past ``SAMPLE_LIMIT_ELEMENTS`` (1 GiB of float64)
is a ValueError naming ``size``, the points and the budget, raised before anything is drawn; a
count within it (plausible-eubo's 32 draws on 10**6 gaits) is drawn as before.
"""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import Feature, PointSet, PreferenceGP, Space, SquaredExponential
from gaitpref.config.schema import MAX_ACTIONS, MAX_QUERY
from gaitpref.model import SAMPLE_LIMIT_ELEMENTS, KroneckerPriorSampler, PopulationModel, Probit
from gaitpref.model.engines import PointEngine
from gaitpref.model.share_mix import PosteriorMixture
from gaitpref.strategies import AskContext, PlausibleEubo

KERNEL = SquaredExponential(0.3, 1.0, 1e-6)
#: 32**4 = 1,048,576 gaits: the scalable (Kronecker) path; cheap to build, never sampled in full
BIG = Space([Feature.linspace(c, 0.0, 1.0, 32) for c in "abcd"])
SMALL = Space([Feature.linspace("a", 0.0, 1.0, 8), Feature.linspace("b", 0.0, 1.0, 6)])
HUGE = 10**9  # without the bound: a MemoryError (petabytes) from NumPy


def _message(size: int, points: int) -> str:
    return rf"size = {size} samples over {points} points .* budget of {SAMPLE_LIMIT_ELEMENTS:,}"


def test_the_budget_is_the_covariance_bound_and_admits_the_largest_config_query() -> None:
    assert SAMPLE_LIMIT_ELEMENTS == 1 << 27  # 1 GiB, as covariance()
    assert SAMPLE_LIMIT_ELEMENTS >= MAX_QUERY * MAX_ACTIONS  # a config's largest query, grid


@pytest.mark.parametrize("sampler", ["dense", "scalable"])
def test_grid_posteriors_refuse_a_sample_past_the_budget(sampler: str) -> None:
    gp = PreferenceGP(SMALL, KERNEL, 0.1, sampler=sampler)
    for post in (gp.prior(), gp.posterior([0, 3], [5, 7])):
        with pytest.raises(ValueError, match=_message(HUGE, len(SMALL))):
            post.sample(np.random.default_rng(0), HUGE)
        with pytest.raises(ValueError, match=_message(HUGE, len(SMALL))):
            post.argmax_samples(np.random.default_rng(0), HUGE)
        assert post.sample(np.random.default_rng(0), 3).shape == (3, len(SMALL))


def test_a_million_gaits_refuse_one_sample_past_the_budget() -> None:
    post = PreferenceGP(BIG, KERNEL, 0.1).posterior([0, 5], [7, 9])
    assert post.sampler == "scalable"
    most = SAMPLE_LIMIT_ELEMENTS // len(BIG)
    with pytest.raises(ValueError, match=_message(most + 1, len(BIG))):
        post.sample(np.random.default_rng(0), most + 1)
    with pytest.raises(ValueError, match=f"draw at most {most} samples at a time"):
        post.sample(np.random.default_rng(0), HUGE, nugget=False)
    assert post.sample(np.random.default_rng(0), 1).shape == (1, len(BIG))


def test_the_kronecker_prior_sampler_refuses_past_the_budget() -> None:
    sampler = KroneckerPriorSampler(BIG, KERNEL)
    with pytest.raises(ValueError, match=_message(HUGE, len(BIG))):
        sampler.sample(np.random.default_rng(0), HUGE)


def test_the_line_paths_point_sets_refuse_past_the_budget() -> None:
    domain = Space([Feature.interval("x", 0.0, 1.0), Feature.interval("y", 0.0, 1.0)])
    points = PointSet(domain, np.random.default_rng(1).random((40, 2)))
    post = PreferenceGP(points, KERNEL, 0.1).posterior([0, 1], [2, 3])
    with pytest.raises(ValueError, match=_message(HUGE, 40)):
        post.sample(np.random.default_rng(0), HUGE)
    with pytest.raises(ValueError, match=_message(HUGE, 40)):
        PointEngine(points, KERNEL).prior_parts(np.random.default_rng(0), HUGE)


def test_population_posteriors_and_mixtures_refuse_past_the_budget() -> None:
    model = PopulationModel(SMALL, KERNEL, 0.5, 0.1)
    size = len(SMALL)
    first, second = np.array([0, size + 3]), np.array([4, size + 9])
    post = model.posterior(first, second, Probit(np.full(2, 0.1)), 0)
    with pytest.raises(ValueError, match=_message(HUGE, size)):
        post.sample(np.random.default_rng(0), HUGE)
    prior = PreferenceGP(SMALL, KERNEL, 0.1).prior()
    mixture = PosteriorMixture(((0.5, post), (0.5, prior)))
    with pytest.raises(ValueError, match=_message(HUGE, size)):
        mixture.sample(np.random.default_rng(0), HUGE)  # before: rng.choice of 10**9 indices
    with pytest.raises(ValueError, match="an integer >= 0"):
        mixture.sample(np.random.default_rng(0), -1)
    assert mixture.sample(np.random.default_rng(0), 2).shape == (2, size)


def test_plausible_eubo_past_the_budget_is_refused_by_name() -> None:
    """Its default 32 draws fit on 10**6 gaits (a fixed cap on k would have refused them or
    let 4096 through); 4096 draws there are refused before any is drawn."""
    assert PlausibleEubo().samples * len(BIG) <= SAMPLE_LIMIT_ELEMENTS
    post = PreferenceGP(BIG, KERNEL, 0.1).posterior([0, 5], [7, 9])
    context = AskContext(post, 1, (0,), 2, np.random.default_rng(0))
    with pytest.raises(ValueError, match=_message(4096, len(BIG))):
        PlausibleEubo(samples=4096).propose(context)
