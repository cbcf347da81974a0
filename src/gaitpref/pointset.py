"""A finite set of explicit points in a space's features: the actions of the line path.

LineCoSpar (Tucker et al., IROS 2020) and LineBO (Kirschner et al., ICML 2019) never enumerate the
space: the model lives on the points visited so far plus the points of the current
one-dimensional subspace (``loop/line.py``).  A :class:`PointSet` is such a set: rows of feature
values (in the features' units) over the features of a *domain* :class:`~gaitpref.space.Space`
whose features may be continuous or too many to enumerate.  It is a :class:`Space` whose action
``a`` is row ``a``, so the model (kernel, Laplace fit, posterior, strategies) runs on it as on a
grid; the kernel computes it from coordinates (``model/kernels.py``).

A point set is immutable; :meth:`PointSet.extended` returns a larger one whose first rows are
this one's (so an action keeps its index), with points already present mapped to their rows.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from gaitpref.space import POINTS_LIMIT_ACTIONS, FloatArray, IntArray, Move, Space


class PointSet(Space):
    """Explicit points (``A x d``, the features' units) over the features of ``domain``."""

    def __init__(
        self,
        domain: Space,
        points: ArrayLike,
        *,
        known: dict[tuple[float, ...], int] | None = None,
    ) -> None:
        """``known`` (from :meth:`extended`) is every row's first index, given when it is
        already known so that it is not rebuilt from all the points."""
        super().__init__(domain.features)
        arr = _rows(points, domain.ndim)
        if arr.shape[0] > POINTS_LIMIT_ACTIONS:  # before a Python tuple is made of each row
            raise ValueError(
                f"a point set holds at most {POINTS_LIMIT_ACTIONS:,} points (a grid's bound), "
                f"got {arr.shape[0]:,}"
            )
        for j, f in enumerate(domain.features):
            col = arr[:, j]
            if col.size and not np.all(np.isfinite(col)):
                raise ValueError(f"{f.name}: points must be numbers, got {col.tolist()}")
            if col.size and (col.min() < f.values[0] or col.max() > f.values[-1]):
                raise ValueError(
                    f"{f.name}: points must lie in {f.values[0]:g} .. {f.values[-1]:g}"
                )
        arr.setflags(write=False)
        object.__setattr__(self, "points", arr)  # shadows Space.points (a cached property)
        if known is None:
            known = {tuple(row): k for k, row in reversed(list(enumerate(arr.tolist())))}
        object.__setattr__(self, "_rows", known)

    #: a point set has no grid: an index past its rows is not in its point table
    _off: ClassVar[str] = "not in the point table"

    def __len__(self) -> int:
        return int(self.points.shape[0])

    def _range_words(self) -> str:
        """The valid rows in words: ``points 0..A-1 so far`` (the line path adds points), or
        none yet."""
        return f"points 0..{len(self) - 1} so far" if len(self) else "it has no points yet"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PointSet):
            return NotImplemented
        return self.features == other.features and np.array_equal(self.points, other.points)

    def __hash__(self) -> int:
        return hash((self.features, self.points.tobytes()))

    def __repr__(self) -> str:
        return f"PointSet({len(self)} points over {', '.join(self.names)})"

    @property
    def shape(self) -> tuple[int, ...]:
        raise TypeError("a point set is not a grid: it has no per-feature shape")

    @property
    def domain(self) -> Space:
        """The space of the features (continuous or grid) these points lie in."""
        return Space(self.features)

    def find(self, point: ArrayLike) -> int | None:
        """The row equal to ``point`` (exactly), or None."""
        key = tuple(float(v) for v in np.asarray(point, dtype=np.float64).ravel())
        if len(key) != self.ndim:  # "not in the set" before, whatever the point
            raise ValueError(
                f"point has {len(key)} coordinates, the point set's features {self.ndim}"
            )
        return self._rows.get(key)  # type: ignore[attr-defined, no-any-return]

    def index(self, point: Sequence[float] | dict[str, float], *, atol: float = 1e-9) -> int:
        coords = np.asarray(self._coords(point, atol))
        dist = np.max(np.abs(self.points - coords), axis=1) if len(self) else np.zeros(0)
        if dist.size == 0 or dist.min() > atol:
            raise ValueError(f"point {coords.tolist()} is not in this point set")
        return int(np.argmin(dist))

    def points_of(self, actions: Sequence[int] | IntArray) -> FloatArray:
        idx = np.asarray([self.check_index(a) for a in actions], dtype=np.intp)
        out: FloatArray = self.points[idx].reshape(-1, self.ndim)
        return out

    def extended(self, points: ArrayLike) -> tuple[PointSet, IntArray]:
        """This set with ``points`` appended (those already present, or repeated, are not
        added again) and the row of each given point in the result."""
        new = _rows(points, self.ndim)
        rows: list[list[float]] = []
        seen: dict[tuple[float, ...], int] = {}
        ids = np.empty(new.shape[0], dtype=np.intp)
        for k, row in enumerate(new.tolist()):
            key = tuple(row)
            found = self.find(row)
            if found is None:
                found = seen.get(key)
            if found is None:
                found = len(self) + len(rows)
                seen[key] = found
                rows.append(row)
            ids[k] = found
        if not rows:
            return self, ids
        known = {**self._rows, **seen}  # type: ignore[attr-defined]
        return PointSet(self, np.concatenate([self.points, np.array(rows)]), known=known), ids

    def move_target(self, index: int, feature: str | int, move: Move) -> FloatArray | None:
        """The point a coactive move of ``feature`` from action ``index`` suggests (the
        feature's fraction of its range, clipped, snapped on a discrete feature), or None
        when it lands back on the same point."""
        i = self.check_index(index)
        f = self.feature_number(feature)
        value = self.features[f].move_value(float(self.points[i, f]), move)
        if value is None:
            return None
        out: FloatArray = self.points[i].copy()
        out[f] = value
        return out

    def coactive_move(self, index: int, feature: str | int, move: Move) -> int | None:
        """The row of the point a coactive move suggests (``move_target``), which must be in
        the set (the line loop adds it before the answer is fitted), or None."""
        target = self.move_target(index, feature, move)
        if target is None:
            return None
        row = self.find(target)
        if row is None:
            raise LookupError(
                f"the suggested point {target.tolist()} is not in the point set yet; "
                "extend the set with move_target first"
            )
        return row


def _rows(points: ArrayLike, ndim: int) -> FloatArray:
    """``points`` as a ``k x ndim`` float array (a copy): rows of one value per feature (a flat
    list of four numbers became two points of a 2-D space before, three a NumPy error)."""
    arr = np.array(points, dtype=np.float64)
    if arr.size == 0:
        return arr.reshape(0, ndim)
    if arr.ndim != 2 or arr.shape[1] != ndim:
        raise ValueError(
            f"points must be rows of {ndim} values (one per feature), got shape {arr.shape}"
        )
    return arr


def empty_points(domain: Space) -> PointSet:
    """A point set over ``domain``'s features with no points yet."""
    return PointSet(domain, np.zeros((0, domain.ndim)))


__all__ = ["PointSet", "empty_points"]
