"""An independent dense O(A^3) Laplace preference GP, written for the tests only.

Newton's method over all A utilities with the explicit prior precision (fine for A <= a few
hundred), probit likelihood through scipy.stats.norm, and the posterior covariance as the inverse
of (K^-1 + Lambda) by dense solves.  Nothing here is shared with gaitpref.model.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.stats import norm

Array = NDArray[Any]


def dense_kernel(points: Array, lengthscales: ArrayLike, variance: float, jitter: float) -> Array:
    diff = (points[:, None, :] - points[None, :, :]) / np.asarray(lengthscales, dtype=float)
    out: Array = variance * np.exp(-0.5 * np.sum(diff**2, axis=-1)) + jitter * np.eye(len(points))
    return out


def dense_laplace(
    K: Array, winners: ArrayLike, losers: ArrayLike, sigma: ArrayLike, iters: int = 200
) -> tuple[Array, Array]:
    """Mode and covariance of the Laplace posterior by dense Newton on all A utilities."""
    A = K.shape[0]
    win, lose = np.asarray(winners, dtype=np.intp), np.asarray(losers, dtype=np.intp)
    scale = np.sqrt(2.0) * np.broadcast_to(np.asarray(sigma, dtype=float), win.shape)
    K_inv = np.linalg.solve(K, np.eye(A))
    G = np.zeros((len(win), A))
    G[np.arange(len(win)), win] += 1.0
    G[np.arange(len(win)), lose] -= 1.0
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


def _ordered_terms(
    d: Array, sigma: ArrayLike, band: ArrayLike, tie: ArrayLike
) -> tuple[Array, Array, Array]:
    """log p, its first two derivatives in d for the ordered probit, by scipy.stats directly."""
    s = np.sqrt(2.0) * sigma
    hi, lo = (d + band) / s, (d - band) / s
    z_tie = norm.cdf(hi) - norm.cdf(lo)
    dz_tie = (norm.pdf(hi) - norm.pdf(lo)) / s
    d2z_tie = (-hi * norm.pdf(hi) + lo * norm.pdf(lo)) / s**2
    z_pref = norm.cdf(lo)
    dz_pref = norm.pdf(lo) / s
    d2z_pref = -lo * norm.pdf(lo) / s**2
    z = np.where(tie, z_tie, z_pref)
    dz = np.where(tie, dz_tie, dz_pref)
    d2z = np.where(tie, d2z_tie, d2z_pref)
    return np.log(z), dz / z, d2z / z - (dz / z) ** 2


def dense_laplace_ordered(
    K: Array,
    first: ArrayLike,
    second: ArrayLike,
    sigma: ArrayLike,
    band: ArrayLike,
    tie: ArrayLike,
    iters: int = 200,
) -> tuple[Array, Array, float]:
    """Mode, covariance and log evidence for the ordered probit by dense Newton on all A."""
    A = K.shape[0]
    K_inv = np.linalg.solve(K, np.eye(A))
    one, two = np.asarray(first, dtype=np.intp), np.asarray(second, dtype=np.intp)
    G = np.zeros((len(one), A))
    G[np.arange(len(one)), one] += 1.0
    G[np.arange(len(one)), two] -= 1.0
    f = np.zeros(A)
    for _ in range(iters):
        _, g, h = _ordered_terms(G @ f, sigma, band, tie)
        grad = K_inv @ f - G.T @ g
        step = np.linalg.solve(K_inv - G.T @ (h[:, None] * G), grad)
        f = f - step
        if np.max(np.abs(step)) < 1e-15 * max(1.0, np.max(np.abs(f))):
            break
    logp, _, h = _ordered_terms(G @ f, sigma, band, tie)
    W = -G.T @ (h[:, None] * G)
    cov = np.linalg.solve(K_inv + W, np.eye(A))
    _, logdet = np.linalg.slogdet(np.eye(A) + K @ W)
    evidence = np.sum(logp) - 0.5 * f @ K_inv @ f - 0.5 * logdet
    return f, 0.5 * (cov + cov.T), float(evidence)
