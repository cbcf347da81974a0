"""Named gait features and the finite grid of actions CoSpar chooses from.

The action set of the paper (Section "Preference-based Learning Algorithm") is a finite grid
``X`` of ``A`` points over ``d`` named features.  The grid is the Cartesian product of the
features' values in **C order over the features as declared**: the last feature varies fastest,
so the point with per-feature value indices ``(i_1, ..., i_d)`` has the flat index
``numpy.ravel_multi_index((i_1, ..., i_d), shape)``.

Coactive moves ("longer step", "slightly shorter step") follow the paper's experiments: a move is
a signed fraction of the feature's range; the suggestion is the grid value nearest to
``current + fraction * (max - min)``, clipped to the grid, and a move that lands back on the current
point carries no feedback (``None``).

A feature may instead be *continuous* (``Feature.interval``: a range with no grid values, issue
13); a space with one has no finite grid and runs on the line path (``pointset.py``,
``loop/line.py``), where a coactive move is the same fraction of the range, clipped and not
snapped.

Notation: ``A`` actions, ``d`` features, feature ``f`` has ``n_f`` values; ``points`` is ``A x d``.
"""

from __future__ import annotations

import bisect
import math
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import ClassVar, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike, NDArray

from gaitpref.checks import is_count, is_number

Move = Literal["+big", "+small", "-small", "-big"]
MOVES: tuple[Move, ...] = get_args(Move)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: The most values :meth:`Feature.linspace` makes, and a :class:`Feature` holds: as many as the
#: largest grid a model takes (``model/engines.py``, ``GRID_LIMIT_ACTIONS``); a config's features
#: have at most 10**6.  A feature keeps its values as Python floats (32 bytes each).
MAX_LINSPACE_VALUES = 10_000_000
#: The most grid points :attr:`Space.points` and :attr:`Space.multi_index` build (``A x d``
#: arrays): as many as a model on a grid takes (``model/engines.py``, ``GRID_LIMIT_ACTIONS``).
#: Past it they are refused before anything is allocated (a 1000^4 grid asked NumPy for 7 TiB).
POINTS_LIMIT_ACTIONS = 10_000_000
#: The most features a grid's actions are indexed over: NumPy indexes them over one axis per
#: feature, and ``ravel_multi_index`` takes one fewer than NumPy's 32 arguments (64 from NumPy
#: 2).  More features run on the line path, which never indexes a grid.
MAX_GRID_FEATURES = 63 if np.lib.NumpyVersion(np.__version__) >= "2.0.0" else 31


