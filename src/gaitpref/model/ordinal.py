"""Ordinal ratings of single gaits: the ordered probit on one action's utility.

ROIAL (Li, Tucker et al., ICRA 2021) and POLAR (Tucker et al. 2022): after a trial the subject
rates the gait in one of ``K`` ordered categories (worst first).  With ``K - 1`` increasing
thresholds ``t_1 < ... < t_{K-1}`` (``t_0 = -inf``, ``t_K = +inf``) and a rating noise ``s``,

    P(rating = k | f) = Phi((t_k - f) / s) - Phi((t_{k-1} - f) / s)

(Chu & Ghahramani 2005's ordinal regression likelihood).  With ``lo = (t_{k-1} - f) / s``,
``hi = (t_k - f) / s``, ``Z = Phi(hi) - Phi(lo)`` and ``rho_x = phi(x) / Z``:

- ``d log p / d f = (rho_lo - rho_hi) / s``;
- ``c = -d^2 log p / d f^2 = ((rho_lo - rho_hi)^2 + hi rho_hi - lo rho_lo) / s^2``, one minus the
  variance of a standard normal truncated to ``[lo, hi]``, over ``s^2``: in ``[0, 1 / s^2]``, so
  the likelihood is log-concave and the Laplace fit stays a convex Newton problem.

The Laplace evidence (``evidence.py``) also needs ``c``'s derivative in ``f`` and the
derivatives of ``(log p, g, c)`` in each threshold.  With ``D = rho_lo - rho_hi``,
``u = hi rho_hi - lo rho_lo`` and ``C = D^2 + u`` (so ``g = D / s``, ``c = C / s^2``):

    dD/dhi = rho_hi (hi - D),                   dD/dlo = rho_lo (D - lo),
    dC/dhi = rho_hi (2 D (hi - D) + 1 - hi^2 - u),  dC/dlo = rho_lo (2 D (D - lo) + u - 1 + lo^2),

``d log Z / dhi = rho_hi``, ``d log Z / dlo = -rho_lo``; ``hi`` and ``lo`` move by ``-1 / s``
with ``f`` and by ``1 / s`` with their own threshold, so ``dc/df = -(dC/dhi + dC/dlo) / s^3``.
An open end contributes nothing.

Tails go through the same Mills-ratio forms as the pairwise probit (``likelihood.py``): an
interval is flipped to ``lo + hi <= 0`` (``Z`` is symmetric), and an open end uses the probit's
own ratio, so nothing underflows.  :class:`Ordinal` holds the settings;
:meth:`Ordinal.thresholds_for` puts unset thresholds at the prior predictive's quantiles
(``f ~ N(0, v)`` plus the rating noise: every category equally likely before any data).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import log_ndtr, ndtr, ndtri

from gaitpref.checks import is_count, is_noise, is_number
from gaitpref.model.likelihood import interval_ratios, mills_ratio
from gaitpref.space import FloatArray

#: The most categories a rating scale may have (an operator picks one of them after a trial).
MAX_CATEGORIES = 100


@dataclass(frozen=True)
class Ordinal:
    """Ordinal ratings: ``categories`` labels (worst first), thresholds and rating noise.

    ``categories`` is the labels or their number ``K`` (labels ``"1"`` .. ``"K"``); a rating names
    its category by label or by its number ``1..K``.

    ``thresholds=None``: set from the signal variance at the prior predictive's quantiles (see
    :meth:`thresholds_for`).  ``noise`` is the rating noise ``s`` in utility units.
    """

    categories: tuple[str, ...]
    thresholds: tuple[float, ...] | None = None
    noise: float = 0.02

    def __init__(
        self,
        categories: Sequence[str] | int,
        thresholds: Sequence[float] | None = None,
        noise: float = 0.02,
    ) -> None:
        labels: tuple[str, ...]
        if isinstance(categories, int | np.integer) and is_count(categories):
            if not 2 <= categories <= MAX_CATEGORIES:
                raise ValueError(
                    f"an ordinal scale needs 2 to {MAX_CATEGORIES} categories, got {categories!r}"
                )
            labels = tuple(str(k) for k in range(1, int(categories) + 1))
        elif isinstance(categories, str) or not isinstance(categories, Sequence):
            raise ValueError(
                "categories must be a number of categories or a sequence of their names "
                f"(worst first), got {categories!r}"
            )
        else:
            labels = tuple(categories)
            if not all(isinstance(c, str) and c for c in labels):
                raise ValueError(f"category names must be non-empty strings, got {labels!r}")
        if len(labels) < 2 or len(set(labels)) != len(labels):
            raise ValueError(f"an ordinal scale needs >= 2 distinct categories, got {labels!r}")
        if len(labels) > MAX_CATEGORIES:
            raise ValueError(
                f"an ordinal scale needs 2 to {MAX_CATEGORIES} categories, got {len(labels)}"
            )
        if not is_noise(noise):
            raise ValueError(
                f"the rating noise must be positive with a finite square, got {noise!r}"
            )
        t = None
        if thresholds is not None:
            if isinstance(thresholds, str) or not isinstance(thresholds, Sequence | np.ndarray):
                raise ValueError(f"thresholds must be a sequence of numbers, got {thresholds!r}")
            if not all(is_number(x) for x in thresholds):
                raise ValueError(f"thresholds must be numbers, got {thresholds!r}")
            t = tuple(float(x) for x in thresholds)
            if len(t) != len(labels) - 1:
                raise ValueError(f"{len(labels)} categories need {len(labels) - 1} thresholds")
            if not all(np.isfinite(t)) or any(b <= a for a, b in itertools.pairwise(t)):
                raise ValueError(f"thresholds must be finite and increasing, got {t!r}")
        object.__setattr__(self, "categories", labels)
        object.__setattr__(self, "thresholds", t)
        object.__setattr__(self, "noise", float(noise))

    @property
    def size(self) -> int:
        return len(self.categories)

    def thresholds_for(self, signal_variance: float) -> tuple[float, ...]:
        """The thresholds, or (unset) ``sqrt(v + s^2) Phi^-1(k / K)``, ``k = 1..K-1``.

        ``signal_variance`` (the kernel's ``s^2``) must be a finite number > 0, even where the
        thresholds are set (a bad one is a caller's error either way)."""
        check_signal_variance(signal_variance)
        if self.thresholds is not None:
            return self.thresholds
        scale = float(np.sqrt(signal_variance + self.noise**2))
        if not np.isfinite(scale):
            raise ValueError(
                f"signal_variance ({signal_variance!r}) plus the rating noise squared "
                f"({self.noise!r}**2) overflows: no thresholds can be set from it"
            )
        return tuple(scale * float(ndtri(k / self.size)) for k in range(1, self.size))

    def label_index(self, label: object) -> int:
        """``1..K`` from a category name or a 1-based index."""
        if isinstance(label, str) and label in self.categories:
            return self.categories.index(label) + 1
        if (
            isinstance(label, int | np.integer)
            and not isinstance(label, bool)
            and 1 <= int(label) <= self.size
        ):
            return int(label)
        raise ValueError(
            f"rating {label!r} is not a category ({', '.join(self.categories)}) or 1..{self.size}"
        )


def check_signal_variance(signal_variance: object) -> None:
    """ValueError naming ``signal_variance`` unless it is a finite number > 0."""
    if not (is_number(signal_variance) and 0 < signal_variance < np.inf):  # type: ignore[operator]
        raise ValueError(f"signal_variance must be finite and positive, got {signal_variance!r}")


@dataclass(frozen=True)
class OrdinalLikelihood:
    """The ordered probit over single utilities, one label ``1..K`` per observation."""

    labels: NDArray[np.intp]
    thresholds: FloatArray  # (K - 1,) increasing
    noise: float
    thresholds_fixed: bool = False  # set by the config: the evidence does not fit them

    def __post_init__(self) -> None:
        if not is_noise(self.noise):
            raise ValueError(
                f"the rating noise must be positive with a finite square, got {self.noise!r}"
            )

    def bounds(self, values: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``(lo, hi)`` in units of ``s`` per observation (``-inf`` / ``+inf`` at the ends)."""
        t = np.concatenate([[-np.inf], self.thresholds, [np.inf]])
        lo = (t[self.labels - 1] - values) / self.noise
        hi = (t[self.labels] - values) / self.noise
        return lo, hi

    def _ratios(self, values: FloatArray) -> tuple[FloatArray, ...]:
        """``(lo, hi, log Z, rho_lo, rho_hi, u)`` per observation, ``u = hi rho_hi - lo rho_lo``
        (``rho`` and ``u`` are 0 at an open end)."""
        lo, hi = self.bounds(values)
        n = values.shape[0]
        log_z, r_lo, r_hi, u = (np.zeros(n) for _ in range(4))
        bottom = np.isneginf(lo)  # k = 1: Z = Phi(hi)
        top = np.isposinf(hi) & ~bottom  # k = K: Z = Phi(-lo)
        both = ~(bottom | top)
        if np.any(bottom):
            h = hi[bottom]
            log_z[bottom] = log_ndtr(h)
            r_hi[bottom] = mills_ratio(h)
            u[bottom] = h * r_hi[bottom]
        if np.any(top):
            ell = lo[top]
            log_z[top] = log_ndtr(-ell)
            r_lo[top] = mills_ratio(-ell)
            u[top] = -ell * r_lo[top]
        if np.any(both):
            a, b = lo[both], hi[both]
            flip = a + b > 0.0  # work at lo + hi <= 0: (a, b) -> (-b, -a), same Z
            fa, fb = np.where(flip, -b, a), np.where(flip, -a, b)
            lz, rho_hi, rho_lo, _ = interval_ratios(fa, fb)
            log_z[both] = lz
            r_lo[both] = np.where(flip, rho_hi, rho_lo)
            r_hi[both] = np.where(flip, rho_lo, rho_hi)
            u[both] = b * r_hi[both] - a * r_lo[both]
        return lo, hi, log_z, r_lo, r_hi, u

    def terms(self, values: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        _, _, log_z, r_lo, r_hi, u = self._ratios(values)
        d = r_lo - r_hi
        grad = d / self.noise
        curv = np.clip(d**2 + u, 0.0, 1.0) / self.noise**2
        return log_z, grad, curv

    def _end_derivatives(self, values: FloatArray) -> tuple[FloatArray, ...]:
        """Derivatives of ``log Z``, ``D = rho_lo - rho_hi`` and ``C = D^2 + u`` in ``hi`` and in
        ``lo``: ``(rho_hi, dD/dhi, dC/dhi, -rho_lo, dD/dlo, dC/dlo)`` (module docstring); each
        is 0 at an open end (no threshold there)."""
        lo, hi, _, r_lo, r_hi, u = self._ratios(values)
        d = r_lo - r_hi
        fin_hi, fin_lo = np.isfinite(hi), np.isfinite(lo)
        h, ell = np.where(fin_hi, hi, 0.0), np.where(fin_lo, lo, 0.0)
        dd_hi = np.where(fin_hi, r_hi * (h - d), 0.0)
        dd_lo = np.where(fin_lo, r_lo * (d - ell), 0.0)
        dc_hi = np.where(fin_hi, r_hi * (2.0 * d * (h - d) + 1.0 - h * h - u), 0.0)
        dc_lo = np.where(fin_lo, r_lo * (2.0 * d * (d - ell) + u - 1.0 + ell * ell), 0.0)
        return r_hi, dd_hi, dc_hi, -r_lo, dd_lo, dc_lo

    def third(self, values: FloatArray) -> FloatArray:
        """``d c / d f = -d^3 log p / d f^3`` per observation (the evidence's gradient)."""
        _, _, dc_hi, _, _, dc_lo = self._end_derivatives(values)
        out: FloatArray = -(dc_hi + dc_lo) / self.noise**3
        return out

    def threshold_terms(self, values: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Derivatives of ``(log p, g, c)`` (as :meth:`terms`) with respect to each threshold:
        three ``n x (K - 1)`` arrays (an observation depends only on the thresholds around its
        category)."""
        s = self.noise
        dz_hi, dd_hi, dc_hi, dz_lo, dd_lo, dc_lo = self._end_derivatives(values)
        n, k = values.shape[0], self.thresholds.shape[0]
        out: tuple[FloatArray, FloatArray, FloatArray] = (
            np.zeros((n, k)),
            np.zeros((n, k)),
            np.zeros((n, k)),
        )
        rows = np.arange(n)
        upper = self.labels <= k  # t_label is this category's upper threshold
        lower = self.labels >= 2  # t_(label - 1) its lower one
        for arr, up, low, power in zip(
            out, (dz_hi, dd_hi, dc_hi), (dz_lo, dd_lo, dc_lo), (1, 2, 3), strict=True
        ):
            arr[rows[upper], self.labels[upper] - 1] += up[upper] / s**power
            arr[rows[lower], self.labels[lower] - 2] += low[lower] / s**power
        return out

    def with_thresholds(self, thresholds: Sequence[float] | FloatArray) -> OrdinalLikelihood:
        """The same ratings under other thresholds (increasing, ``K - 1`` of them)."""
        t = np.asarray(thresholds, dtype=np.float64)
        if t.shape != self.thresholds.shape or np.any(np.diff(t) <= 0):
            raise ValueError(
                f"thresholds must be {self.thresholds.size} increasing values, got {t.tolist()}"
            )
        return OrdinalLikelihood(self.labels, t, self.noise, self.thresholds_fixed)


def rating_likelihood(
    ordinal: Ordinal, signal_variance: float, labels: ArrayLike
) -> OrdinalLikelihood:
    """The likelihood of ratings ``labels`` (``1..K``) under ``ordinal``."""
    given = np.asarray(labels)
    if given.ndim != 1 or (given.size and not np.issubdtype(given.dtype, np.integer)):
        raise ValueError(
            f"rating labels must be a 1-D sequence of integers 1..{ordinal.size}, got "
            f"dtype {given.dtype} and shape {given.shape}"
        )
    idx = given.astype(np.intp)
    if idx.size and (idx.min() < 1 or idx.max() > ordinal.size):
        raise ValueError(f"rating labels must be in 1..{ordinal.size}")
    t = np.asarray(ordinal.thresholds_for(signal_variance), dtype=np.float64)
    return OrdinalLikelihood(idx, t, ordinal.noise, ordinal.thresholds is not None)


def rating_probabilities(
    ordinal: Ordinal, signal_variance: float, mean: FloatArray, variance: FloatArray
) -> FloatArray:
    """``P(rating = k)`` (``n x K``) for utilities ``N(mean, variance)``: the ordered probit with
    the noise widened to ``sqrt(s^2 + variance)`` (the posterior integrated out).

    ``mean`` and ``variance`` are 1-D of one length, finite; a variance may fall below 0 by
    rounding (a posterior covariance's diagonal) but not by more than ``sqrt(eps)`` times
    ``signal_variance + s^2``."""
    t = ordinal.thresholds_for(signal_variance)
    _check_moments(mean, variance, float(signal_variance) + ordinal.noise**2)
    return predictive_probabilities(ordinal, t, mean, variance)


def predictive_probabilities(
    ordinal: Ordinal, thresholds: Sequence[float], mean: ArrayLike, variance: ArrayLike
) -> FloatArray:
    """:func:`rating_probabilities` with the thresholds given and the moments unchecked: for a
    posterior's own moments (``Posterior.rating_probabilities``), whose variances may fall
    below 0 by the rounding of the prior variance (which this function cannot see)."""
    t = np.concatenate([[-np.inf], thresholds, [np.inf]])
    scale = np.sqrt(ordinal.noise**2 + np.asarray(variance))[:, None]
    cdf = ndtr((t[None, :] - np.asarray(mean)[:, None]) / scale)
    out: FloatArray = np.clip(np.diff(cdf, axis=1), 0.0, 1.0)
    return out


def _check_moments(mean: object, variance: object, scale: float) -> None:
    """``mean`` and ``variance`` of :func:`rating_probabilities`, or a ValueError naming them."""
    m, v = np.asarray(mean), np.asarray(variance)
    if m.ndim != 1 or v.shape != m.shape or m.dtype.kind not in "iuf" or v.dtype.kind not in "iuf":
        raise ValueError(
            "mean and variance must be 1-D arrays of numbers of one length, got shapes "
            f"{m.shape} and {v.shape} (dtypes {m.dtype} and {v.dtype})"
        )
    if not np.all(np.isfinite(m)):
        raise ValueError("mean must be finite")
    floor = -float(np.sqrt(np.finfo(float).eps)) * scale
    if not np.all(np.isfinite(v) & (v >= floor)):
        low = float(v.min())
        raise ValueError(f"variance must be finite and >= 0 (to rounding), got min {low!r}")


__all__ = ["Ordinal", "OrdinalLikelihood", "rating_likelihood", "rating_probabilities"]
