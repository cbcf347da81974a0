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

from gaitpref.model.likelihood import interval_ratios, mills_ratio
from gaitpref.space import FloatArray


@dataclass(frozen=True)
class Ordinal:
    """Ordinal ratings: ``categories`` labels (worst first), thresholds and rating noise.

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
        labels = (
            tuple(str(k) for k in range(1, categories + 1))
            if isinstance(categories, int)
            else tuple(categories)
        )
        if len(labels) < 2 or len(set(labels)) != len(labels):
            raise ValueError(f"an ordinal scale needs >= 2 distinct categories, got {labels!r}")
        if not (np.isfinite(noise) and noise > 0):
            raise ValueError(f"the rating noise must be positive, got {noise!r}")
        t = None
        if thresholds is not None:
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
        """The thresholds, or (unset) ``sqrt(v + s^2) Phi^-1(k / K)``, ``k = 1..K-1``."""
        if self.thresholds is not None:
            return self.thresholds
        scale = float(np.sqrt(signal_variance + self.noise**2))
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


@dataclass(frozen=True)
class OrdinalLikelihood:
    """The ordered probit over single utilities, one label ``1..K`` per observation."""

    labels: NDArray[np.intp]
    thresholds: FloatArray  # (K - 1,) increasing
    noise: float

    def bounds(self, values: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``(lo, hi)`` in units of ``s`` per observation (``-inf`` / ``+inf`` at the ends)."""
        t = np.concatenate([[-np.inf], self.thresholds, [np.inf]])
        lo = (t[self.labels - 1] - values) / self.noise
        hi = (t[self.labels] - values) / self.noise
        return lo, hi

    def terms(self, values: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        lo, hi = self.bounds(values)
        n = values.shape[0]
        log_z, r_lo, r_hi, u = (np.zeros(n) for _ in range(4))  # u = hi rho_hi - lo rho_lo
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
        d = r_lo - r_hi
        grad = d / self.noise
        curv = np.clip(d**2 + u, 0.0, 1.0) / self.noise**2
        return log_z, grad, curv


def rating_likelihood(
    ordinal: Ordinal, signal_variance: float, labels: ArrayLike
) -> OrdinalLikelihood:
    """The likelihood of ratings ``labels`` (``1..K``) under ``ordinal``."""
    idx = np.asarray(labels, dtype=np.intp)
    if idx.size and (idx.min() < 1 or idx.max() > ordinal.size):
        raise ValueError(f"rating labels must be in 1..{ordinal.size}")
    t = np.asarray(ordinal.thresholds_for(signal_variance), dtype=np.float64)
    return OrdinalLikelihood(idx, t, ordinal.noise)


def rating_probabilities(
    ordinal: Ordinal, signal_variance: float, mean: FloatArray, variance: FloatArray
) -> FloatArray:
    """``P(rating = k)`` (``n x K``) for utilities ``N(mean, variance)``: the ordered probit with
    the noise widened to ``sqrt(s^2 + variance)`` (the posterior integrated out)."""
    t = np.concatenate([[-np.inf], ordinal.thresholds_for(signal_variance), [np.inf]])
    scale = np.sqrt(ordinal.noise**2 + np.asarray(variance))[:, None]
    cdf = ndtr((t[None, :] - np.asarray(mean)[:, None]) / scale)
    out: FloatArray = np.clip(np.diff(cdf, axis=1), 0.0, 1.0)
    return out


__all__ = ["Ordinal", "OrdinalLikelihood", "rating_likelihood", "rating_probabilities"]
