"""The population model: its limits (rho = 0, rho = 1), a dense reference, the evidence."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gaitpref import Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.model.evidence import Hyperparameters, PairData
from gaitpref.model.likelihood import Probit
from gaitpref.model.population import (
    PopulationModel,
    PopulationPosterior,
    logit,
    node_codes,
    population_evidence,
)
from tests.dense_reference import dense_kernel, dense_laplace_ordered

SIGMA = 0.02


def _population_data(
    rng: np.random.Generator, space: Space, subjects: int, per_subject: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Winners, losers (grid indices) and the subject of each preference: a utility per subject
    (a shared random direction plus an individual one) and noisy answers."""
    A = len(space)
    shared = rng.normal(size=A)
    w, loser, who = [], [], []
    for s in range(subjects):
        utility = shared + rng.normal(size=A)
        for _ in range(per_subject):
            i, j = rng.choice(A, 2, replace=False)
            first = utility[i] + rng.normal(0, 0.3) > utility[j]
            w.append(i if first else j)
            loser.append(j if first else i)
            who.append(s)
    return np.array(w), np.array(loser), np.array(who)


def _population(
    space: Space, kernel: SquaredExponential, rho: float, w: np.ndarray, l_: np.ndarray,
    who: np.ndarray, target: int,
) -> PopulationPosterior:  # fmt: skip
    model = PopulationModel(space, kernel, rho, SIGMA)
    post = model.posterior(
        node_codes(space, w, who), node_codes(space, l_, who), Probit(np.full(w.size, SIGMA)),
        target,
    )  # fmt: skip
    assert isinstance(post, PopulationPosterior)
    return post


@pytest.mark.parametrize("target", [0, 1, 2])
def test_rho_zero_is_the_single_subject_posterior(
    small_space: Space, small_kernel: SquaredExponential, target: int
) -> None:
    rng = np.random.default_rng(target)
    w, l_, who = _population_data(rng, small_space, 3, 12)
    pop = _population(small_space, small_kernel, 0.0, w, l_, who, target)
    mine = who == target
    single = PreferenceGP(small_space, small_kernel, SIGMA).posterior(w[mine], l_[mine])
    scale = np.max(np.abs(single.mean))
    assert np.allclose(pop.mean, single.mean, rtol=0, atol=1e-9 * scale)
    assert np.allclose(pop.variance, single.variance, rtol=1e-9, atol=1e-15)
    assert np.allclose(pop.covariance(), single.covariance(), rtol=1e-8, atol=1e-15)
    assert pop.log_evidence != pytest.approx(single.log_evidence)  # the others' data are in it
    ra, rb = np.random.default_rng(7), np.random.default_rng(7)
    a, b = pop.sample(ra, 5), single.sample(rb, 5)
    assert np.allclose(a, b, rtol=0, atol=1e-8 * np.max(np.abs(b)))
    assert ra.bit_generator.state == rb.bit_generator.state  # a loop proposes as it would alone


