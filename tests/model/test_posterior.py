from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import chi2

from gaitpref import Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.model.posterior import KroneckerPriorSampler, random_argmax


def test_kronecker_prior_factor_reproduces_the_dense_prior(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    sampler = KroneckerPriorSampler(small_space, small_kernel)
    root = np.kron(sampler.roots[0], sampler.roots[1])
    implied = small_kernel.variance * root @ root.T + small_kernel.jitter * np.eye(35)
    assert np.allclose(implied, small_kernel.dense(small_space), rtol=0, atol=1e-12)


def _whitened(samples: np.ndarray, mean: np.ndarray, cov: np.ndarray) -> np.ndarray:
    L = np.linalg.cholesky(cov)
    return np.linalg.solve(L, (samples - mean).T).T


def test_joint_samples_follow_the_posterior(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    """Whitened by the dense posterior's Cholesky factor, samples are N(0, I).

    Per-coordinate mean ~ N(0, 1/n) and covariance entries ~ N(delta, (1 + delta)/n): each
    checked at 5 sigma (false alarm < 1e-3 over all entries; fixed seed, so reproducible).
    """
    rng = np.random.default_rng(7)
    w = rng.integers(0, 35, 40)
    l = (w + rng.integers(1, 35, 40)) % 35
    post = PreferenceGP(small_space, small_kernel, 0.02).posterior(w, l)
    n = 20000
    x = _whitened(post.sample(np.random.default_rng(1), n), post.mean, post.covariance())
    assert np.all(np.abs(x.mean(axis=0)) < 5 / np.sqrt(n))
    cov = np.cov(x.T)
    allowed = 5 * np.sqrt((1 + np.eye(35)) / n)
    assert np.all(np.abs(cov - np.eye(35)) < allowed)
    # squared norms are chi^2 with A degrees of freedom
    assert np.mean(np.sum(x**2, axis=1)) == pytest.approx(
        chi2(35).mean(), rel=5 * np.sqrt(70 / n) / 35
    )


def test_samples_are_reproducible_from_the_generator(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = PreferenceGP(small_space, small_kernel, 0.02).posterior([0, 3, 9], [4, 4, 12])
    a = post.sample(np.random.default_rng(3), 4)
    b = post.sample(np.random.default_rng(3), 4)
    assert a.shape == (4, 35) and np.array_equal(a, b)


def test_prior_posterior(small_space: Space, small_kernel: SquaredExponential) -> None:
    prior = PreferenceGP(small_space, small_kernel, 0.02).prior()
    assert np.all(prior.mean == 0)
    assert np.allclose(prior.variance, small_kernel.variance + small_kernel.jitter)
    assert np.allclose(prior.covariance(), small_kernel.dense(small_space))
    assert prior.log_evidence == 0.0


def test_posterior_arrays_are_read_only(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = PreferenceGP(small_space, small_kernel, 0.02).posterior([0], [1])
    with pytest.raises(ValueError, match="read-only"):
        post.mean[0] = 1.0


def test_random_argmax_breaks_exact_ties_uniformly() -> None:
    values = np.array([0.0, 2.0, 1.0, 2.0, 2.0])
    rng = np.random.default_rng(0)
    picks = np.array([random_argmax(values, rng) for _ in range(3000)])
    counts = np.bincount(picks, minlength=5)
    assert counts[0] == counts[2] == 0
    assert np.all(np.abs(counts[[1, 3, 4]] - 1000) < 5 * np.sqrt(3000 * (1 / 3) * (2 / 3)))


def test_variance_many_is_the_dense_posterior_variance(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    """More actions than visited ones: the quadratic-form path, against the dense posterior."""
    rng = np.random.default_rng(11)
    w, l = rng.integers(0, 35, 6), rng.integers(0, 35, 6)
    keep = w != l
    post = PreferenceGP(small_space, small_kernel, 0.02).posterior(w[keep], l[keep])
    assert post.visited.size < 30  # the quadratic-form path, not variance_at's
    idx = np.concatenate([np.arange(35), [3, 3, 17]]).astype(np.intp)
    dense = np.diag(post.covariance())[idx]
    assert np.allclose(post.variance_many(idx), dense, rtol=0, atol=1e-12)
    assert np.allclose(post.variance_many(idx[:4]), dense[:4], rtol=0, atol=1e-12)
    assert not np.allclose(dense, np.diag(small_kernel.dense(small_space))[idx])  # data moved it


def test_variance_many_agrees_with_the_blockwise_variance_on_a_large_grid() -> None:
    space = Space([Feature.linspace("a", 0.0, 1.0, 40), Feature.linspace("b", 0.0, 1.0, 30)])
    kernel = SquaredExponential(0.15, 1.0, 1e-4)
    rng = np.random.default_rng(5)
    w, l = rng.integers(0, 1200, 80), rng.integers(0, 1200, 80)
    keep = w != l
    post = PreferenceGP(space, kernel, 0.05).posterior(w[keep], l[keep])
    every = np.arange(1200, dtype=np.intp)
    assert np.allclose(post.variance_many(every), post.variance, rtol=0, atol=1e-10)
