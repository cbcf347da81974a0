"""The Laplace posterior over all actions: mean, variance, covariance and joint samples.

From a :class:`~gaitpref.model.laplace.LaplaceMode` on the visited set ``V`` (``K_VV = L L^T``,
``I + L^T Lambda L = R R^T``), with ``P = L^-1 K_{V,:}``:

- mean        ``mu = K_{:,V} K_VV^-1 f_hat_V``;
- covariance  ``Sigma = K - P^T P + (R^-1 P)^T (R^-1 P)``  (GPML eq. 3.24 in the visited subspace:
  the prior's conditional given ``f_V`` plus ``Sigma_VV = L (R R^T)^-1 L^T`` carried through it);
- samples (pathwise conditioning, Wilson et al. 2020): with a prior sample ``f0 ~ N(0, K)`` and
  ``w = L^-1 f0_V``,  ``f = mu + f0 + K_{:,V} L^-T (R^-T w - w)``, an exact draw from
  ``N(mu, Sigma)`` that costs ``O(A m)`` once ``f0`` is drawn.

Prior samples come from the kernel's Kronecker factors (``design/algorithm.md``, "Joint samples"):
``f0 = s (S_1 (x) ... (x) S_d) z + sqrt(jitter) z'`` with ``S_f S_f^T = K_f`` from the eigen-
decomposition of each ``n_f x n_f`` factor, applied axis by axis in ``O(A sum n_f)``.

Notation: ``A`` actions, ``m`` visited, ``size`` samples; samples are ``size x A``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.linalg import solve_triangular

from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.laplace import LaplaceMode
from gaitpref.space import FloatArray, IntArray, Space


class KroneckerPriorSampler:
    """Joint samples of ``N(0, K)`` over the whole grid through per-feature square roots."""

    def __init__(self, space: Space, kernel: SquaredExponential) -> None:
        self.shape = space.shape
        self.size = len(space)
        self.scale = float(np.sqrt(kernel.variance))
        self.jitter_scale = float(np.sqrt(kernel.jitter))
        self.roots: list[FloatArray] = []
        for factor in kernel.factors(space):
            eigval, eigvec = np.linalg.eigh(factor)
            self.roots.append(eigvec * np.sqrt(np.clip(eigval, 0.0, None)))

    def sample(self, rng: np.random.Generator, size: int) -> FloatArray:
        """``size x A`` joint prior samples."""
        z = rng.standard_normal((size, *self.shape))
        x = z
        for axis, root in enumerate(self.roots, start=1):
            x = np.moveaxis(np.tensordot(root, x, axes=([1], [axis])), 0, axis)
        out = self.scale * x.reshape(size, self.size)
        if self.jitter_scale:
            out += self.jitter_scale * rng.standard_normal((size, self.size))
        return out


def _readonly(a: FloatArray) -> FloatArray:
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Posterior:
    """Immutable Laplace posterior ``N(mean, Sigma)`` over every action of ``space``.

    ``fit`` is None for the prior (no data).  ``mean`` and ``variance`` are computed on first use
    and cached; nothing ``A x A`` is built unless :meth:`covariance` is called.
    """

    space: Space
    kernel: SquaredExponential
    fit: LaplaceMode | None
    prior_sampler: KroneckerPriorSampler

    @property
    def visited(self) -> IntArray:
        return self.fit.visited if self.fit is not None else np.zeros(0, dtype=np.intp)

    @cached_property
    def cross(self) -> FloatArray:
        """``K_{:,V}``, ``A x m``."""
        return _readonly(self.kernel.cross(self.space, self.visited))

    @cached_property
    def _projected(self) -> tuple[FloatArray, FloatArray]:
        """``P = L^-1 K_{V,:}`` and ``R^-1 P`` (both ``m x A``)."""
        assert self.fit is not None
        P = solve_triangular(self.fit.chol_prior, self.cross.T, lower=True, check_finite=False)
        Q = solve_triangular(self.fit.chol_hessian, P, lower=True, check_finite=False)
        return P, Q

    @cached_property
    def mean(self) -> FloatArray:
        """Posterior mean utility of every action (length ``A``)."""
        if self.fit is None:
            return _readonly(np.zeros(len(self.space)))
        return _readonly(self.cross @ self.fit.alpha)

    @cached_property
    def variance(self) -> FloatArray:
        """Posterior marginal variance of every action (length ``A``)."""
        prior = self.kernel.diagonal(self.space)
        if self.fit is None:
            return _readonly(prior)
        P, Q = self._projected
        var = prior - np.einsum("ij,ij->j", P, P) + np.einsum("ij,ij->j", Q, Q)
        return _readonly(np.maximum(var, 0.0))

    @property
    def std(self) -> FloatArray:
        return np.sqrt(self.variance)

    def covariance(self) -> FloatArray:
        """The dense ``A x A`` posterior covariance (small grids: ``O(A^2 m)`` time)."""
        K = self.kernel.dense(self.space)
        if self.fit is None:
            return K
        P, Q = self._projected
        return K - P.T @ P + Q.T @ Q

    def sample(self, rng: np.random.Generator, size: int = 1) -> FloatArray:
        """``size x A`` joint samples of the utilities over every action."""
        if size < 0:
            raise ValueError(f"size must be >= 0, got {size}")
        f0 = self.prior_sampler.sample(rng, size)
        if self.fit is None:
            return f0
        L, R = self.fit.chol_prior, self.fit.chol_hessian
        w = solve_triangular(L, f0[:, self.visited].T, lower=True, check_finite=False)
        v = solve_triangular(R, w, lower=True, trans="T", check_finite=False) - w
        beta = solve_triangular(L, v, lower=True, trans="T", check_finite=False)
        out: FloatArray = f0 + self.mean + (self.cross @ beta).T
        return out

    def argmax_samples(self, rng: np.random.Generator, size: int) -> IntArray:
        """The argmax of each of ``size`` joint samples, exact ties broken uniformly at random."""
        samples = self.sample(rng, size)
        return np.array([random_argmax(s, rng) for s in samples], dtype=np.intp)

    @property
    def argmax(self) -> int:
        """The action with the highest posterior mean (lowest index among exact ties)."""
        return int(np.argmax(self.mean))

    @property
    def log_evidence(self) -> float:
        """Laplace approximation of the data's log marginal likelihood (0 with no data)."""
        return self.fit.log_evidence if self.fit is not None else 0.0


def random_argmax(values: FloatArray, rng: np.random.Generator) -> int:
    """Index of the maximum of ``values``, exact ties broken uniformly at random with ``rng``."""
    best = np.flatnonzero(values == np.max(values))
    if best.size == 1:
        return int(best[0])
    return int(rng.choice(best))
