"""Objectives of the paper's simulations, shipped with the package.

- The 100 synthetic 2-D objectives of Fig. 4 (Section "Optimizing Synthetic Two-Dimensional
  Functions"): samples of a GP (mean 0.5, variance 0.1, lengthscale 0.15) on the 30 x 30 grid
  ``x = y = linspace(0, 1, 30)``, from the authors' public code (MIT licence, in
  ``data/cospar2d/LICENSE``).
  ``objectives[k, i, j]`` is the utility at ``(x_i, y_j)``, higher is better; flattened in C order
  it matches the ``synthetic-2d`` config's grid.
- The compass-gait biped's cost of transport over step length (Fig. 2), as the authors' code
  has it: a 5th-degree polynomial fit in metres, lower is better (``design/algorithm.md``).

Notation: ``K`` objectives over ``A = 900`` grid points; COT is dimensionless (J / (N m)).
"""

from __future__ import annotations

from importlib import resources

import numpy as np
from numpy.typing import ArrayLike

from gaitpref.space import FloatArray

#: ``numpy.polyval`` coefficients (highest degree first) of the authors' COT fit, x in metres.
COT_COEFFICIENTS: tuple[float, ...] = (-660.1898, 556.5202, -186.4672, 34.1877, -3.4090, 0.1602)

_DATA = "cospar2d"


def paper_objectives() -> FloatArray:
    """The paper's 100 synthetic objectives, shape ``(100, 30, 30)`` (a fresh read-only copy)."""
    with (resources.files("gaitpref") / "data" / _DATA / "objectives.npy").open("rb") as fh:
        arr = np.load(fh, allow_pickle=False)
    out = np.asarray(arr, dtype=np.float64)
    if out.shape != (100, 30, 30):
        raise ValueError(f"shipped objectives.npy has shape {out.shape}, expected (100, 30, 30)")
    out.setflags(write=False)
    return out


def published_curves_text() -> str:
    """The text of the shipped ``published_curves.csv`` (the authors' 100 runs per setting)."""
    return (resources.files("gaitpref") / "data" / _DATA / "published_curves.csv").read_text(
        encoding="utf-8"
    )


def compass_gait_cot(step_length: ArrayLike) -> FloatArray:
    """The authors' compass-gait COT at ``step_length`` (metres), fitted on [0.08, 0.18] m."""
    x = np.asarray(step_length, dtype=np.float64)
    return np.asarray(np.polyval(COT_COEFFICIENTS, x), dtype=np.float64)
