"""Pairwise likelihoods as functions of a utility difference, stable in the tails.

Chu & Ghahramani (2005), eq. (3), as used by the paper: a preference ``w > l`` has probability
``Phi(z)`` with ``z = (f_w - f_l) / (sqrt(2) sigma)``.  Every pairwise likelihood here is written as
a function of the difference ``d_k = f_a - f_b`` of one observation ``k`` and returns three arrays:

- ``log p_k(d_k)``;
- ``g_k = d log p_k / d d_k`` (for the probit: ``r_k / (sqrt(2) sigma_k)``, ``r = phi(z)/Phi(z)``);
- ``c_k = -d^2 log p_k / d d_k^2 >= 0`` (for the probit: ``(r_k^2 + z_k r_k) / (2 sigma_k^2)``).

With the signed incidence matrix ``G`` (row ``k`` is ``e_a - e_b``) the log-likelihood's gradient
over utilities is ``G^T g`` and its negative Hessian ``Lambda = G^T diag(c) G`` (``docs/model.md``,
"Likelihood" for ``g`` and ``c``, "Laplace mode" for the gradient and ``H = diag(sqrt(c)) G L``,
with ``H^T H = L^T Lambda L``).  ``log Phi`` uses ``scipy.special.log_ndtr``
and ``r`` the scaled complementary error function, so neither underflows: the authors' code
computed ``log(norm.cdf(z))``, which reaches ``-inf`` and made their fit fall back to the prior.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray
from scipy.special import erf, erfcx, log_ndtr

from gaitpref.space import FloatArray


def check_scales(values: object, name: str, *, zero: bool = False) -> None:
    """Raise ``ValueError`` naming ``name`` unless ``values`` holds real numbers (not bools),
    every one finite and > 0 (``>= 0`` with ``zero``).  Checked once where a likelihood is
    built, never in the Newton iterations that evaluate it."""
    try:
        arr = np.asarray(values)
    except (TypeError, ValueError):
        arr = np.asarray(None)
    bound = ">= 0" if zero else "positive"
    if arr.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be finite numbers {bound}, got {values!r}")
    good = np.isfinite(arr) & ((arr >= 0) if zero else (arr > 0))
    if not np.all(good):
        if arr.ndim == 0:
            raise ValueError(f"{name} must be finite and {bound}, got {values!r}")
        k = int(np.flatnonzero(~good.ravel())[0])
        bad = float(arr.ravel()[k])
        raise ValueError(f"{name} must be finite and {bound}, got {bad!r} at entry {k}")


_SQRT2 = float(np.sqrt(2.0))
_SQRT_2_OVER_PI = float(np.sqrt(2.0 / np.pi))


class PairLikelihood(Protocol):
    """A likelihood over observation differences ``d`` (one entry per observation)."""

    def terms(self, diff: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(log p, d log p / d d, -d^2 log p / d d^2)`` per observation."""
        ...


