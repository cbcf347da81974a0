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
With ``share=True`` (the line path's table, which grows by a few rows an answer and keeps every
earlier table for undo) the larger set's rows are a view of one buffer that the sets of a
lineage share, each set the one before and more, and so is their index of rows: 500 tables of
up to 1,000 points on 12 features held 47 MB of rows and 20 MB of indices, a copy each.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike

from gaitpref.space import POINTS_LIMIT_ACTIONS, FloatArray, IntArray, Move, Space


class _Lineage:
    """The rows of point sets each one the one before with rows appended: one buffer (its first
    ``used`` rows those of the last set) and the row of each point (its first), shared by all."""

    __slots__ = ("buffer", "rows", "used")

    def __init__(self, buffer: FloatArray, used: int, rows: dict[tuple[float, ...], int]) -> None:
        self.buffer, self.used, self.rows = buffer, used, rows


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
        object.__setattr__(self, "_lineage", None)

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
        row: int | None = self._rows.get(key)  # type: ignore[attr-defined]
        # a lineage's index holds the rows of the sets extended from this one too
        return row if row is not None and row < len(self) else None

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

    def extended(self, points: ArrayLike, *, share: bool = False) -> tuple[PointSet, IntArray]:
        """This set with ``points`` appended (those already present, or repeated, are not
        added again) and the row of each given point in the result.

        ``share``: the result's rows and index are those of this set's lineage (a view of its
        buffer, :class:`_Lineage`), not a copy, when this set is the last one extended in it,
        else of a new lineage starting with them; the same points either way.  For a set that
        grows step by step and keeps its earlier sets (the line path's table); not for a set
        extended by points tried and dropped (a line's), which would start a lineage each."""
        new = _rows(points, self.ndim)
        rows: list[list[float]] = []
        seen: dict[tuple[float, ...], int] = {}
        ids = np.empty(new.shape[0], dtype=np.intp)
        index: dict[tuple[float, ...], int] = self._rows  # type: ignore[attr-defined]
        size = len(self)
        for k, row in enumerate(new.tolist()):
            key = tuple(row)
            found = index.get(key)  # as find(row): a lineage's index holds later sets' rows
            if found is not None and found >= size:
                found = None
            if found is None:
                found = seen.get(key)
            if found is None:
                found = len(self) + len(rows)
                seen[key] = found
                rows.append(row)
            ids[k] = found
        if not rows:
            return self, ids
        added = np.array(rows)
        if share and _in_domain(self, added) and len(self) + len(rows) <= POINTS_LIMIT_ACTIONS:
            return self._grown(added, seen), ids
        known = {**self._own_rows(), **seen}
        return PointSet(self, np.concatenate([self.points, added]), known=known), ids

    def _own_rows(self) -> dict[tuple[float, ...], int]:
        """The row of each point of this set (a lineage's index less the rows past it)."""
        rows: dict[tuple[float, ...], int] = self._rows  # type: ignore[attr-defined]
        lineage: _Lineage | None = self._lineage  # type: ignore[attr-defined]
        if lineage is None or lineage.used == len(self):
            return rows
        return {key: k for key, k in rows.items() if k < len(self)}

    def _grown(self, added: FloatArray, seen: dict[tuple[float, ...], int]) -> PointSet:
        """This set with ``added`` (checked, new, distinct) appended, in its lineage."""
        n, total = len(self), len(self) + len(added)
        lineage: _Lineage | None = self._lineage  # type: ignore[attr-defined]
        if lineage is None or lineage.used != n:  # not the lineage's last set: a new lineage
            buffer = np.empty((max(2 * total, 16), self.ndim))
            buffer[:n] = self.points
            lineage = _Lineage(buffer, n, dict(self._own_rows()))
        elif total > lineage.buffer.shape[0]:  # earlier sets keep their views of the old one
            buffer = np.empty((2 * total, self.ndim))
            buffer[:n] = lineage.buffer[:n]
            lineage.buffer = buffer
        lineage.buffer[n:total] = added
        lineage.used = total
        lineage.rows.update(seen)
        view = lineage.buffer[:total]
        view.setflags(write=False)
        out = object.__new__(PointSet)
        Space.__init__(out, self.features)
        object.__setattr__(out, "points", view)
        object.__setattr__(out, "_rows", lineage.rows)
        object.__setattr__(out, "_lineage", lineage)
        return out

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


def _in_domain(space: Space, added: FloatArray) -> bool:
    """Whether every row of ``added`` is numbers within the features' ranges (else the
    constructor's checks say which feature)."""
    lo = np.array([f.values[0] for f in space.features])
    hi = np.array([f.values[-1] for f in space.features])
    return bool(np.all(np.isfinite(added)) and np.all((added >= lo) & (added <= hi)))


def empty_points(domain: Space) -> PointSet:
    """A point set over ``domain``'s features with no points yet."""
    return PointSet(domain, np.zeros((0, domain.ndim)))


__all__ = ["PointSet", "empty_points"]