@dataclass(frozen=True)
class Feature:
    """One gait feature: its grid values (strictly increasing), unit and coactive fractions.

    ``coactive = (small, big)`` are the fractions of the feature's range that "slightly longer"
    and "longer" move by.  ``words = (increase, decrease)`` name the direction for an operator
    ("longer", "shorter").
    """

    name: str
    values: tuple[float, ...]
    unit: str = ""
    coactive: tuple[float, float] = (0.1, 0.2)
    words: tuple[str, str] = ("more", "less")
    continuous: bool = False

    def __init__(
        self,
        name: str,
        values: ArrayLike,
        unit: str = "",
        coactive: Sequence[float] = (0.1, 0.2),
        words: Sequence[str] = ("more", "less"),
        *,
        continuous: bool = False,
    ) -> None:
        if not isinstance(name, str) or not name.isidentifier():
            raise ValueError(f"feature name must be an identifier, got {name!r}")
        # numbers only: NumPy read "123" as the value 123.0, [False, True] as 0 and 1, and a
        # table of values as one row after another
        try:
            raw = None if isinstance(values, str | bytes) else np.asarray(values)
        except (TypeError, ValueError):
            raw = None
        if raw is None or raw.dtype.kind not in "iuf":
            raise ValueError(f"feature {name!r}: values must be numbers, got {values!r}")
        if raw.ndim > 1:
            raise ValueError(
                f"feature {name!r}: values must be a 1-D sequence, got shape {raw.shape}"
            )
        if raw.size > MAX_LINSPACE_VALUES:  # before a Python float is made for each
            raise ValueError(
                f"feature {name!r}: at most {MAX_LINSPACE_VALUES:,} values, got {raw.size:,}"
            )
        arr = raw.astype(np.float64).ravel()
        if arr.size == 0:
            raise ValueError(f"feature {name!r}: needs at least one value")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"feature {name!r}: values must be finite")
        if not math.isfinite(float(arr[-1]) - float(arr[0])):  # past a float: moves, scales inf
            raise ValueError(f"feature {name!r}: the range of the values must be finite")
        if arr.size > 1 and not np.all(np.diff(arr) > 0):
            raise ValueError(f"feature {name!r}: values must be strictly increasing")
        if not isinstance(continuous, bool | np.bool_):  # "no" was truthy: continuous
            raise ValueError(
                f"feature {name!r}: continuous must be True or False, got {continuous!r}"
            )
        if continuous and arr.size != 2:
            raise ValueError(f"feature {name!r}: a continuous feature is given as (min, max)")
        try:
            small, big = (float(c) for c in coactive)
        except (TypeError, ValueError):
            raise ValueError(
                f"feature {name!r}: coactive must be two numbers (small, big), got {coactive!r}"
            ) from None
        if not (0 < small <= big <= 1):
            raise ValueError(
                f"feature {name!r}: coactive must be (small, big) with 0 < small <= big <= 1, "
                f"got {tuple(coactive)!r}"
            )
        if not isinstance(unit, str):
            raise ValueError(f"feature {name!r}: unit must be a string, got {unit!r}")
        if (
            isinstance(words, str)
            or len(words) != 2
            or not all(isinstance(w, str) and w for w in words)
        ):
            raise ValueError(f"feature {name!r}: words must be two non-empty strings")
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "values", tuple(float(v) for v in arr))
        object.__setattr__(self, "unit", str(unit))
        object.__setattr__(self, "coactive", (small, big))
        object.__setattr__(self, "words", (str(words[0]), str(words[1])))
        object.__setattr__(self, "continuous", bool(continuous))

    @classmethod
    def interval(cls, name: str, lo: float, hi: float, **kwargs: object) -> Feature:
        """A continuous feature over ``[lo, hi]`` (``values`` holds the two bounds)."""
        if not (is_number(lo) and is_number(hi)):
            raise ValueError(f"feature {name!r}: min and max must be numbers, got {lo!r}..{hi!r}")
        if not hi > lo:
            raise ValueError(f"feature {name!r}: max must exceed min, got {lo}..{hi}")
        return cls(name, (lo, hi), continuous=True, **kwargs)  # type: ignore[arg-type]

    @classmethod
    def linspace(cls, name: str, lo: float, hi: float, num: int, **kwargs: object) -> Feature:
        """A feature with ``num`` equally spaced values from ``lo`` to ``hi`` inclusive."""
        if not (is_number(lo) and is_number(hi)):
            raise ValueError(f"feature {name!r}: min and max must be numbers, got {lo!r}..{hi!r}")
        if (
            isinstance(num, bool)
            or not isinstance(num, int | np.integer)
            or not 1 <= num <= MAX_LINSPACE_VALUES
        ):
            raise ValueError(
                f"feature {name!r}: num must be an integer in 1..{MAX_LINSPACE_VALUES:,}, "
                f"got {num!r}"
            )
        if (num > 1 and not hi > lo) or hi < lo:  # num = 1 with max < min gave the value max
            raise ValueError(f"feature {name!r}: max must exceed min, got {lo}..{hi}")
        return cls(name, np.linspace(lo, hi, num), **kwargs)  # type: ignore[arg-type]

    def __len__(self) -> int:
        return len(self.values)

    @property
    def array(self) -> FloatArray:
        return np.asarray(self.values, dtype=np.float64)

    @property
    def span(self) -> float:
        """``max - min`` of the values (0 for a single value)."""
        return self.values[-1] - self.values[0]

    @property
    def step(self) -> float | None:
        """The smallest gap between grid values (None: continuous or a single value)."""
        if self.continuous or len(self.values) < 2:
            return None
        return float(np.min(np.diff(self.array)))

    def snap(self, value: float) -> float:
        """``value`` clipped to the range and, for a discrete feature, the nearest grid value."""
        if math.isnan(value):
            raise ValueError(f"feature {self.name!r}: a value must be a number, got nan")
        clipped = min(max(float(value), self.values[0]), self.values[-1])
        if self.continuous:
            return clipped
        # the values increase: bisect (O(log n)), the lower value on a tie
        k = bisect.bisect_left(self.values, clipped)
        if k == len(self.values):
            return self.values[-1]
        if k > 0 and clipped - self.values[k - 1] <= self.values[k] - clipped:
            return self.values[k - 1]
        return self.values[k]

    def _moved(self, value: float, move: str) -> float:
        """Where a coactive move from ``value`` points: a fraction of the range, before any
        clipping or snapping."""
        if move not in MOVES:
            raise ValueError(f"move must be one of {', '.join(MOVES)}; got {move!r}")
        fraction = self.coactive[1] if move.endswith("big") else self.coactive[0]
        sign = 1.0 if move.startswith("+") else -1.0
        return float(value) + sign * fraction * self.span

    def move_value(self, value: float, move: Move) -> float | None:
        """The value after a coactive move from ``value`` (a fraction of the range, clipped and
        snapped as :meth:`snap`), or ``None`` when it lands back on ``value``."""
        new = self.snap(self._moved(value, move))
        return None if new == value else new

    def move_clipped(self, value: float, move: str) -> bool:
        """Whether a coactive move from ``value`` would leave the feature's range, so that
        :meth:`move_value` clips it at the edge (to the edge, or back to ``value`` when it is
        there already): the subject asked for more than the range holds."""
        raw = self._moved(value, move)
        slack = 1e-9 * self.span  # rounding: a move that ends exactly on the edge stays in
        return raw > self.values[-1] + slack or raw < self.values[0] - slack

    def move(self, value_index: int, move: Move) -> int | None:
        """Value index after a coactive move, or ``None`` when it clips back to the same value."""
        if (
            isinstance(value_index, bool)
            or not isinstance(value_index, int | np.integer)
            or not 0 <= value_index < len(self.values)
        ):
            raise IndexError(
                f"feature {self.name!r}: value index must be an integer in "
                f"0..{len(self.values) - 1}, got {value_index!r}"
            )
        new = self.move_value(self.values[value_index], move)
        return None if new is None else self.values.index(new)


