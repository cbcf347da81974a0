"""Data shipped with gaitpref: the CoSpar authors' 2-D benchmark (MIT; see cospar2d/LICENSE).

``cospar2d/objectives.npy`` holds the 100 synthetic objectives of the paper's Fig. 4, shape
``(100, 30, 30)``: ``objectives[k, i, j]`` is the utility at ``(x_i, y_j)``,
``x = y = linspace(0, 1, 30)`` (flat index ``30 i + j``, the C order of
``configs/synthetic-2d.toml``).  ``cospar2d/published_curves.csv`` holds, per setting and trial, the
mean normalised objective of the authors' 100 stored runs and its standard error.  Both were
converted from the authors' public repository (ernovoseller/CoSpar); see ``cospar2d/README.md``.
"""

from __future__ import annotations

import csv
from importlib import resources

import numpy as np

from gaitpref.space import FloatArray

_ROOT = resources.files("gaitpref") / "data" / "cospar2d"


def paper_objectives() -> FloatArray:
    """The authors' 100 objectives, ``(100, 30, 30)`` float64, higher is better."""
    with (_ROOT / "objectives.npy").open("rb") as fh:
        arr: FloatArray = np.load(fh, allow_pickle=False)
    if arr.shape != (100, 30, 30):
        raise ValueError(f"packaged objectives have shape {arr.shape}, expected (100, 30, 30)")
    return arr


def published_curves() -> dict[str, tuple[FloatArray, FloatArray]]:
    """Setting name -> (mean normalised objective, standard error), each of length 150."""
    rows: dict[str, list[tuple[int, float, float]]] = {}
    with (_ROOT / "published_curves.csv").open("r", encoding="utf-8") as fh:
        for row in csv.DictReader(fh):
            rows.setdefault(row["setting"], []).append(
                (
                    int(row["trial"]),
                    float(row["mean_normalized_objective"]),
                    float(row["standard_error"]),
                )
            )
    out = {}
    for name, items in rows.items():
        items.sort()
        out[name] = (np.array([m for _, m, _ in items]), np.array([s for _, _, s in items]))
    return out
