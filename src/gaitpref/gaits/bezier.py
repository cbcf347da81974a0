"""Bezier polynomials for virtual constraints (Westervelt et al. 2007, Section 6.2.1).

``B(alpha, tau) = sum_k alpha_k C(M, k) tau^k (1 - tau)^(M - k)`` on ``tau in [0, 1]``, with
``B(0) = alpha_0``, ``B(1) = alpha_M``, ``B'(0) = M (alpha_1 - alpha_0)`` and
``B'(1) = M (alpha_M - alpha_{M-1})``; the derivatives are Bezier polynomials of degree ``M - 1``
and ``M - 2`` over the differences of the coefficients.

Notation: ``M`` the degree, ``alpha`` has ``M + 1`` coefficients, ``tau`` is ``(N,)``; the basis
matrices are ``N x (M + 1)`` so that ``B = Phi @ alpha``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import comb

from gaitpref.space import FloatArray


def bernstein(degree: int, tau: ArrayLike) -> FloatArray:
    """Bernstein basis ``C(M, k) tau^k (1 - tau)^(M - k)``, ``N x (M + 1)``."""
    t = np.asarray(tau, dtype=np.float64)[..., None]
    k = np.arange(degree + 1)
    return np.asarray(comb(degree, k) * t**k * (1.0 - t) ** (degree - k))


def basis(degree: int, tau: ArrayLike, order: int = 0) -> FloatArray:
    """Matrix ``Phi`` with ``d^order B / d tau^order = Phi @ alpha``, ``N x (M + 1)``."""
    if degree < 2:
        raise ValueError(f"Bezier degree must be at least 2, got {degree}")
    if order not in (0, 1, 2):
        raise ValueError(f"derivative order must be 0, 1 or 2, got {order}")
    # forward differences: alpha -> Delta^order alpha, a (M + 1 - order) x (M + 1) matrix
    diff = np.eye(degree + 1)
    scale = 1.0
    for j in range(order):
        diff = diff[1:] - diff[:-1]
        scale *= degree - j
    return np.asarray(scale * bernstein(degree - order, tau) @ diff)


def evaluate(alpha: ArrayLike, tau: ArrayLike, order: int = 0) -> FloatArray:
    """``d^order B / d tau^order`` at ``tau`` for the coefficients ``alpha``."""
    a = np.asarray(alpha, dtype=np.float64)
    return basis(a.shape[-1] - 1, tau, order) @ a
