"""Samples without the nugget (``Posterior.sample(..., nugget=False)``): the smooth part ``g`` of
``f = g + e``, where ``e`` is the kernel's jitter (independent per gait), against a dense
reference, for one subject and for a population."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import PreferenceGP, Space, SquaredExponential
from gaitpref.model.likelihood import Probit
from gaitpref.model.population import PopulationModel, node_codes
from gaitpref.model.posterior import Posterior
from tests.dense_reference import dense_kernel, dense_laplace_ordered

SCALES, VARIANCE, JITTER, SIGMA = (0.03, 0.08), 0.005, 0.002, 0.05  # a large nugget: visible
DRAWS = 20000


def _data(space: Space, subjects: int, per: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    A = len(space)
    shared = rng.normal(size=A)
    w, loser, who = [], [], []
    for s in range(subjects):
        utility = shared + rng.normal(size=A)
        for _ in range(per):
            i, j = rng.choice(A, 2, replace=False)
            first = utility[i] > utility[j]
            w.append(i if first else j)
            loser.append(j if first else i)
            who.append(s)
    return np.array(w), np.array(loser), np.array(who)


def _smooth_reference(
    space: Space, rho: float, subjects: int, w: np.ndarray, l_: np.ndarray, who: np.ndarray,
    target: int, task: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Mean and covariance of ``g_target`` from the dense Laplace over every (gait, subject):
    ``Ks_{t,:} K^-1 f_hat`` and ``Ks_tt - Ks_{t,:} K^-1 Ks_{:,t} + Ks_{t,:} K^-1 S K^-1 Ks_{:,t}``
    with ``Ks`` the kernel without the jitter and ``S`` the Laplace covariance."""
    A = len(space)
    if task is None:
        task = rho + (1 - rho) * np.eye(subjects)
    smooth = dense_kernel(space.points, SCALES, VARIANCE, 0.0)
    K = np.kron(task, smooth + JITTER * np.eye(A))
    n = w.size
    f_hat, S, _ = dense_laplace_ordered(
        K, who * A + w, who * A + l_, np.full(n, SIGMA), np.zeros(n), np.zeros(n, bool)
    )
    cross = np.kron(task[target : target + 1], smooth)  # Ks_{t,:}: A x (S A)
    B = np.linalg.solve(K, cross.T)  # K^-1 Ks_{:,t}
    return cross @ np.linalg.solve(K, f_hat), smooth - cross @ B + B.T @ S @ B


def _check_moments(post: Posterior, mean: np.ndarray, cov: np.ndarray) -> None:
    ra, rb = np.random.default_rng(0), np.random.default_rng(0)
    g = post.sample(ra, DRAWS, nugget=False)
    f = post.sample(rb, DRAWS)
    assert ra.bit_generator.state == rb.bit_generator.state  # the same use of the generator
    sd = np.sqrt(np.diag(cov))
    assert np.all(np.abs(g.mean(axis=0) - mean) < 5 * sd / np.sqrt(DRAWS))
    assert np.all(np.abs(g.var(axis=0) / np.diag(cov) - 1) < 5 * np.sqrt(2 / DRAWS))
    emp = np.cov(g, rowvar=False)
    assert np.max(np.abs(emp - cov)) < 6 * np.max(np.diag(cov)) / np.sqrt(DRAWS)
    # what was left out is the nugget: at a gait no one visited, f = g + e with e independent
    gaits = post.visited % len(post.space)
    away = np.setdiff1d(np.arange(len(post.space)), gaits)
    assert away.size > 5
    extra = (f - g)[:, away]
    assert np.all(np.abs(extra.var(axis=0) / JITTER - 1) < 5 * np.sqrt(2 / DRAWS))


def test_one_subject(small_space: Space) -> None:
    kernel = SquaredExponential(SCALES, VARIANCE, JITTER)
    w, l_, _ = _data(small_space, 1, 14)
    post = PreferenceGP(small_space, kernel, SIGMA).posterior(w, l_)
    mean, cov = _smooth_reference(small_space, 0.0, 1, w, l_, np.zeros_like(w), 0)
    assert not np.allclose(np.asarray(post.mean), mean)  # the jitter's share is visible
    _check_moments(post, mean, cov)


@pytest.mark.parametrize("rho", [0.0, 0.6, 1.0])
def test_a_population(small_space: Space, rho: float) -> None:
    kernel = SquaredExponential(SCALES, VARIANCE, JITTER)
    w, l_, who = _data(small_space, 3, 8)
    model = PopulationModel(small_space, kernel, rho, SIGMA)
    first, second = node_codes(small_space, w, who), node_codes(small_space, l_, who)
    post = model.posterior(first, second, Probit(np.full(w.size, SIGMA)), 1)
    if rho == 1.0:  # pooled: one subject's data
        mean, cov = _smooth_reference(small_space, 0.0, 1, w, l_, np.zeros_like(w), 0)
    else:
        mean, cov = _smooth_reference(small_space, rho, 3, w, l_, who, 1)
    _check_moments(post, mean, cov)


def test_the_prior_without_the_nugget(small_space: Space) -> None:
    kernel = SquaredExponential(SCALES, VARIANCE, JITTER)
    post = PreferenceGP(small_space, kernel, SIGMA).prior()
    g = post.sample(np.random.default_rng(1), DRAWS, nugget=False)
    cov = dense_kernel(small_space.points, SCALES, VARIANCE, 0.0)
    assert np.max(np.abs(np.cov(g, rowvar=False) - cov)) < 6 * VARIANCE / np.sqrt(DRAWS)


@pytest.mark.parametrize(("rho", "share"), [(0.6, 0.2), (0.3, 0.9)])
def test_the_new_subjects_own_share(small_space: Space, rho: float, share: float) -> None:
    """The new subject (0) with a share of their own (``model/population.py``): the task
    covariance ``[[1, sqrt(share rho) 1^T], [., rho + (1 - rho) I]]``, jitter included."""
    kernel = SquaredExponential(SCALES, VARIANCE, JITTER)
    w, l_, who = _data(small_space, 3, 8)
    model = PopulationModel(small_space, kernel, rho, SIGMA, share=share)
    first, second = node_codes(small_space, w, who), node_codes(small_space, l_, who)
    post = model.posterior(first, second, Probit(np.full(w.size, SIGMA)), 0)
    task = rho + (1 - rho) * np.eye(3)
    task[0, 1:] = task[1:, 0] = np.sqrt(share * rho)
    mean, cov = _smooth_reference(small_space, rho, 3, w, l_, who, 0, task=task)
    _check_moments(post, mean, cov)
