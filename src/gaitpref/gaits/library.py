"""A gait library: one optimized gait per point of a parameter grid (the paper's "Gait Library").

The grid's axes are, in this order, ``step_length`` (always), ``step_duration`` (unless the
library is built at a fixed forward ``speed``, when each gait's duration is ``L / v``) and
optionally ``step_width``.  **The planar compass gait has no step width**: a width axis is carried
as a label only, every width shares the gait of its (length, duration), and the dynamics ignore it.

Flat grid indices follow :class:`gaitpref.Space`: C order over the axes as declared, the last axis
fastest, so ``library.space().index(point)`` and ``library.index(...)`` agree.  File format:
:mod:`gaitpref.gaits.library_io`.

Notation: ``A`` grid points, ``shape`` the per-axis value counts, ``prod(shape) = A``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import NamedTuple

import numpy as np

from gaitpref.errors import GaitLibraryError
from gaitpref.gaits.gait import Gait, HZDSettings
from gaitpref.gaits.params import CompassGaitParams
from gaitpref.space import Feature, FloatArray, Space


class AxisSpec(NamedTuple):
    unit: str
    coactive: tuple[float, float]
    words: tuple[str, str]
    letter: str


AXES: dict[str, AxisSpec] = {
    "step_length": AxisSpec("m", (0.1, 0.2), ("longer", "shorter"), "L"),
    "step_duration": AxisSpec("s", (0.1, 0.2), ("slower", "faster"), "T"),
    "step_width": AxisSpec("m", (0.2, 0.4), ("wider", "narrower"), "W"),
}
DURATION_RTOL = 1e-4


def check_axes(axes: tuple[tuple[str, tuple[float, ...]], ...], speed: float | None) -> None:
    """Raise :class:`GaitLibraryError` unless ``axes`` and ``speed`` describe a valid grid."""
    names = [name for name, _ in axes]
    known = list(AXES)
    if not names or names[0] != "step_length":
        raise GaitLibraryError(f"axes must start with step_length, got {names}")
    if any(n not in AXES for n in names) or names != sorted(names, key=known.index):
        raise GaitLibraryError(f"axes must be a subsequence of {known} in that order, got {names}")
    if len(set(names)) != len(names):
        raise GaitLibraryError(f"axes repeat a name: {names}")
    if ("step_duration" in names) == (speed is not None):
        raise GaitLibraryError(
            "a library has a step_duration axis or a fixed speed, not both/neither"
        )
    if speed is not None and not (math.isfinite(speed) and speed > 0):
        raise GaitLibraryError(f"speed must be a positive number, got {speed!r}")
    for name, values in axes:
        arr = np.asarray(values, dtype=np.float64)
        if arr.size == 0 or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
            raise GaitLibraryError(f"axis {name}: values must be positive and finite, got {values}")
        if np.any(np.diff(arr) <= 0):
            raise GaitLibraryError(f"axis {name}: values must be strictly increasing")
        if len({f"{v:.3f}" for v in arr}) != arr.size:  # an id shows each value so
            raise GaitLibraryError(
                f"axis {name}: values too close to give distinct gait ids (ids show 3 decimals)"
            )


def grid_size(shape: Sequence[int]) -> int:
    """The number of points of a grid of ``shape``, in exact integer arithmetic (``np.prod``
    of int64 wrapped around silently: a grid of ``(2**22,) * 3`` had 0 points)."""
    return math.prod(int(n) for n in shape)


def feasible_gait_problem(gait: Gait) -> str | None:
    """What makes a gait flagged feasible unusable (non-finite numbers, ``delta^2`` outside
    ``(0, 1)``), or None: a library, and a gait cache, refuse such a gait."""
    numbers = [gait.step_duration, gait.cot, gait.delta_squared, gait.phase_start, gait.phase_end]
    if not (np.all(np.isfinite(gait.alpha)) and np.all(np.isfinite(gait.orbit_state))):
        return "feasible gait with non-finite coefficients or orbit"
    if not all(math.isfinite(v) for v in numbers) or not 0 < gait.delta_squared < 1:
        return "feasible gait with bad cot/delta^2/duration/phase"
    return None


#: the longest gait id a session takes (a library's, a generator's): ids are shown on every
#: trial, stored in each event that names a gait and in the session's record
MAX_GAIT_ID = 200


def gait_id_of(values: Mapping[str, float], speed: float | None) -> str:
    """The id of the gait with these axis values (in axis order), e.g. ``L0.130-T0.950``, or
    ``L0.130-V0.200`` at a fixed ``speed``; a library and gaits made on demand share it."""
    parts = []
    for name, value in values.items():
        parts.append(f"{AXES[name].letter}{value:.3f}")
        if name == "step_length" and speed is not None:
            parts.append(f"V{speed:.3f}")
    return "-".join(parts)


@dataclass(frozen=True, eq=False)
class GaitLibrary:
    """Gaits over a grid, with the model and formulation that produced them."""

    params: CompassGaitParams
    settings: HZDSettings
    axes: tuple[tuple[str, tuple[float, ...]], ...]
    gaits: tuple[Gait, ...]
    speed: float | None = None

    def __post_init__(self) -> None:
        axes = tuple((str(n), tuple(float(v) for v in vals)) for n, vals in self.axes)
        object.__setattr__(self, "axes", axes)
        object.__setattr__(self, "gaits", tuple(self.gaits))
        check_axes(axes, self.speed)
        if len(self.gaits) != self.size:  # the exact count: len() cannot hold past 2**63 - 1
            raise GaitLibraryError(
                f"the grid {self.shape} has {self.size} points but the library has "
                f"{len(self.gaits)} gaits"
            )
        ids = [self.gait_id(i) for i in range(len(self))]
        if len(set(ids)) != len(ids):
            raise GaitLibraryError("grid values are too close to give distinct gait ids")
        for i, gait in enumerate(self.gaits):
            self._check_gait(i, gait)

    def _check_gait(self, i: int, gait: Gait) -> None:
        where = f"gait {i} ({self.gait_id(i)})"
        point = self.parameters(i)
        if not math.isclose(gait.step_length, point["step_length"], rel_tol=1e-9):
            raise GaitLibraryError(
                f"{where}: step length {gait.step_length} does not match the grid's "
                f"{point['step_length']}"
            )
        if gait.degree != self.settings.degree or gait.alpha.shape != (1, gait.degree + 1):
            raise GaitLibraryError(
                f"{where}: alpha has shape {gait.alpha.shape}, "
                f"expected (1, {self.settings.degree + 1})"
            )
        if gait.orbit_state.shape != (4,):
            raise GaitLibraryError(
                f"{where}: orbit_state has shape {gait.orbit_state.shape}, expected (4,)"
            )
        if not gait.feasible:
            return
        problem = feasible_gait_problem(gait)
        if problem is not None:
            raise GaitLibraryError(f"{where}: {problem}")
        target = point.get("step_duration", point["step_length"] / (self.speed or math.nan))
        if not math.isclose(gait.step_duration, target, rel_tol=DURATION_RTOL):
            raise GaitLibraryError(
                f"{where}: step duration {gait.step_duration:.6f} s, the grid asks {target:.6f} s"
            )

    # -- grid ------------------------------------------------------------------------------
    @property
    def names(self) -> tuple[str, ...]:
        return tuple(name for name, _ in self.axes)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(values) for _, values in self.axes)

    @property
    def size(self) -> int:
        """The grid's number of points, exactly (``np.prod`` wrapped around past ``2**63``)."""
        return grid_size(self.shape)

    def __len__(self) -> int:
        return self.size

    def features(self) -> list[Feature]:
        """The grid's axes as :class:`gaitpref.Feature` (units, coactive fractions, words)."""
        out = []
        for name, values in self.axes:
            spec = AXES[name]
            out.append(Feature(name, values, spec.unit, spec.coactive, spec.words))
        return out

    @cached_property
    def _space(self) -> Space:
        return Space(self.features())

    def space(self) -> Space:
        """The grid as a :class:`gaitpref.Space` (same flat indices)."""
        return self._space

    def check_index(self, index: object) -> int:
        if isinstance(index, bool) or not isinstance(index, int | np.integer):
            raise GaitLibraryError(f"gait index must be an integer, got {index!r}")
        if not 0 <= int(index) < len(self):
            raise GaitLibraryError(f"gait index {index} is off the grid (0..{len(self) - 1})")
        return int(index)

    def parameters(self, index: int) -> dict[str, float]:
        """Grid values of gait ``index``, by axis name."""
        multi = np.unravel_index(self.check_index(index), self.shape)
        return {name: values[int(k)] for (name, values), k in zip(self.axes, multi, strict=True)}

    def index(self, point: Sequence[float] | dict[str, float] | None = None, **named: float) -> int:
        """Flat index of the grid point with these values (exact grid values, within 1e-9)."""
        if point is not None and named:
            raise GaitLibraryError("give the point positionally or by name, not both")
        query: Sequence[float] | dict[str, float] = named if point is None else point
        try:
            return self._space.index(query)
        except (KeyError, ValueError) as exc:
            raise GaitLibraryError(f"no gait at {query!r}: {exc}") from None

    def gait(self, index: int) -> Gait:
        return self.gaits[self.check_index(index)]

    def lookup(self, **named: float) -> Gait:
        """The gait at the grid point with these named values."""
        return self.gaits[self.index(dict(named))]

    def gait_id(self, index: int) -> str:
        """A stable short id from the grid values, e.g. ``L0.130-T0.950`` (``-V0.200`` at a fixed
        speed, ``-W0.270`` with a width label)."""
        return gait_id_of(self.parameters(index), self.speed)

    def index_of_id(self, gait_id: str) -> int:
        for i in range(len(self)):
            if self.gait_id(i) == gait_id:
                return i
        raise GaitLibraryError(f"no gait with id {gait_id!r} (e.g. {self.gait_id(0)!r})")

    # -- summaries ---------------------------------------------------------------------------
    def cot_grid(self) -> FloatArray:
        """COT of every gait, shaped like the grid (``nan`` where a gait is infeasible)."""
        cot = [g.cot if g.feasible else math.nan for g in self.gaits]
        return np.asarray(cot, dtype=np.float64).reshape(self.shape)

    def infeasible(self) -> list[int]:
        return [i for i, g in enumerate(self.gaits) if not g.feasible]

    # -- files -------------------------------------------------------------------------------
    def save(self, path: str | Path) -> None:
        from gaitpref.gaits.library_io import save_library

        save_library(self, path)

    @classmethod
    def load(cls, path: str | Path, *, allow_infeasible: bool = False) -> GaitLibrary:
        from gaitpref.gaits.library_io import load_library

        return load_library(path, allow_infeasible=allow_infeasible)