@dataclass(frozen=True)
class Space:
    """The Cartesian grid over ``features`` (C order: the last feature varies fastest)."""

    features: tuple[Feature, ...]
    _names: dict[str, int] = field(init=False, repr=False, compare=False)

    def __init__(self, features: Sequence[Feature]) -> None:
        feats = tuple(features)
        for k, f in enumerate(feats):
            if not isinstance(f, Feature):
                raise TypeError(f"features[{k}] must be a Feature, got {f!r}")
        if not feats:
            raise ValueError("a space needs at least one feature")
        names = [f.name for f in feats]
        if len(set(names)) != len(names):
            raise ValueError(f"feature names must be unique, got {names}")
        object.__setattr__(self, "features", feats)
        object.__setattr__(self, "_names", {n: i for i, n in enumerate(names)})

    def __len__(self) -> int:
        # exact: NumPy's product wrapped past 2**63 (64 two-valued features read as 0 actions)
        size = math.prod(self.shape)
        if size > sys.maxsize:
            raise OverflowError(
                f"the grid has {size:,} actions, more than len() can count ({sys.maxsize:,}): "
                "grid_size gives the number; a model needs a smaller grid or the line path"
            )
        return size

    def __iter__(self) -> Iterator[Feature]:
        return iter(self.features)

    @property
    def continuous(self) -> bool:
        """Whether any feature is continuous (then the space has no finite grid)."""
        return any(f.continuous for f in self.features)

    @property
    def grid_size(self) -> int | None:
        """The number of grid points as an exact integer (None for a continuous space)."""
        if self.continuous:
            return None
        return math.prod(len(f) for f in self.features)

    @property
    def shape(self) -> tuple[int, ...]:
        if self.continuous:
            names = ", ".join(f.name for f in self.features if f.continuous)
            raise ValueError(
                f"the space has continuous features ({names}) and no finite grid: it runs on "
                "the line path ([cospar] subspace = 'line')"
            )
        return tuple(len(f) for f in self.features)

    @property
    def index_shape(self) -> tuple[int, ...]:
        """:attr:`shape`, where NumPy can index the grid's actions by it (at most
        :data:`MAX_GRID_FEATURES` features: NumPy's "maximum supported dimension" otherwise)."""
        shape = self.shape
        if len(shape) > MAX_GRID_FEATURES:
            raise ValueError(
                f"the space has {len(shape)} features; a grid's actions are indexed over at most "
                f"{MAX_GRID_FEATURES} (one array axis each): it runs on the line path "
                "([cospar] subspace = 'line')"
            )
        return shape

    @property
    def words(self) -> str:
        """The space in a few words: ``15 x 10``, or ``continuous: a, b, c`` with no grid."""
        if self.continuous:
            return "continuous: " + ", ".join(self.names)
        return " x ".join(str(len(f)) for f in self.features)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(f.name for f in self.features)

    @property
    def ndim(self) -> int:
        return len(self.features)

    @cached_property
    def points(self) -> FloatArray:
        """All grid points, ``A x d``, row ``a`` is the point with flat index ``a``.

        A continuous space has no grid points (it returned the grid of its bounds before) and a
        grid past :data:`POINTS_LIMIT_ACTIONS` is refused: ValueError, before anything is
        allocated (:meth:`point` and :meth:`points_of` read single actions of any grid)."""
        shape = self._enumerable("points")
        out = np.empty((math.prod(shape), self.ndim))
        for j, f in enumerate(self.features):  # each column in place: no A-sized temporaries
            column = out[:, j].reshape(shape)
            column[...] = f.array.reshape([-1 if k == j else 1 for k in range(self.ndim)])
        return out

    @cached_property
    def multi_index(self) -> IntArray:
        """Per-feature value indices of every point, ``A x d`` (refused as :attr:`points`)."""
        shape = self._enumerable("multi_index")
        return np.stack(np.unravel_index(np.arange(math.prod(shape)), shape), axis=1).astype(
            np.intp
        )

    def _enumerable(self, what: str) -> tuple[int, ...]:
        """The grid's shape if ``what`` (an ``A x d`` array over every action) may be built."""
        shape = self.index_shape  # ValueError for a continuous space
        size = math.prod(shape)
        if size > POINTS_LIMIT_ACTIONS:
            raise ValueError(
                f"{what} would hold every one of the grid's {size:,} actions ({self.words}); "
                f"it is built for at most {POINTS_LIMIT_ACTIONS:,}: use point(index) or "
                "points_of(actions) for the actions wanted"
            )
        return shape

    def feature_index(self, name: str) -> int:
        try:
            return self._names[name]
        except KeyError:
            raise KeyError(
                f"unknown feature {name!r}; this space has {', '.join(self.names)}"
            ) from None

    def check_index(self, index: object) -> int:
        """``index`` as an ``int`` if it is a valid flat grid index, else ``IndexError``."""
        if isinstance(index, bool) or not isinstance(index, int | np.integer):
            raise TypeError(f"action index must be an integer, got {index!r}")
        i = int(index)
        if not 0 <= i < len(self):
            raise IndexError(f"action index {i} is {self._off} ({self._range_words()})")
        return i

    #: What an index past the actions is, in an error: off the grid (a point set: not a row)
    _off: ClassVar[str] = "off the grid"

    def _range_words(self) -> str:
        """The valid indices in words: ``0..A-1``, or none (an empty point set)."""
        return f"0..{len(self) - 1}" if len(self) else "it has no actions yet"

    def check_indices(self, values: ArrayLike, name: str = "actions") -> IntArray:
        """``values`` as a 1-D array of valid flat grid indices, else an error naming ``name``:
        ``TypeError`` for anything but integers (floats and bools included), ``IndexError`` for
        an index off the grid (negative ones too: they never wrap)."""
        size = len(self)
        items: Sequence[object] = values if isinstance(values, list | tuple) else ()
        if items and not {bool, np.bool_}.isdisjoint(map(type, items)):
            # NumPy reads [True, 3] as the integers [1, 3]
            k, v = next((k, v) for k, v in enumerate(items) if isinstance(v, bool | np.bool_))
            raise TypeError(f"{name}[{k}] = {v!r} is a bool, not a grid index")
        arr = np.asarray(values)
        if items and arr.dtype.kind not in "iu" and all(is_count(v) for v in items):
            # integers NumPy did not read as such: [3, 2**63] as floats, past 64 bits objects
            ints = [int(v) for v in items]  # type: ignore[call-overload]
            for k, i in enumerate(ints):
                if not 0 <= i < size:
                    raise IndexError(f"{name}[{k}] = {i} is {self._off} ({self._range_words()})")
            arr = np.asarray(ints, dtype=np.intp)
        if arr.ndim != 1:
            raise ValueError(
                f"{name} must be a 1-D sequence of grid indices, got shape {arr.shape}"
            )
        if arr.size and not np.issubdtype(arr.dtype, np.integer):
            raise TypeError(f"{name} must hold integer grid indices, got dtype {arr.dtype}")
        # the bounds on the values given (an unsigned index past 2**63 read as a negative one)
        bad = (arr < 0) | (arr >= size)
        if np.any(bad):
            raise IndexError(
                f"{name}[{int(np.flatnonzero(bad)[0])}] = {int(arr[bad][0])} is {self._off} "
                f"({self._range_words()})"
            )
        idx: IntArray = arr.astype(np.intp)
        return idx

    def points_of(self, actions: Sequence[int] | IntArray) -> FloatArray:
        """Feature values of ``actions`` (``k x d``) without building every grid point."""
        idx = np.asarray([self.check_index(a) for a in actions], dtype=np.intp)
        multi = np.unravel_index(idx, self.index_shape)
        cols = [f.array[m] for f, m in zip(self.features, multi, strict=True)]
        return np.stack(cols, axis=1) if cols else np.zeros((0, 0))

    def point(self, index: int) -> FloatArray:
        """Feature values of the action with flat index ``index`` (from the features' values:
        not every grid point, which a grid of 10^8 actions holds in gigabytes)."""
        out: FloatArray = self.points_of([index])[0]
        return out

    def values_of(self, index: int) -> dict[str, float]:
        """Feature name -> value of one action."""
        return dict(zip(self.names, self.point(index).tolist(), strict=True))

    def index(self, point: Sequence[float] | dict[str, float], *, atol: float = 1e-9) -> int:
        """Flat index of the grid point equal (within ``atol``) to ``point``."""
        coords = self._coords(point, atol)
        idx = []
        for f, v in zip(self.features, coords, strict=True):
            k = int(np.argmin(np.abs(f.array - v)))
            if abs(f.values[k] - v) > atol:
                raise ValueError(f"{f.name} = {v} is not a grid value of this space")
            idx.append(k)
        return int(np.ravel_multi_index(tuple(idx), self.index_shape))

    def _coords(self, point: Sequence[float] | dict[str, float], atol: float) -> list[float]:
        """A point's coordinates in feature order (with ``atol``, the tolerance it is matched
        with, a finite number >= 0: NaN matched any point): every feature once (by name in a dict,
        no other key), each a number (NaN matched grid value 0 before)."""
        if not (is_number(atol) and 0 <= atol < math.inf):
            raise ValueError(f"atol must be a finite number >= 0, got {atol!r}")
        if isinstance(point, dict):
            missing = set(self.names) - set(point)
            if missing:
                raise KeyError(f"point is missing features {sorted(missing)}")
            unknown = set(point) - set(self.names)
            if unknown:
                raise KeyError(
                    f"point names unknown features {sorted(map(str, unknown))}; this space has "
                    f"{', '.join(self.names)}"
                )
            coords = [float(point[n]) for n in self.names]
        else:
            coords = [float(v) for v in point]
        if len(coords) != self.ndim:
            raise ValueError(f"point has {len(coords)} coordinates, space has {self.ndim}")
        for name, v in zip(self.names, coords, strict=True):
            if math.isnan(v):
                raise ValueError(f"{name} = nan is not a value")
        return coords

    def feature_number(self, feature: str | int) -> int:
        """A feature's position from its name or its number (``0..d-1``; no bools)."""
        if isinstance(feature, str):
            return self.feature_index(feature)
        if isinstance(feature, bool) or not isinstance(feature, int | np.integer):
            raise TypeError(f"feature must be a name or a number, got {feature!r}")
        if not 0 <= feature < self.ndim:
            raise IndexError(f"feature number {feature} out of range (0..{self.ndim - 1})")
        return int(feature)

    def coactive_move(self, index: int, feature: str | int, move: Move) -> int | None:
        """Flat index after moving one feature of action ``index``; ``None`` if it clips back."""
        i = self.check_index(index)
        f = self.feature_number(feature)
        multi = [int(m) for m in np.unravel_index(i, self.index_shape)]
        new = self.features[f].move(multi[f], move)
        if new is None:
            return None
        multi[f] = new
        return int(np.ravel_multi_index(tuple(multi), self.index_shape))

    def describe(self, index: int) -> str:
        """Human-readable feature values (4 significant digits), e.g. ``step_length=0.13 m``."""
        parts = []
        for f, v in zip(self.features, self.point(index), strict=True):
            unit = f" {f.unit}" if f.unit else ""
            parts.append(f"{f.name}={v:.4g}{unit}")
        return ", ".join(parts)
