"""Expected utility of the best option (EUBO) on the finite grid.

Lin et al. (AISTATS 2022) and Astudillo et al. (2023, qEUBO): a query of actions ``Q`` is worth
``E[max_{x in Q} f(x)]`` under the posterior.  For a pair, in closed form (Clark 1961): with
``delta = mu_x - mu_y`` and ``s^2 = var_x + var_y - 2 cov(x, y)``,

    EUBO(x, y) = mu_x Phi(delta / s) + mu_y Phi(-delta / s) + s phi(delta / s)
               = max(mu_x, mu_y) + s psi(-|delta| / s),   psi(t) = phi(t) + t Phi(t),

the second form without cancellation.  ``EUBO(x, y) - mu_y`` is the expected improvement of
``x`` over ``y`` with their correlation taken into account, so against a fixed ``y`` (the
buffered action of ``n = 1, b = 1``) EUBO trades the new action's mean against what a
comparison with ``y`` can reveal.

Covariances come from the Laplace fit on the visited set (``model/posterior.py``):
``cov(., y) = k(., y) - K_{:,V} L^-T (p - R^-T R^-1 p)``, ``p = L^-1 k(V, y)``, ``O(A m)``; the
covariance among ``c`` candidates costs ``O(c m^2)``.

Notation: ``A`` actions, ``m`` visited, ``c`` candidates.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import ndtr

from gaitpref.model.posterior import Posterior
from gaitpref.space import FloatArray, IntArray
from gaitpref.strategies.base import MAX_CANDIDATES

_INV_SQRT_2PI = 1.0 / float(np.sqrt(2.0 * np.pi))
_ROW_BLOCK = 8192


def eubo_pair(
    mu_x: ArrayLike, mu_y: ArrayLike, var_x: ArrayLike, var_y: ArrayLike, cov_xy: ArrayLike
) -> FloatArray:
    """``E[max(f_x, f_y)]`` for jointly Gaussian ``f_x, f_y`` (broadcasting)."""
    mx, my = np.asarray(mu_x, dtype=np.float64), np.asarray(mu_y, dtype=np.float64)
    s2 = np.asarray(var_x) + np.asarray(var_y) - 2.0 * np.asarray(cov_xy)
    s = np.sqrt(np.maximum(s2, 0.0))
    t = -np.abs(mx - my) / np.where(s > 0, s, 1.0)
    psi = _INV_SQRT_2PI * np.exp(-0.5 * t**2) + t * ndtr(t)
    out: FloatArray = np.maximum(mx, my) + np.where(s > 0, s * psi, 0.0)
    return out


def covariance_with(posterior: Posterior, action: int) -> FloatArray:
    """``cov(f_x, f_action)`` for every action ``x`` (length ``A``)."""
    space = posterior.space
    col = np.array([space.check_index(action)], dtype=np.intp)  # -1 wrapped, 2.5 truncated
    out = posterior.kernel_column(int(col[0]))
    if posterior.fit is None:
        return out
    w = posterior.visited_solve(posterior.visited_cross(col).T)[:, 0]
    for start in range(0, len(space), _ROW_BLOCK):
        rows = np.arange(start, min(start + _ROW_BLOCK, len(space)), dtype=np.intp)
        out[rows] -= posterior.visited_cross(rows) @ w
    return out


def covariance_among(posterior: Posterior, actions: IntArray) -> FloatArray:
    """The ``c x c`` posterior covariance of ``actions`` (at most :data:`MAX_CANDIDATES`)."""
    space, kernel = posterior.space, posterior.kernel
    actions = space.check_indices(actions, "candidates")
    if actions.size > MAX_CANDIDATES:  # c x c numbers: 10**6 candidates asked for 8 TB
        raise ValueError(
            f"at most {MAX_CANDIDATES} candidates are compared in pairs, got {actions.size}"
        )
    out: FloatArray = kernel.cross(space, actions, rows=actions)
    if posterior.fit is None:
        return out
    k_vc = posterior.visited_cross(actions).T
    out = out - k_vc.T @ posterior.visited_solve(k_vc)
    return 0.5 * (out + out.T)


def eubo_against(posterior: Posterior, reference: int) -> FloatArray:
    """``EUBO(x, reference)`` for every action ``x`` (length ``A``)."""
    reference = posterior.space.check_index(reference)  # -1 read the last gait before
    mu, var = np.asarray(posterior.mean), np.asarray(posterior.variance)
    cov = covariance_with(posterior, reference)
    return eubo_pair(mu, mu[reference], var, var[reference], cov)


def best_pair(posterior: Posterior, candidates: IntArray) -> tuple[int, int, float]:
    """The pair of distinct ``candidates`` with the highest EUBO (first maximum)."""
    candidates = posterior.space.check_indices(candidates, "candidates")
    if candidates.shape[0] < 2:
        raise ValueError("best_pair needs at least two candidates")
    cov = covariance_among(posterior, candidates)
    mu = np.asarray(posterior.mean)[candidates]
    var = np.diag(cov)
    values = eubo_pair(mu[:, None], mu[None, :], var[:, None], var[None, :], cov)
    values[np.tril_indices(candidates.shape[0])] = -np.inf
    i, j = np.unravel_index(int(np.argmax(values)), values.shape)
    return int(candidates[i]), int(candidates[j]), float(values[i, j])
