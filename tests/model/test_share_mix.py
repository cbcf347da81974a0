"""Share hypotheses weighted by evidence x prior (``model/share_mix.py``): the weights against a
dense brute-force evidence, the prior's mass on "alone", one hypothesis is today's posterior
exactly, and a mixture's samples come from its components by weight."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gaitpref import Feature, Space, SquaredExponential
from gaitpref.loop.stopping import confidence
from gaitpref.model.evidence import Hyperparameters, PairData
from gaitpref.model.likelihood import Probit
from gaitpref.model.population import PopulationModel, node_codes
from gaitpref.model.share_fit import share_mixture_fit
from gaitpref.model.share_mix import (
    ALONE_PRIOR,
    SHARE_FACTORS,
    PosteriorMixture,
    share_prior,
    weigh_shares,
)
from tests.dense_reference import dense_kernel, dense_laplace_ordered
from tests.model.test_population import SIGMA, _pair_data, _population_data

RHO = 0.6
HYPER = Hyperparameters((0.3,), 0.005, 1e-7)
TINY = Space([Feature.linspace("x", 0.0, 1.0, 6)])  # 6 gaits x 3 subjects: 18 nodes


def _dense_log_evidence(
    space: Space, share: float, w: np.ndarray, l_: np.ndarray, who: np.ndarray
) -> float:
    """The Laplace evidence over every (gait, subject) node, by dense Newton (no visited set)."""
    A = len(space)
    task = RHO + (1 - RHO) * np.eye(3)
    task[0, 1:] = task[1:, 0] = np.sqrt(RHO * share)
    K = dense_kernel(space.points, HYPER.lengthscale, HYPER.variance, HYPER.jitter)
    n = w.size
    _, _, ev = dense_laplace_ordered(
        np.kron(task, K), who * A + w, who * A + l_, np.full(n, SIGMA), np.zeros(n),
        np.zeros(n, bool),
    )  # fmt: skip
    return float(ev)


def test_weights_equal_a_dense_brute_force_evidence_times_the_prior() -> None:
    rng = np.random.default_rng(3)
    w, l_, who = _population_data(rng, TINY, 3, 6)
    hypotheses = share_prior(RHO)
    weighed = weigh_shares(TINY, HYPER, RHO, hypotheses, _pair_data(TINY, w, l_, who))
    logs = [_dense_log_evidence(TINY, s, w, l_, who) + math.log(p) for s, p in hypotheses]
    top = max(logs)
    ref = np.exp(np.array(logs) - top)
    ref /= ref.sum()
    got = np.array([h.weight for h in weighed])
    assert np.allclose(got, ref, rtol=1e-6, atol=1e-9)
    assert got.sum() == pytest.approx(1.0)
    assert len(set(np.round(got, 6))) > 1  # the new subject's answers moved the weights
    for h, value in zip(weighed, logs, strict=True):
        assert h.objective is not None and weighed[0].objective is not None
        assert h.objective - weighed[0].objective == pytest.approx(value - logs[0], abs=1e-6)


def test_without_answers_of_the_new_subject_the_weights_are_the_prior() -> None:
    rng = np.random.default_rng(4)
    w, l_, who = _population_data(rng, TINY, 3, 6)
    theirs = who != 0  # the earlier subjects' evidence does not depend on the share
    data = _pair_data(TINY, w[theirs], l_[theirs], who[theirs])
    weighed = weigh_shares(TINY, HYPER, RHO, share_prior(RHO), data)
    assert [h.weight for h in weighed] == pytest.approx([h.prior for h in weighed], rel=1e-6)
    empty = PairData(np.zeros(0, np.intp), np.zeros(0, np.intp), np.zeros(0), np.zeros(0, bool),
                     np.zeros(0, bool))  # fmt: skip
    assert [h.weight for h in weigh_shares(TINY, HYPER, RHO, share_prior(RHO), empty)] == (
        pytest.approx([h.prior for h in weighed])
    )


def test_the_prior_puts_its_mass_on_alone_and_checks_its_factors() -> None:
    prior = share_prior(0.8)
    assert [s for s, _ in prior] == pytest.approx([c * 0.8 for c in SHARE_FACTORS])
    assert prior[0] == (0.0, ALONE_PRIOR) and ALONE_PRIOR >= 0.2
    assert share_prior(0.8, alone=0.6)[0] == (0.0, 0.6)
    assert share_prior(0.8, alone=0.6)[1] == pytest.approx((0.2, 0.1))
    assert sum(p for _, p in prior) == pytest.approx(1.0)
    assert share_prior(0.5, (1.0,)) == ((0.5, 1.0),)
    for bad in ((), (0.5, 0.5), (1.5,), (-0.1, 0.5)):
        with pytest.raises(ValueError, match="share factors"):
            share_prior(0.5, bad)
    with pytest.raises(ValueError, match="prior mass"):
        share_prior(0.5, alone=1.5)


def test_one_hypothesis_is_todays_posterior_exactly(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    rng = np.random.default_rng(5)
    w, l_, who = _population_data(rng, small_space, 3, 6)
    data = _pair_data(small_space, w, l_, who)
    lengthscales = small_kernel.lengthscales(small_space.ndim)
    hyper = Hyperparameters(lengthscales, small_kernel.variance, small_kernel.jitter)
    fit = share_mixture_fit(small_space, hyper, RHO, 0.0, data, hypotheses=[(0.3, 1.0)])
    assert fit.after == 0.3 and [h.weight for h in fit.hypotheses] == [1.0]
    model = PopulationModel(small_space, small_kernel, RHO, SIGMA, share=fit.after)
    post = model.posterior(
        node_codes(small_space, w, who), node_codes(small_space, l_, who),
        Probit(np.full(w.size, SIGMA)), 0,
    )  # fmt: skip
    mixture = PosteriorMixture(((1.0, post),))
    assert np.array_equal(mixture.mean, post.mean)
    a = confidence(post, np.random.default_rng(9), samples=400)
    b = confidence(post, np.random.default_rng(9), samples=400, draws=mixture)
    assert a == b


def test_a_mixtures_samples_come_from_its_components_by_weight(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    rng = np.random.default_rng(6)
    w, l_, who = _population_data(rng, small_space, 3, 8)
    first, second = node_codes(small_space, w, who), node_codes(small_space, l_, who)
    likelihood = Probit(np.full(w.size, SIGMA))
    posts = [
        PopulationModel(small_space, small_kernel, RHO, SIGMA, share=s).posterior(
            first, second, likelihood, 0
        )
        for s in (0.0, RHO)
    ]
    mixture = PosteriorMixture(((0.25, posts[0]), (0.75, posts[1])))
    assert np.allclose(mixture.mean, 0.25 * posts[0].mean + 0.75 * posts[1].mean)
    draws = mixture.sample(np.random.default_rng(1), 4000, nugget=False)
    assert np.allclose(draws.mean(axis=0), mixture.mean, atol=4 * np.sqrt(
        np.max(np.var(draws, axis=0)) / 4000))  # fmt: skip
    with pytest.raises(ValueError, match="sum to 1"):
        PosteriorMixture(((0.5, posts[0]), (0.4, posts[1])))
    with pytest.raises(ValueError, match="at least one"):
        PosteriorMixture(())