def test_rho_one_pools_the_data_as_one_subject(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    rng = np.random.default_rng(11)
    w, l_, who = _population_data(rng, small_space, 3, 10)
    pop = _population(small_space, small_kernel, 1.0, w, l_, who, 2)
    pooled = PreferenceGP(small_space, small_kernel, SIGMA).posterior(w, l_)
    assert pop.visited.size == np.unique(np.concatenate([w, l_])).size
    assert np.allclose(pop.mean, pooled.mean, rtol=0, atol=1e-10 * np.max(np.abs(pooled.mean)))
    assert np.allclose(pop.covariance(), pooled.covariance(), rtol=1e-9, atol=1e-16)
    assert pop.log_evidence == pytest.approx(pooled.log_evidence, rel=1e-10)
    a = pop.sample(np.random.default_rng(3), 4)
    b = pooled.sample(np.random.default_rng(3), 4)
    assert np.allclose(a, b, rtol=0, atol=1e-9 * np.max(np.abs(b)))


def _dense_population(
    space: Space, rho: float, subjects: int, w: np.ndarray, l_: np.ndarray, who: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float]:
    """Dense Laplace over all grid x subjects utilities (node s * A + x)."""
    K = dense_kernel(space.points, (0.03, 0.08), 0.005, 1e-7)
    task = rho + (1 - rho) * np.eye(subjects)
    A = len(space)
    first, second = who * A + w, who * A + l_
    n = w.size
    return dense_laplace_ordered(
        np.kron(task, K), first, second, np.full(n, SIGMA), np.zeros(n), np.zeros(n, bool)
    )


@pytest.mark.parametrize("rho", [0.3, 0.8])
def test_population_posterior_equals_a_dense_reference(
    small_space: Space, small_kernel: SquaredExponential, rho: float
) -> None:
    rng = np.random.default_rng(5)
    w, l_, who = _population_data(rng, small_space, 3, 10)
    A, target = len(small_space), 1
    f_ref, cov_ref, ev_ref = _dense_population(small_space, rho, 3, w, l_, who)
    block = slice(target * A, (target + 1) * A)
    pop = _population(small_space, small_kernel, rho, w, l_, who, target)
    # the visited set is the distinct (gait, subject) pairs, never the grid times the subjects
    assert pop.visited.size == np.unique(np.concatenate([who * A + w, who * A + l_])).size
    scale = np.max(np.abs(f_ref))
    assert np.allclose(pop.mean, f_ref[block], rtol=1e-7, atol=1e-8 * scale)
    cov = cov_ref[block, block]
    assert np.allclose(pop.covariance(), cov, rtol=1e-6, atol=1e-8 * np.max(cov))
    assert np.allclose(pop.variance, np.diag(cov), rtol=1e-6, atol=1e-8 * np.max(cov))
    assert pop.log_evidence == pytest.approx(ev_ref, rel=1e-8)
    hyper = Hyperparameters((0.03, 0.08), 0.005, 1e-7)
    data = _pair_data(small_space, w, l_, who)
    assert population_evidence(small_space, hyper, rho, data).value == pytest.approx(
        ev_ref, rel=1e-8
    )


def test_samples_have_the_posterior_moments(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    """The joint prior draw over the subject's grid and the others' nodes is right: the
    samples' mean and covariance match the posterior's (20000 draws, 5 standard errors)."""
    rng = np.random.default_rng(8)
    w, l_, who = _population_data(rng, small_space, 3, 8)
    pop = _population(small_space, small_kernel, 0.6, w, l_, who, 0)
    draws = pop.sample(np.random.default_rng(0), 20000)
    sd = np.sqrt(pop.variance)
    assert np.all(np.abs(draws.mean(axis=0) - pop.mean) < 5 * sd / np.sqrt(20000))
    emp_var = draws.var(axis=0)
    assert np.all(np.abs(emp_var / pop.variance - 1) < 5 * np.sqrt(2 / 20000))


def _pair_data(space: Space, w: np.ndarray, l_: np.ndarray, who: np.ndarray) -> PairData:
    n = w.size
    return PairData(
        node_codes(space, w, who), node_codes(space, l_, who), np.full(n, SIGMA),
        np.zeros(n, bool), np.zeros(n, bool),
    )  # fmt: skip


@settings(max_examples=6, deadline=None)
@given(seed=st.integers(0, 10_000), rho=st.floats(0.05, 0.95))
def test_evidence_gradient_matches_finite_differences(seed: int, rho: float) -> None:
    space = Space(
        [
            Feature.linspace("step_length", 0.08, 0.18, 7, unit="m"),
            Feature.linspace("step_duration", 0.85, 1.15, 5, unit="s"),
        ]
    )
    rng = np.random.default_rng(seed)
    w, l_, who = _population_data(rng, space, 3, 10)
    data = _pair_data(space, w, l_, who)
    hyper = Hyperparameters((0.025, 0.1), 0.004, 4e-7)
    ev = population_evidence(space, hyper, rho, data)
    theta = np.concatenate([hyper.log_vector(), [logit(rho)]])
    assert ev.gradient.shape == theta.shape
    eps = 1e-5

    def value(t: np.ndarray) -> float:
        r = float(1 / (1 + np.exp(-t[-1])))
        return population_evidence(space, hyper.with_log_vector(t[:-1]), r, data).value

    for j in np.flatnonzero(np.isfinite(theta)):
        up, down = theta.copy(), theta.copy()
        up[j] += eps
        down[j] -= eps
        fd = (value(up) - value(down)) / (2 * eps)
        assert ev.gradient[j] == pytest.approx(fd, rel=1e-5, abs=1e-6), j
    assert ev.gradient[space.ndim + 1] == 0.0  # no band


def test_refuses_rho_outside_the_unit_interval(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    with pytest.raises(ValueError, match="rho must lie in"):
        PopulationModel(small_space, small_kernel, 1.2, SIGMA)


def _subjects_alike(
    rng: np.random.Generator, space: Space, alike: bool, subjects: int = 4
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Preferences of ``subjects`` subjects with one utility (``alike``) or independent ones."""
    x = space.points
    w, l_, who = [], [], []
    centres = rng.uniform(space.points.min(0), space.points.max(0), (subjects, space.ndim))
    if alike:
        centres[:] = centres[0]
    span = np.ptp(x, axis=0)
    for s in range(subjects):
        utility = -np.sum(((x - centres[s]) / span) ** 2, axis=1)
        for _ in range(25):
            i, j = rng.choice(len(space), 2, replace=False)
            first = utility[i] + rng.normal(0, 0.02) > utility[j]
            w.append(i if first else j)
            l_.append(j if first else i)
            who.append(s)
    return np.array(w), np.array(l_), np.array(who)


@pytest.mark.parametrize("seed", [0, 1])
def test_the_evidence_learns_how_much_the_subjects_share(small_space: Space, seed: int) -> None:
    from gaitpref.model.hyperfit import default_prior
    from gaitpref.model.population_fit import fit_population

    prior = default_prior(small_space, 0.005, SIGMA)
    start = Hyperparameters((0.03, 0.08), 0.005, 1e-7)
    fitted = {}
    for alike in (True, False):
        w, l_, who = _subjects_alike(np.random.default_rng(seed), small_space, alike)
        fit = fit_population(small_space, start, 0.5, _pair_data(small_space, w, l_, who), prior)
        assert fit.accepted, fit.message
        assert fit.objective_after >= fit.objective_before
        fitted[alike] = fit.rho_after
    assert fitted[True] > 0.7
    assert fitted[False] < 0.5
