"""Pairwise likelihoods as functions of a utility difference, stable in the tails.

Chu & Ghahramani (2005), eq. (3), as used by the paper: a preference ``w > l`` has probability
``Phi(z)`` with ``z = (f_w - f_l) / (sqrt(2) sigma)``.  Every pairwise likelihood here is written as
a function of the difference ``d_k = f_a - f_b`` of one observation ``k`` and returns three arrays:

- ``log p_k(d_k)``;
- ``g_k = d log p_k / d d_k`` (for the probit: ``r_k / (sqrt(2) sigma_k)``, ``r = phi(z)/Phi(z)``);
- ``c_k = -d^2 log p_k / d d_k^2 >= 0`` (for the probit: ``(r_k^2 + z_k r_k) / (2 sigma_k^2)``).

With the signed incidence matrix ``G`` (row ``k`` is ``e_a - e_b``) the log-likelihood's gradient
over utilities is ``G^T g`` and its negative Hessian ``Lambda = G^T diag(c) G``
(``design/algorithm.md``, "Laplace approximation").  ``log Phi`` uses ``scipy.special.log_ndtr``
and ``r`` the scaled complementary error function, so neither underflows: the authors' code
computed ``log(norm.cdf(z))``, which reaches ``-inf`` and made their fit fall back to the prior.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from scipy.special import erfcx, log_ndtr

from gaitpref.space import FloatArray

_SQRT2 = float(np.sqrt(2.0))
_SQRT_2_OVER_PI = float(np.sqrt(2.0 / np.pi))


class PairLikelihood(Protocol):
    """A likelihood over observation differences ``d`` (one entry per observation)."""

    def terms(self, diff: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(log p, d log p / d d, -d^2 log p / d d^2)`` per observation."""
        ...


def mills_ratio(z: FloatArray) -> FloatArray:
    """``phi(z) / Phi(z)`` for any real ``z``, without underflow (``-> -z`` as ``z -> -inf``)."""
    with np.errstate(over="ignore"):
        out: FloatArray = _SQRT_2_OVER_PI / erfcx(-z / _SQRT2)
    return out


@dataclass(frozen=True)
class Probit:
    """``P(a > b) = Phi((f_a - f_b) / (sqrt(2) sigma_k))``, one noise per observation."""

    sigma: FloatArray

    def terms(self, diff: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        scale = _SQRT2 * self.sigma
        z = diff / scale
        r = mills_ratio(z)
        logp = log_ndtr(z)
        grad = r / scale
        # r (r + z) lies in (0, 1); clip the rounding of r + z for z -> -inf.
        curv = np.clip(r * (r + z), 0.0, 1.0) / scale**2
        return logp, grad, curv
