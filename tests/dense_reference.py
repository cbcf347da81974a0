"""An independent dense O(A^3) Laplace preference GP, written for the tests only.

Newton's method over all A utilities with the explicit prior precision (fine for A <= a few
hundred), probit likelihood through scipy.stats.norm, and the posterior covariance as the inverse
of (K^-1 + Lambda) by dense solves.  Nothing here is shared with gaitpref.model.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import norm


def dense_kernel(points: np.ndarray, lengthscales, variance: float, jitter: float) -> np.ndarray:
    diff = (points[:, None, :] - points[None, :, :]) / np.asarray(lengthscales, dtype=float)
    return variance * np.exp(-0.5 * np.sum(diff**2, axis=-1)) + jitter * np.eye(len(points))


def dense_laplace(K, winners, losers, sigma, iters: int = 200):
    """Mode and covariance of the Laplace posterior by dense Newton on all A utilities."""
    A = K.shape[0]
    sigma = np.broadcast_to(np.asarray(sigma, dtype=float), np.shape(winners))
    scale = np.sqrt(2.0) * sigma
    K_inv = np.linalg.solve(K, np.eye(A))
    G = np.zeros((len(winners), A))
    G[np.arange(len(winners)), winners] += 1.0
    G[np.arange(len(winners)), losers] -= 1.0
    f = np.zeros(A)
    for _ in range(iters):
        z = (G @ f) / scale
        ratio = np.exp(norm.logpdf(z) - norm.logcdf(z))
        grad = K_inv @ f - G.T @ (ratio / scale)
        lam = G.T @ (((ratio**2 + z * ratio) / scale**2)[:, None] * G)
        step = np.linalg.solve(K_inv + lam, grad)
        f = f - step
        if np.max(np.abs(step)) < 1e-15 * max(1.0, np.max(np.abs(f))):
            break
    z = (G @ f) / scale
    ratio = np.exp(norm.logpdf(z) - norm.logcdf(z))
    lam = G.T @ (((ratio**2 + z * ratio) / scale**2)[:, None] * G)
    cov = np.linalg.solve(K_inv + lam, np.eye(A))
    return f, 0.5 * (cov + cov.T)
