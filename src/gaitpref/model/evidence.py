"""The Laplace approximation's log evidence and its gradient in the hyperparameters.

GPML (Rasmussen & Williams 2006) Section 5.5.1, eq. (5.20)-(5.24), written for a pairwise
likelihood and worked in the visited subspace ``V`` (``laplace.py``).  With the mode ``f`` on
``V`` (``f = K a``, ``a = G^T g``), ``W = G^T diag(c) G`` and ``Sigma = (K^-1 + W)^-1``:

    log q(D | theta) = sum_k log p_k(d_k) - 1/2 f^T K^-1 f - 1/2 log |I + K W|            (5.20)

Its derivative in a kernel parameter ``theta_j`` has an explicit part and an implicit one
through the mode's dependence on ``theta`` (the mode's own first-order terms vanish):

    explicit  1/2 a^T dK a - 1/2 tr((W - W Sigma W) dK)                                   (5.22)
    implicit  s2^T (I - Sigma W) dK a,     s2 = -1/2 G^T (c' * diag(G Sigma G^T))         (5.23-24)

(``c' = dc/dd``, the likelihood's third derivative; ``(I + K W)^-1 = I - Sigma W`` and
``W (I + K W)^-1 = W - W Sigma W`` need no inverse of the singular ``W``).  For the likelihood's
own parameter, ``log band`` of the ordered probit, the explicit part is
``sum_k dlog p_k - 1/2 sum_k dc_k (G Sigma G^T)_kk`` and the implicit one
``s2^T (I - Sigma W) K G^T dg``.  ``Sigma = S^T S`` with ``S = R^-1 L^T`` from the Laplace fit.

The parameters are ``theta = (log l_1, ..., log l_d, log s^2, log band)``: lengthscales, the
signal variance and the indifference band.  The jitter scales with ``s^2`` (its ratio to the
signal variance is the config's), and the probit noise ``sigma`` is held fixed: scaling ``f``,
``s``, ``sigma`` and the band by one factor leaves every probability unchanged, so only ``s /
sigma`` and ``band / sigma`` are identifiable, and fixing ``sigma`` removes the redundancy.

Notation: ``N`` observations, ``m`` visited actions, ``d`` features; ``K`` is ``K_VV``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import solve_triangular

from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.laplace import LaplaceMode, fit_laplace
from gaitpref.model.likelihood import OrderedProbit
from gaitpref.space import FloatArray, IntArray, Space


@dataclass(frozen=True)
class PairData:
    """Observations of ``d_k = f[first_k] - f[second_k]`` (grid indices).

    ``tie[k]``: a "no preference" answer; otherwise ``first`` was preferred.  ``banded[k]``:
    the indifference band applies (answers to comparisons); coactive suggestions are plain
    probit preferences (no band).
    """

    first: IntArray
    second: IntArray
    sigma: FloatArray
    banded: NDArray[np.bool_]
    tie: NDArray[np.bool_]

    def __post_init__(self) -> None:
        n = self.first.shape[0]
        shapes = {a.shape for a in (self.first, self.second, self.sigma, self.banded, self.tie)}
        if shapes != {(n,)}:
            raise ValueError("first, second, sigma, banded and tie need one entry per observation")
        if np.any(self.tie & ~self.banded):
            raise ValueError("a 'no preference' observation must be banded")

    @property
    def size(self) -> int:
        return int(self.first.shape[0])

    def likelihood(self, band: float) -> OrderedProbit:
        """The ordered probit with ``band`` on the banded observations (0 elsewhere)."""
        return OrderedProbit(self.sigma, np.where(self.banded, band, 0.0), self.tie)


@dataclass(frozen=True)
class Hyperparameters:
    """Kernel lengthscales (feature units), signal variance, jitter, and indifference band."""

    lengthscale: tuple[float, ...]
    variance: float
    jitter: float
    band: float = 0.0

    @classmethod
    def from_kernel(
        cls, kernel: SquaredExponential, ndim: int, band: float = 0.0
    ) -> Hyperparameters:
        return cls(kernel.lengthscales(ndim), kernel.variance, kernel.jitter, float(band))

    def kernel(self) -> SquaredExponential:
        return SquaredExponential(self.lengthscale, self.variance, self.jitter)

    def log_vector(self) -> FloatArray:
        """``(log l_1, ..., log l_d, log s^2, log band)`` (``log band = -inf`` for no band)."""
        with np.errstate(divide="ignore"):
            out: FloatArray = np.log(np.array([*self.lengthscale, self.variance, self.band]))
        return out

    def with_log_vector(self, theta: FloatArray) -> Hyperparameters:
        """New values from a log vector; the jitter keeps its ratio to the signal variance."""
        values = np.exp(np.asarray(theta, dtype=np.float64))
        d = len(self.lengthscale)
        variance = float(values[d])
        return Hyperparameters(
            tuple(float(v) for v in values[:d]),
            variance,
            self.jitter * variance / self.variance,
            float(values[d + 1]),
        )


@dataclass(frozen=True)
class Evidence:
    """Laplace log evidence, its gradient in :meth:`Hyperparameters.log_vector`, the fit."""

    value: float
    gradient: FloatArray  # (d + 2,)
    fit: LaplaceMode


def visited_pairs(data: PairData) -> tuple[IntArray, IntArray, IntArray]:
    """The visited grid actions (sorted) and each observation's pair as indices into them."""
    visited, inverse = np.unique(np.concatenate([data.first, data.second]), return_inverse=True)
    n = data.size
    return visited.astype(np.intp), inverse[:n].astype(np.intp), inverse[n:].astype(np.intp)


