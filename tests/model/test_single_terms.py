"""Single-action likelihood terms in the Laplace fit (the shape ordinal ratings will use).

Checked on two toy likelihoods written here: a Gaussian observation ``y ~ N(f_s, s^2)``, whose
Laplace posterior is exact GP regression (closed form), and a binary probit ``P(y) = Phi(y f_s/s)``
mixed with pairwise preferences, against a dense Newton over all actions written here too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from scipy.special import log_ndtr
from scipy.stats import norm

from gaitpref import PreferenceGP, Space, SquaredExponential
from gaitpref.model.likelihood import Probit, StackedActionLikelihood
from tests.dense_reference import dense_kernel


@dataclass(frozen=True)
class GaussianObservation:
    y: np.ndarray
    s: float

    def terms(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        r = self.y - values
        logp = -0.5 * (r / self.s) ** 2 - np.log(self.s * np.sqrt(2 * np.pi))
        return logp, r / self.s**2, np.full(values.shape, 1.0 / self.s**2)


@dataclass(frozen=True)
class BinaryProbit:
    y: np.ndarray  # +1 / -1
    s: float

    def terms(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        z = self.y * values / self.s
        ratio = np.exp(norm.logpdf(z) - log_ndtr(z))
        return log_ndtr(z), self.y * ratio / self.s, ratio * (ratio + z) / self.s**2


def _kernel_matrix(space: Space) -> np.ndarray:
    return dense_kernel(space.points, (0.03, 0.08), 0.005, 1e-7)


@pytest.mark.parametrize("seed", range(3))
def test_gaussian_single_terms_give_exact_gp_regression(
    small_space: Space, small_kernel: SquaredExponential, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    actions = rng.choice(len(small_space), size=12, replace=True)
    y = rng.normal(0.0, 0.05, actions.size)
    s = 0.03
    gp = PreferenceGP(small_space, small_kernel, 0.02)
    none = np.zeros(0, dtype=np.intp)
    post = gp.posterior_from(
        none, none, Probit(np.zeros(0)), single=actions, single_likelihood=GaussianObservation(y, s)
    )
    K = _kernel_matrix(small_space)
    Kxs = K[:, actions]
    gram = K[np.ix_(actions, actions)] + s**2 * np.eye(actions.size)
    mean = Kxs @ np.linalg.solve(gram, y)
    cov = K - Kxs @ np.linalg.solve(gram, Kxs.T)
    assert np.allclose(post.mean, mean, rtol=1e-7, atol=1e-9)
    assert np.allclose(post.covariance(), cov, rtol=1e-7, atol=1e-11)


def _dense_mixed(
    K: np.ndarray,
    w: np.ndarray,
    l: np.ndarray,
    sigma: float,
    single: np.ndarray,
    y: np.ndarray,
    s: float,
) -> tuple[np.ndarray, np.ndarray]:
    A = K.shape[0]
    K_inv = np.linalg.solve(K, np.eye(A))
    G = np.zeros((w.size, A))
    G[np.arange(w.size), w] += 1.0
    G[np.arange(w.size), l] -= 1.0
    E = np.zeros((single.size, A))
    E[np.arange(single.size), single] = 1.0
    scale = np.sqrt(2.0) * sigma

    def derivs(f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        z = (G @ f) / scale
        r = np.exp(norm.logpdf(z) - norm.logcdf(z))
        zs = y * (E @ f) / s
        rs = np.exp(norm.logpdf(zs) - norm.logcdf(zs))
        grad = G.T @ (r / scale) + E.T @ (y * rs / s)
        lam = G.T @ (((r**2 + z * r) / scale**2)[:, None] * G)
        lam += E.T @ (((rs**2 + zs * rs) / s**2)[:, None] * E)
        return grad, lam

    f = np.zeros(A)
    for _ in range(200):
        grad, lam = derivs(f)
        step = np.linalg.solve(K_inv + lam, K_inv @ f - grad)
        f = f - step
        if np.max(np.abs(step)) < 1e-15 * max(1.0, np.max(np.abs(f))):
            break
    _, lam = derivs(f)
    cov = np.linalg.solve(K_inv + lam, np.eye(A))
    return f, 0.5 * (cov + cov.T)


@pytest.mark.parametrize("seed", range(3))
def test_pairs_and_single_terms_together_match_a_dense_newton(
    small_space: Space, small_kernel: SquaredExponential, seed: int
) -> None:
    rng = np.random.default_rng(100 + seed)
    A = len(small_space)
    w, l = rng.integers(0, A, 20), rng.integers(0, A, 20)
    keep = w != l
    w, l = w[keep], l[keep]
    single = rng.integers(0, A, 15)
    y = rng.choice([-1.0, 1.0], single.size)
    sigma, s = 0.02, 0.05
    gp = PreferenceGP(small_space, small_kernel, sigma)
    # two blocks through the stacked likelihood: the same data split in two kinds
    lik = StackedActionLikelihood(
        ((7, BinaryProbit(y[:7], s)), (single.size - 7, BinaryProbit(y[7:], s)))
    )
    post = gp.posterior_from(
        w, l, Probit(np.full(w.size, sigma)), single=single, single_likelihood=lik
    )
    f_ref, cov_ref = _dense_mixed(_kernel_matrix(small_space), w, l, sigma, single, y, s)
    assert np.allclose(post.mean, f_ref, rtol=1e-8, atol=1e-8 * np.max(np.abs(f_ref)))
    assert np.allclose(post.covariance(), cov_ref, rtol=1e-8, atol=1e-8 * np.max(np.abs(cov_ref)))


def test_no_single_terms_is_the_pair_only_fit_bit_for_bit(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    rng = np.random.default_rng(7)
    A = len(small_space)
    w, l = rng.integers(0, A, 30), rng.integers(0, A, 30)
    keep = w != l
    gp = PreferenceGP(small_space, small_kernel, 0.02)
    lik = Probit(np.full(int(keep.sum()), 0.02))
    plain = gp.posterior_from(w[keep], l[keep], lik)
    empty = gp.posterior_from(
        w[keep],
        l[keep],
        lik,
        single=np.zeros(0, dtype=np.intp),
        single_likelihood=GaussianObservation(np.zeros(0), 1.0),
    )
    assert np.array_equal(plain.mean, empty.mean)
    assert np.array_equal(plain.variance, empty.variance)


def test_single_terms_without_a_likelihood_are_refused(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    gp = PreferenceGP(small_space, small_kernel, 0.02)
    none = np.zeros(0, dtype=np.intp)
    with pytest.raises(ValueError, match="single_likelihood"):
        gp.posterior_from(none, none, Probit(np.zeros(0)), single=np.array([3]))
