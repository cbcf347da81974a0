"""The new subject's own share (``model/population.py``, ``model/share_fit.py``): a dense
reference, its limits (share = 0: the subject alone; share = rho: the plain population model),
its samples, and the 1-D evidence fit with and without the gate."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import PreferenceGP, Space, SquaredExponential
from gaitpref.model.evidence import Hyperparameters, PairData
from gaitpref.model.likelihood import Probit
from gaitpref.model.population import (
    PopulationModel,
    PopulationPosterior,
    node_codes,
    population_evidence,
)
from gaitpref.model.population_fit import LogitNormal
from gaitpref.model.share_fit import fit_share, share_objective
from tests.dense_reference import dense_kernel, dense_laplace_ordered
from tests.model.test_population import SIGMA, _pair_data, _population_data

HYPER = Hyperparameters((0.03, 0.08), 0.005, 1e-7)


def _post(
    space: Space, kernel: SquaredExponential, rho: float, share: float | None,
    w: np.ndarray, l_: np.ndarray, who: np.ndarray,
) -> PopulationPosterior:  # fmt: skip
    model = PopulationModel(space, kernel, rho, SIGMA, share=share)
    post = model.posterior(
        node_codes(space, w, who), node_codes(space, l_, who), Probit(np.full(w.size, SIGMA)), 0
    )
    assert isinstance(post, PopulationPosterior)
    return post


@pytest.mark.parametrize(("rho", "share"), [(0.6, 0.1), (0.3, 0.9)])
def test_share_posterior_equals_a_dense_reference(
    small_space: Space, small_kernel: SquaredExponential, rho: float, share: float
) -> None:
    rng = np.random.default_rng(5)
    w, l_, who = _population_data(rng, small_space, 3, 10)
    A = len(small_space)
    task = rho + (1 - rho) * np.eye(3)
    task[0, 1:] = task[1:, 0] = np.sqrt(rho * share)  # f_0 = sqrt(share) g + sqrt(1 - share) h_0
    K = dense_kernel(small_space.points, (0.03, 0.08), 0.005, 1e-7)
    n = w.size
    f_ref, cov_ref, ev_ref = dense_laplace_ordered(
        np.kron(task, K), who * A + w, who * A + l_, np.full(n, SIGMA), np.zeros(n),
        np.zeros(n, bool),
    )  # fmt: skip
    pop = _post(small_space, small_kernel, rho, share, w, l_, who)
    scale = np.max(np.abs(f_ref))
    assert np.allclose(pop.mean, f_ref[:A], rtol=1e-7, atol=1e-8 * scale)
    cov = cov_ref[:A, :A]
    assert np.allclose(pop.covariance(), cov, rtol=1e-6, atol=1e-8 * np.max(cov))
    assert pop.log_evidence == pytest.approx(ev_ref, rel=1e-8)
    data = _pair_data(small_space, w, l_, who)
    value = population_evidence(small_space, HYPER, rho, data, share=share).value
    assert value == pytest.approx(ev_ref, rel=1e-8)


def test_share_zero_is_the_subject_alone_and_share_rho_the_plain_model(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    rng = np.random.default_rng(3)
    w, l_, who = _population_data(rng, small_space, 3, 12)
    alone = _post(small_space, small_kernel, 0.7, 0.0, w, l_, who)
    mine = who == 0
    single = PreferenceGP(small_space, small_kernel, SIGMA).posterior(w[mine], l_[mine])
    assert np.allclose(alone.mean, single.mean, rtol=0, atol=1e-9 * np.max(np.abs(single.mean)))
    assert np.allclose(alone.covariance(), single.covariance(), rtol=1e-8, atol=1e-15)
    ra, rb = np.random.default_rng(7), np.random.default_rng(7)
    a, b = alone.sample(ra, 5), single.sample(rb, 5)
    assert np.allclose(a, b, rtol=0, atol=1e-8 * np.max(np.abs(b)))
    assert ra.bit_generator.state == rb.bit_generator.state  # the loop proposes as if alone
    same = _post(small_space, small_kernel, 0.7, 0.7, w, l_, who)
    plain = _post(small_space, small_kernel, 0.7, None, w, l_, who)
    assert np.array_equal(same.mean, plain.mean)
    assert np.array_equal(
        same.sample(np.random.default_rng(2), 3), plain.sample(np.random.default_rng(2), 3)
    )


def test_share_samples_have_the_posterior_moments(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    """20000 draws, 5 standard errors: the joint prior draw with the subject's own loading."""
    rng = np.random.default_rng(8)
    w, l_, who = _population_data(rng, small_space, 3, 8)
    pop = _post(small_space, small_kernel, 0.6, 0.2, w, l_, who)
    draws = pop.sample(np.random.default_rng(0), 20000)
    sd = np.sqrt(pop.variance)
    assert np.all(np.abs(draws.mean(axis=0) - pop.mean) < 5 * sd / np.sqrt(20000))
    assert np.all(np.abs(draws.var(axis=0) / pop.variance - 1) < 5 * np.sqrt(2 / 20000))


def _subjects(space: Space, new_like_others: bool) -> PairData:
    """Two earlier subjects who agree, and a new one who agrees with them or is reversed."""
    rng = np.random.default_rng(4)
    A = len(space)
    utility = rng.normal(size=A)
    w, l_, who = [], [], []
    for s, sign in ((0, 1.0 if new_like_others else -1.0), (1, 1.0), (2, 1.0)):
        for _ in range(25):
            i, j = rng.choice(A, 2, replace=False)
            first = sign * (utility[i] - utility[j]) > 0
            w.append(i if first else j)
            l_.append(j if first else i)
            who.append(s)
    return _pair_data(space, np.array(w), np.array(l_), np.array(who))


def test_the_share_fit_maximises_the_objective_and_the_gate_lets_go(small_space: Space) -> None:
    prior = LogitNormal(0.6, 1.5)
    for like in (True, False):
        data = _subjects(small_space, like)
        fit = fit_share(small_space, HYPER, 0.6, 0.6, data, prior)
        assert fit.accepted
        best = share_objective(small_space, HYPER, 0.6, fit.after, data, prior)
        assert best == pytest.approx(fit.objective_after, rel=1e-12)
        grid = [share_objective(small_space, HYPER, 0.6, s, data, prior) for s in (0.05, 0.3, 0.9)]
        assert best >= max(grid) - 1e-3
        gated = fit_share(small_space, HYPER, 0.6, 0.0, data, prior, gate=1.0)
        if like:  # agreeing with the others: the evidence supports sharing
            assert fit.after > 0.7 and gated.after == pytest.approx(fit.after, abs=0.05)
        else:  # reversed: let go of the others
            assert fit.after < 0.3 and gated.after == 0.0