def laplace_evidence(
    space: Space, hyper: Hyperparameters, data: PairData, init: FloatArray | None = None
) -> Evidence:
    """Log evidence and gradient at ``hyper``; ``init`` warm-starts the mode on the visited set.

    Raises what :func:`~gaitpref.model.laplace.fit_laplace` raises (``ConvergenceError``,
    ``PriorNotPositiveDefiniteError``).
    """
    if data.size == 0:
        raise ValueError("the evidence needs at least one observation")
    visited, a, b = visited_pairs(data)
    kernel = hyper.kernel()
    K = kernel.cross(space, visited, rows=visited)
    lik = data.likelihood(hyper.band)
    fit = fit_laplace(K, visited, a, b, lik, init)
    m = visited.shape[0]
    f = fit.mode
    diff = f[a] - f[b]
    _, g, c = lik.terms(diff)
    G = np.zeros((data.size, m))
    G[np.arange(data.size), a] += 1.0
    G[np.arange(data.size), b] -= 1.0
    alpha = G.T @ g
    W = G.T @ (c[:, None] * G)
    S = solve_triangular(fit.chol_hessian, fit.chol_prior.T, lower=True, check_finite=False)
    Sigma = S.T @ S
    GS = G @ Sigma
    v = np.einsum("kj,kj->k", GS, G)  # diag(G Sigma G^T)
    s2 = -0.5 * (G.T @ (lik.third(diff) * v))
    q = s2 - W @ (Sigma @ s2)  # (I - W Sigma) s2
    B = 0.5 * np.outer(alpha, alpha) - 0.5 * (W - W @ Sigma @ W) + np.outer(q, alpha)
    grad = np.zeros(space.ndim + 2)
    points = space.points[visited]
    se = K - kernel.jitter * np.eye(m)  # the squared-exponential part
    for j, ell in enumerate(hyper.lengthscale):
        dK = se * ((points[:, j, None] - points[None, :, j]) / ell) ** 2
        grad[j] = float(np.sum(dK * B))
    grad[space.ndim] = float(np.sum(K * B))  # dK / dlog s^2 = K (the jitter scales along)
    if hyper.band > 0 and np.any(data.banded):
        dlogp, dg, dc = lik.band_terms(diff)
        explicit = float(np.sum(dlogp)) - 0.5 * float(np.sum(dc * v))
        grad[space.ndim + 1] = explicit + float(q @ (K @ (G.T @ dg)))
    return Evidence(fit.log_evidence, grad, fit)
