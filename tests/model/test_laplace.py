from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.special import log_ndtr

from gaitpref import Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.errors import ConvergenceError
from gaitpref.model.laplace import fit_laplace
from gaitpref.model.likelihood import Probit
from tests.dense_reference import dense_kernel, dense_laplace


def _random_data(rng: np.random.Generator, A: int, N: int) -> tuple[np.ndarray, np.ndarray]:
    w = rng.integers(0, A, N)
    l = rng.integers(0, A, N)
    keep = w != l
    return w[keep], l[keep]


@pytest.mark.parametrize("seed", range(4))
def test_posterior_equals_independent_dense_reference(
    small_space: Space, small_kernel: SquaredExponential, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    w, l = _random_data(rng, len(small_space), int(rng.integers(5, 60)))
    sigma = rng.uniform(0.01, 0.04, w.size)
    post = PreferenceGP(small_space, small_kernel, 0.02).posterior(w, l, sigma)
    K = dense_kernel(small_space.points, (0.03, 0.08), 0.005, 1e-7)
    f_ref, cov_ref = dense_laplace(K, w, l, sigma)
    assert np.allclose(post.mean, f_ref, rtol=1e-8, atol=1e-8 * np.max(np.abs(f_ref)))
    cov = post.covariance()
    assert np.allclose(cov, cov_ref, rtol=1e-8, atol=1e-8 * np.max(np.abs(cov_ref)))
    assert np.allclose(post.variance, np.diag(cov_ref), rtol=1e-8)


def test_mode_has_zero_gradient_over_all_actions(
    small_space: Space, small_kernel: SquaredExponential, rng: np.random.Generator
) -> None:
    w, l = _random_data(rng, len(small_space), 40)
    post = PreferenceGP(small_space, small_kernel, 0.02).posterior(w, l)
    K = small_kernel.dense(small_space)
    f = np.asarray(post.mean)
    scale = np.sqrt(2) * 0.02
    z = (f[w] - f[l]) / scale
    r = np.exp(-0.5 * z**2 - 0.5 * np.log(2 * np.pi) - log_ndtr(z))
    g = np.zeros(len(small_space))
    np.add.at(g, w, r / scale)
    np.add.at(g, l, -r / scale)
    # grad of S = K^-1 f - g = 0  <=>  f = K g (no inverse needed to check it)
    assert np.allclose(f, K @ g, rtol=1e-9, atol=1e-12)
    assert post.fit is not None and post.fit.gradient_norm < 1e-9


def test_whitened_objective_gradient_and_hessian_match_finite_differences(
    small_space: Space, small_kernel: SquaredExponential, rng: np.random.Generator
) -> None:
    """The Newton system (gradient u - L^T G^T g, Hessian I + H^T H) against S(u) itself."""
    w, l = _random_data(rng, len(small_space), 25)
    visited, inv = np.unique(np.concatenate([w, l]), return_inverse=True)
    a, b = inv[: w.size], inv[w.size :]
    K = small_kernel.cross(small_space, visited, rows=visited)
    L = np.linalg.cholesky(K)
    sigma = np.full(w.size, 0.02)
    lik = Probit(sigma)

    def objective(u: np.ndarray) -> float:
        f = L @ u
        return float(0.5 * u @ u) - float(np.sum(lik.terms(f[a] - f[b])[0]))

    u = rng.normal(size=visited.size)
    f = L @ u
    _, g, c = lik.terms(f[a] - f[b])
    grad = u - L.T @ (np.bincount(a, g, visited.size) - np.bincount(b, g, visited.size))
    H = np.sqrt(c)[:, None] * (L[a] - L[b])
    hess = np.eye(visited.size) + H.T @ H
    h = 1e-6
    fd_grad = np.array(
        [(objective(u + h * e) - objective(u - h * e)) / (2 * h) for e in np.eye(visited.size)]
    )
    assert np.allclose(grad, fd_grad, rtol=1e-6, atol=1e-6)

    def grad_at(v: np.ndarray) -> np.ndarray:
        fv = L @ v
        gv = lik.terms(fv[a] - fv[b])[1]
        return v - L.T @ (np.bincount(a, gv, visited.size) - np.bincount(b, gv, visited.size))

    fd_hess = np.stack(
        [(grad_at(u + h * e) - grad_at(u - h * e)) / (2 * h) for e in np.eye(visited.size)]
    )
    assert np.allclose(hess, fd_hess, rtol=1e-5, atol=1e-5)


def test_warm_start_reaches_the_same_mode(
    small_space: Space, small_kernel: SquaredExponential, rng: np.random.Generator
) -> None:
    gp = PreferenceGP(small_space, small_kernel, 0.02)
    w, l = _random_data(rng, len(small_space), 30)
    first = gp.posterior(w[:20], l[:20])
    cold = gp.posterior(w, l)
    warm = gp.posterior(w, l, init=first)
    assert np.allclose(cold.mean, warm.mean, rtol=1e-10, atol=1e-14)
    assert warm.fit is not None and cold.fit is not None
    assert warm.fit.iterations <= cold.fit.iterations


def test_non_convergence_raises_instead_of_returning_the_prior(
    small_space: Space, small_kernel: SquaredExponential, rng: np.random.Generator
) -> None:
    w, l = _random_data(rng, len(small_space), 30)
    visited, inv = np.unique(np.concatenate([w, l]), return_inverse=True)
    K = small_kernel.cross(small_space, visited, rows=visited)
    with pytest.raises(ConvergenceError, match="did not converge in 1 Newton"):
        fit_laplace(
            K, visited, inv[: w.size], inv[w.size :], Probit(np.full(w.size, 0.02)), max_iter=1
        )


_pairs = st.lists(st.tuples(st.integers(0, 34), st.integers(0, 34)), min_size=1, max_size=80)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    pairs=_pairs,
    kind=st.sampled_from(["as-is", "contradictory", "duplicated", "one-sided"]),
    noise=st.sampled_from([1e-4, 0.01, 1.0]),
)
def test_hard_preference_sets_give_finite_converged_posteriors(
    pairs: list[tuple[int, int]], kind: str, noise: float
) -> None:
    space = Space([Feature.linspace("a", 0, 1, 7), Feature.linspace("b", 0, 1, 5)])
    kernel = SquaredExponential((0.2, 0.3), 1e-4, 1e-6)
    w = np.array([p[0] for p in pairs])
    l = np.array([p[1] for p in pairs])
    keep = w != l  # a preference of a gait over itself is refused (test_self_preferences.py)
    w, l = w[keep], l[keep]
    if kind == "contradictory":
        w, l = np.concatenate([w, l]), np.concatenate([l, w])
    elif kind == "duplicated":
        w, l = np.repeat(w, 25), np.repeat(l, 25)
    elif kind == "one-sided":  # one action beats everything, extremely confidently
        l = np.where(w == 0, 1, w)
        w = np.zeros_like(l)
    post = PreferenceGP(space, kernel, noise).posterior(w, l)
    assert np.all(np.isfinite(post.mean)) and np.all(np.isfinite(post.variance))
    assert np.all(post.variance >= 0)
    if post.fit is not None:
        assert post.fit.gradient_norm <= 1e-6 * max(1.0, np.max(np.abs(post.fit.whitened_mode)))
    if kind == "one-sided" and np.any(w != l):
        assert post.argmax == 0


def test_bad_inputs_are_rejected(small_space: Space, small_kernel: SquaredExponential) -> None:
    gp = PreferenceGP(small_space, small_kernel, 0.02)
    with pytest.raises(IndexError, match="off the grid"):
        gp.posterior([0, 35], [1, 2])
    with pytest.raises(ValueError, match="2 winners but 1 losers"):
        gp.posterior([0, 3], [1])
    with pytest.raises(TypeError, match="integer"):
        gp.posterior([0.5], [1])
    with pytest.raises(ValueError, match="noise"):
        gp.posterior([0], [1], noise=[-1.0])
    with pytest.raises(ValueError, match="noise"):
        PreferenceGP(small_space, small_kernel, 0.0)
    with pytest.raises(ValueError, match="lengthscales"):
        PreferenceGP(small_space, SquaredExponential((0.1, 0.1, 0.1), 1.0), 0.1)
