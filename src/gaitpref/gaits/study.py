"""COT over step length at a fixed forward speed: the paper's compass-gait objective.

Section "Simulation Results", Fig. 5 (left): mechanical COT (Reher et al. 2016, eqs. 17-18) of
HZD gaits for several step lengths, each at a forward hip speed of 0.2 m/s, synthesized by
single-point shooting.  :func:`cot_over_step_length` reads that curve off a fixed-speed library;
:func:`compass_gait_cot` builds the library first.  A simulated user (``bench compass-gait
--objective hzd``) can compare gaits by this COT.

Notation: ``n`` step lengths; every array is ``(n,)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gaitpref.errors import GaitLibraryError
from gaitpref.gaits.build import build_library
from gaitpref.gaits.gait import HZDSettings
from gaitpref.gaits.library import (
    GaitLibrary,
)
from gaitpref.gaits.params import CompassGaitParams
from gaitpref.space import FloatArray

PAPER_STEP_LENGTHS: tuple[float, ...] = tuple(float(v) for v in np.linspace(0.08, 0.18, 15))
PAPER_SPEED = 0.2


@dataclass(frozen=True, eq=False)
class CotCurve:
    """COT per step length at one speed (``nan`` where no feasible gait exists)."""

    step_length: FloatArray
    cot: FloatArray
    feasible: NDArray[np.bool_]
    speed: float

    @property
    def best_step_length(self) -> float:
        """Step length of least COT among the feasible gaits."""
        if not self.feasible.any():
            raise GaitLibraryError("no feasible gait on this curve")
        return float(self.step_length[int(np.nanargmin(self.cot))])


def cot_over_step_length(library: GaitLibrary) -> CotCurve:
    """The COT curve of a library built at a fixed speed over step length.

    A step-width axis (a label) is allowed and must not change the COT; a step-duration axis is
    not (build the library with ``speed=``).
    """
    if library.speed is None:
        raise GaitLibraryError(
            "COT over step length needs a library built at a fixed speed "
            "(this one has a step_duration axis)"
        )
    grid = library.cot_grid().reshape(library.shape[0], -1)
    cot = grid[:, 0]
    if not np.allclose(grid, cot[:, None], equal_nan=True):
        raise GaitLibraryError(
            "COT varies along the step_width label axis; the library is inconsistent"
        )
    lengths = np.asarray(library.axes[0][1], dtype=np.float64)
    return CotCurve(lengths, cot.copy(), np.isfinite(cot), float(library.speed))


def compass_gait_cot(
    step_lengths: Sequence[float] = PAPER_STEP_LENGTHS,
    speed: float = PAPER_SPEED,
    *,
    params: CompassGaitParams | None = None,
    settings: HZDSettings | None = None,
    n_jobs: int = 1,
) -> CotCurve:
    """Build a fixed-speed library over ``step_lengths`` and return its COT curve."""
    if not (math.isfinite(speed) and speed > 0):
        raise ValueError(f"speed must be positive, got {speed}")
    lib = build_library(step_lengths, speed=speed, params=params, settings=settings, n_jobs=n_jobs)
    return cot_over_step_length(lib)