class ActionLikelihood(Protocol):
    """A likelihood over single utilities ``f_s`` (one entry per observation of one action).

    The second shape of observation the Laplace fit takes (``laplace.py``); ordinal ratings are
    one.  Same contract as :class:`PairLikelihood`: log-concave in ``f_s``, so ``c >= 0``.
    """

    def terms(self, values: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(log p, d log p / d f, -d^2 log p / d f^2)`` per observation."""
        ...


@dataclass(frozen=True)
class StackedActionLikelihood:
    """Several single-action likelihoods over consecutive blocks of observations, as one."""

    parts: tuple[tuple[int, ActionLikelihood], ...]  # (number of observations, likelihood)

    def terms(self, values: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        out: list[tuple[FloatArray, FloatArray, FloatArray]] = []
        start = 0
        for size, part in self.parts:
            out.append(part.terms(values[start : start + size]))
            start += size
        if start != values.shape[0]:
            raise ValueError(f"{values.shape[0]} values for {start} single-action observations")
        logp, g, c = (np.concatenate([t[k] for t in out]) for k in range(3))
        return logp, g, c


def mills_ratio(z: FloatArray) -> FloatArray:
    """``phi(z) / Phi(z)`` for any real ``z``, without underflow (``-> -z`` as ``z -> -inf``)."""
    with np.errstate(over="ignore"):
        out: FloatArray = _SQRT_2_OVER_PI / erfcx(-z / _SQRT2)
    return out


@dataclass(frozen=True)
class Probit:
    """``P(a > b) = Phi((f_a - f_b) / (sqrt(2) sigma_k))``, one noise per observation."""

    sigma: FloatArray

    def __post_init__(self) -> None:
        check_scales(self.sigma, "the probit noise sigma")

    def terms(self, diff: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        scale = _SQRT2 * self.sigma
        z = diff / scale
        r = mills_ratio(z)
        logp = log_ndtr(z)
        grad = r / scale
        # r (r + z) lies in (0, 1); clip the rounding of r + z for z -> -inf.
        curv = np.clip(r * (r + z), 0.0, 1.0) / scale**2
        return logp, grad, curv

    def third(self, diff: FloatArray) -> FloatArray:
        """``d c / d d = -d^3 log p / d d^3`` (the Laplace evidence's gradient needs it)."""
        scale = _SQRT2 * self.sigma
        z = diff / scale
        r = mills_ratio(z)
        out: FloatArray = -r * ((r + z) * (2.0 * r + z) - 1.0) / scale**3
        return out


def interval_ratios(
    lo: FloatArray, hi: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """For ``lo < hi`` with ``lo + hi <= 0``: ``log Z``, ``phi(hi) / Z``, ``phi(lo) / Z`` and
    ``hi + phi(hi) / Z``, where ``Z = Phi(hi) - Phi(lo)``, accurate far into the left tail."""
    log_z, rho_hi, rho_lo, u_hi = (np.empty_like(lo) for _ in range(4))
    left = hi <= 0.0
    # left tail: Z = Phi(hi) (1 - q), q = Phi(lo) / Phi(hi), through Mills ratios (no underflow)
    lh, ll = hi[left], lo[left]
    log_hi = log_ndtr(lh)
    log_q = log_ndtr(ll) - log_hi
    one_minus_q = -np.expm1(log_q)
    r_hi = mills_ratio(lh)
    log_z[left] = log_hi + np.log(one_minus_q)
    rho_hi[left] = r_hi / one_minus_q
    rho_lo[left] = mills_ratio(ll) * np.exp(log_q) / one_minus_q
    u_hi[left] = (lh + r_hi) + r_hi * np.exp(log_q) / one_minus_q
    # lo < 0 < hi: erf(hi) and -erf(lo) add without cancellation
    mid = ~left
    mh, ml = hi[mid], lo[mid]
    log_z[mid] = np.log(0.5 * (erf(mh / _SQRT2) - erf(ml / _SQRT2)))
    rho_hi[mid] = np.exp(-0.5 * mh**2 - _LOG_SQRT_2PI - log_z[mid])
    rho_lo[mid] = np.exp(-0.5 * ml**2 - _LOG_SQRT_2PI - log_z[mid])
    u_hi[mid] = mh + rho_hi[mid]
    return log_z, rho_hi, rho_lo, u_hi


_LOG_SQRT_2PI = 0.5 * float(np.log(2.0 * np.pi))


@dataclass(frozen=True)
class OrderedProbit:
    """Preferences and "no preference" answers with an indifference band (ordered probit).

    The subject perceives ``d + e``, ``e ~ N(0, 2 sigma^2)``, and says "no preference" when
    ``|d + e| < band``.  With ``s = sqrt(2) sigma``, an observation of ``d = f_a - f_b`` has

    - ``P(a preferred) = Phi((d - band) / s)``            (``tie`` False);
    - ``P(no preference) = Phi((d + band) / s) - Phi((d - band) / s)``  (``tie`` True).

    ``band = 0`` gives the paper's :class:`Probit` exactly (coactive suggestions use it).  Both
    forms are log-concave in ``d``, and ``c = -d^2 log p / d d^2`` lies in ``[0, 1 / s^2]`` (one
    minus the variance of a truncated standard normal), so the Laplace problem stays convex.
    Besides :meth:`terms`, the Laplace evidence's gradient uses :meth:`third` (``d c / d d``)
    and :meth:`band_terms` (derivatives with respect to ``log band``).
    """

    sigma: FloatArray
    band: FloatArray
    tie: NDArray[np.bool_]

    def __post_init__(self) -> None:
        if not (self.sigma.shape == self.band.shape == self.tie.shape):
            raise ValueError("sigma, band and tie must have one entry per observation")
        check_scales(self.sigma, "the probit noise sigma")
        check_scales(self.band, "the indifference band", zero=True)
        if np.any(self.band < 0) or np.any(self.tie & (self.band <= 0)):
            raise ValueError("bands must be >= 0, and > 0 for 'no preference' observations")

    def _derivatives(self, diff: FloatArray, band_terms: bool) -> tuple[FloatArray, ...]:
        """``(h, h1, h2, h3)`` in units of ``s`` and, with ``band_terms``, ``d(h, h1, h2)/de``."""
        scale = _SQRT2 * self.sigma
        x, e = diff / scale, self.band / scale
        n = x.size
        h, h1, h2, h3 = (np.zeros(n) for _ in range(4))
        dh, dh1, dh2 = (np.zeros(n) for _ in range(3))
        pref = ~self.tie
        a = x[pref] - e[pref]
        r = mills_ratio(a)
        h[pref] = log_ndtr(a)
        h1[pref] = r
        h2[pref] = -np.clip(r * (r + a), 0.0, 1.0)
        h3[pref] = r * ((r + a) * (2.0 * r + a) - 1.0)
        if band_terms:
            dh[pref], dh1[pref], dh2[pref] = -r, -h2[pref], -h3[pref]
        if np.any(self.tie):
            # symmetric in x: work at -|x| and flip the odd derivatives back
            sign = np.where(x[self.tie] >= 0.0, -1.0, 1.0)
            xm, et = -np.abs(x[self.tie]), e[self.tie]
            lo, hi = xm - et, xm + et
            log_z, rho_hi, rho_lo, u_hi = interval_ratios(lo, hi)
            t1 = rho_hi - rho_lo
            # -d2: one minus a truncated normal's variance, in [0, 1]
            t2 = np.clip(-rho_hi * u_hi + rho_lo * (lo + 2.0 * rho_hi - rho_lo), -1.0, 0.0)
            d_hi, d_lo = -rho_hi * (u_hi - rho_lo), -rho_lo * (lo + t1)
            t3 = -rho_hi - hi * d_hi + rho_lo + lo * d_lo - 2.0 * t1 * t2
            h[self.tie], h1[self.tie], h2[self.tie], h3[self.tie] = log_z, sign * t1, t2, sign * t3
            if band_terms:
                s_sum = rho_hi + rho_lo
                e_hi = -rho_hi * (u_hi + rho_lo)
                e_lo = lo * rho_lo - rho_lo * s_sum
                e1 = e_hi - e_lo
                e2 = -rho_hi - hi * e_hi - rho_lo + lo * e_lo - 2.0 * t1 * e1
                dh[self.tie], dh1[self.tie], dh2[self.tie] = s_sum, sign * e1, e2
        return h, h1, h2, h3, dh, dh1, dh2

    def terms(self, diff: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        scale = _SQRT2 * self.sigma
        h, h1, h2, *_ = self._derivatives(diff, band_terms=False)
        return h, h1 / scale, -h2 / scale**2

    def third(self, diff: FloatArray) -> FloatArray:
        """``d c / d d = -d^3 log p / d d^3`` per observation."""
        scale = _SQRT2 * self.sigma
        h3 = self._derivatives(diff, band_terms=False)[3]
        out: FloatArray = -h3 / scale**3
        return out

    def band_terms(self, diff: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Derivatives of ``(log p, g, c)`` (as :meth:`terms`) with respect to ``log band``."""
        scale = _SQRT2 * self.sigma
        e = self.band / scale
        _, _, _, _, dh, dh1, dh2 = self._derivatives(diff, band_terms=True)
        return e * dh, e * dh1 / scale, -e * dh2 / scale**2
