"""Squared-exponential product kernel over a gait grid, with its Kronecker structure.

The paper's prior (Section "Modeling Utilities from Preference Data"): ``f ~ N(0, K)`` with
``K_ij = s^2 prod_f exp(-(x_if - x_jf)^2 / (2 l_f^2)) + jitter [i == j]``.  The jitter (the paper's
"noise variance") belongs to the prior over grid points: it appears wherever a row and a column
are the same grid point, also in a cross-covariance ``K_{:,V}`` (``docs/model.md``, "Notation"
for ``K``, "Large grids" for the jitter at row ``v_j`` of column ``j`` of ``K_{:,V}``).

On a Cartesian grid the kernel factorises, ``K = s^2 (K_1 (x) ... (x) K_d) + jitter I`` with the
per-feature ``n_f x n_f`` correlation matrices ``K_f``; any block ``K[rows, cols]`` is the product
of per-feature gathers, so no ``A x A`` matrix is ever needed.

On a :class:`~gaitpref.pointset.PointSet` (the line path's explicit points, issue 13) there is no
grid: ``K[rows, cols]`` is computed from the points' coordinates, with the jitter where a row and
a column are the same point.

Notation: ``A`` grid points, ``m`` columns asked for, ``d`` features.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitpref.checks import is_number
from gaitpref.pointset import PointSet
from gaitpref.space import FloatArray, IntArray, Space


@dataclass(frozen=True)
class SquaredExponential:
    """Squared-exponential product kernel: per-feature lengthscales (feature units), signal
    variance ``variance`` and a grid jitter ``jitter`` added on the diagonal."""

    lengthscale: tuple[float, ...] | float
    variance: float
    jitter: float = 0.0

    def __post_init__(self) -> None:
        ls = self.lengthscale
        ls_t: tuple[float, ...] | float
        if np.ndim(ls) > 1:  # a table of lengthscales was read row after row
            raise ValueError(
                f"lengthscale must be one number or one per feature, got shape {np.shape(ls)}"
            )
        items = list(np.ravel(np.asarray(ls, dtype=object)))
        if not items or not all(is_number(v) and np.isfinite(v) and v > 0 for v in items):
            raise ValueError(f"lengthscale must be positive and finite, got {ls!r}")
        if is_number(ls) or np.ndim(ls) == 0:
            ls_t = float(items[0])
        else:
            ls_t = tuple(float(v) for v in items)
        if not (is_number(self.variance) and np.isfinite(self.variance) and self.variance > 0):
            raise ValueError(f"signal variance must be positive, got {self.variance!r}")
        if not (is_number(self.jitter) and np.isfinite(self.jitter) and self.jitter >= 0):
            raise ValueError(f"jitter must be >= 0, got {self.jitter!r}")
        if not np.isfinite(float(self.variance) + float(self.jitter)):  # the prior variance
            raise ValueError(
                f"signal variance + jitter (each gait's prior variance) must be finite, got "
                f"{self.variance!r} + {self.jitter!r}"
            )
        object.__setattr__(self, "lengthscale", ls_t)
        object.__setattr__(self, "variance", float(self.variance))
        object.__setattr__(self, "jitter", float(self.jitter))

    def lengthscales(self, ndim: int) -> tuple[float, ...]:
        """One lengthscale per feature (a scalar is shared by all)."""
        if isinstance(self.lengthscale, float):
            return (self.lengthscale,) * ndim
        if len(self.lengthscale) != ndim:
            raise ValueError(
                f"kernel has {len(self.lengthscale)} lengthscales but the space has {ndim} features"
            )
        return self.lengthscale

    def same_covariances(self, other: SquaredExponential, ndim: int) -> bool:
        """Whether ``other`` computes the same covariances over ``ndim`` features: the same
        lengthscales, variance and jitter (a scalar lengthscale is every feature's, so ``0.15``
        and ``(0.15,)`` are one kernel in 1-D, though not equal as dataclasses)."""
        return (self.lengthscales(ndim), self.variance, self.jitter) == (
            other.lengthscales(ndim),
            other.variance,
            other.jitter,
        )

    def factors(self, space: Space) -> list[FloatArray]:
        """Per-feature correlation matrices ``K_f`` (``n_f x n_f``, unit diagonal)."""
        out = []
        for f, ell in zip(space.features, self.lengthscales(space.ndim), strict=True):
            x = f.array
            out.append(np.exp(-0.5 * ((x[:, None] - x[None, :]) / ell) ** 2))
        return out

    def cross(self, space: Space, cols: IntArray, rows: IntArray | None = None) -> FloatArray:
        """``K[rows, cols]`` (all rows when ``rows`` is None), jitter where row == col.

        Each factor's columns are gathered first (``n_f x m``), then their rows: for all rows
        the result is a column-wise Khatri-Rao product built by broadcasting, never an
        ``A x m`` fancy-index gather per feature.
        """
        if isinstance(space, PointSet):
            return self._cross_points(space, cols, rows)
        cols = np.asarray(cols, dtype=np.intp)
        m = cols.shape[0]
        col_mi = np.unravel_index(cols, space.shape)
        gathered = [kf[:, c] for kf, c in zip(self.factors(space), col_mi, strict=True)]
        if rows is None:
            row_idx = np.arange(len(space))
            out = np.full((1, m), self.variance)
            for g in gathered:
                out = (out[:, None, :] * g[None, :, :]).reshape(out.shape[0] * g.shape[0], m)
        else:
            row_idx = np.asarray(rows, dtype=np.intp)
            row_mi = np.unravel_index(row_idx, space.shape)
            out = np.full((row_idx.shape[0], m), self.variance)
            for g, r in zip(gathered, row_mi, strict=True):
                out *= g[r]
        if self.jitter:
            out += self.jitter * (row_idx[:, None] == cols[None, :])
        return out

    def _cross_points(self, space: PointSet, cols: IntArray, rows: IntArray | None) -> FloatArray:
        """``K[rows, cols]`` from the points' coordinates (a point set: no grid structure)."""
        cols = np.asarray(cols, dtype=np.intp)
        row_idx = np.arange(len(space)) if rows is None else np.asarray(rows, dtype=np.intp)
        scale = np.asarray(self.lengthscales(space.ndim))
        # Features as contiguous rows and two preallocated buffers: the same elementwise
        # operations in the same order as summing ``(x_i - x_j)^2`` feature by feature, so the
        # same floats, without an ``n x m`` temporary per feature (issue 13's speed target).
        x_rows = np.ascontiguousarray((space.points[row_idx] / scale).T)
        x_cols = np.ascontiguousarray((space.points[cols] / scale).T)
        out: FloatArray = np.zeros((row_idx.shape[0], cols.shape[0]))
        diff = np.empty_like(out)
        for j in range(space.ndim):
            np.subtract(x_rows[j, :, None], x_cols[j, None, :], out=diff)
            np.square(diff, out=diff)
            out += diff
        out *= -0.5
        np.exp(out, out=out)
        out *= self.variance
        if self.jitter:
            out += self.jitter * (row_idx[:, None] == cols[None, :])
        return out

    def diagonal(self, space: Space) -> FloatArray:
        """Prior variance of every action, ``s^2 + jitter``."""
        return np.full(len(space), self.variance + self.jitter)

    def dense(self, space: Space) -> FloatArray:
        """The full ``A x A`` prior covariance (small grids only: tests, dense covariance)."""
        return self.cross(space, np.arange(len(space)))
