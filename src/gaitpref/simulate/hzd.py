"""Adapter: the cost of transport over step length from an HZD gait library file.

The project's gait library (``gaitpref.gaits``, ``design/gaits.md``) stores per gait its step
length, COT and feasibility.  Until its reader is integrated here, this adapter reads the
*documented expectation* of what a library built at 0.2 m/s exports:

- ``.csv`` with a header naming ``step_length`` (m) and ``cot``, optionally ``feasible``
  (``true``/``false``/``1``/``0``), one gait per row;
- ``.npz`` with arrays ``step_length`` and ``cot`` (and optionally ``feasible``);
- ``.json``: a gait library file as ``gaitpref.gaits`` writes it (schema 1: ``"speed"`` and
  ``"gaits"``, each gait with ``"parameters": {"step_length": ...}``, ``"cot"``, ``"feasible"``;
  a step-width label axis repeats each step length with the same COT), or an object with lists
  ``step_length`` and ``cot`` (optionally ``feasible``).  When ``gaitpref.gaits.study`` is
  installed (the gait library's branch), its ``cot_over_step_length(GaitLibrary.load(path))``
  reads JSON libraries instead, so the two cannot drift apart.

Infeasible gaits are dropped (and said so).  If the library's step lengths are the grid's, the
grid is kept; otherwise the study runs on the library's own step lengths within the grid's range,
which the returned note says.  Every problem raises ``ValueError`` naming the file and the field.
"""

from __future__ import annotations

import csv
import importlib
import json
from pathlib import Path
from typing import Any

import numpy as np

from gaitpref.space import Feature, FloatArray, Space

_TRUE = {"true", "1", "yes", "y", "t"}
_FALSE = {"false", "0", "no", "n", "f"}


def read_cot_curve(path: str | Path) -> tuple[FloatArray, FloatArray, np.ndarray[Any, Any]]:
    """``(step_length, cot, feasible)`` from a library export, sorted by step length."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such gait library file")
    if path.suffix == ".csv":
        raw = _from_csv(path)
    elif path.suffix == ".npz":
        with np.load(path, allow_pickle=False) as z:
            raw = {k: z[k].tolist() for k in z.files}
    elif path.suffix == ".json":
        curve = _from_gait_library(path)
        raw = _from_json(path) if curve is None else curve
    else:
        raise ValueError(f"{path}: a gait library export must be .csv, .npz or .json")
    for key in ("step_length", "cot"):
        if key not in raw:
            raise ValueError(f"{path}: missing field {key!r} (have {', '.join(sorted(raw))})")
    try:
        x = np.asarray(raw["step_length"], dtype=np.float64).ravel()
        cot = np.asarray(raw["cot"], dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"{path}: step_length and cot must be numbers") from None
    feasible = np.asarray(
        [_flag(v, path) for v in raw.get("feasible", [True] * x.size)], dtype=bool
    ).ravel()
    if not x.size == cot.size == feasible.size or x.size == 0:
        raise ValueError(
            f"{path}: step_length ({x.size}), cot ({cot.size}) and feasible ({feasible.size}) "
            "must be non-empty and of equal length"
        )
    order = np.argsort(x, kind="stable")
    x, cot, feasible = x[order], cot[order], feasible[order]
    if np.any(np.diff(x) <= 0):
        raise ValueError(f"{path}: step lengths repeat")
    if not np.all(np.isfinite(x)) or not np.all(np.isfinite(cot[feasible])):
        raise ValueError(f"{path}: step_length and the feasible gaits' cot must be finite")
    return x, cot, feasible


def library_objective(path: str | Path, grid: Space) -> tuple[Space, FloatArray, str]:
    """The library's COT on ``grid`` (a 1-D step-length space), or on its own step lengths."""
    x, cot, feasible = read_cot_curve(path)
    notes = []
    if not np.all(feasible):
        notes.append(
            f"dropped {int((~feasible).sum())} infeasible gait(s) at step length(s) "
            + ", ".join(f"{v:.4f}" for v in x[~feasible])
            + " m"
        )
        x, cot = x[feasible], cot[feasible]
    feature = grid.features[0]
    if x.size == len(feature) and np.allclose(x, feature.array, atol=1e-6, rtol=0):
        space = grid
    else:
        keep = (x >= feature.values[0] - 1e-9) & (x <= feature.values[-1] + 1e-9)
        if keep.sum() < 2:
            raise ValueError(
                f"{path}: fewer than 2 feasible gaits with step length in "
                f"[{feature.values[0]}, {feature.values[-1]}] m"
            )
        x, cot = x[keep], cot[keep]
        space = Space([Feature(feature.name, x, feature.unit, feature.coactive, feature.words)])
        notes.append(
            f"the library's {x.size} step lengths differ from the {len(feature)}-point grid: "
            "the study runs on the library's own step lengths"
        )
    return space, np.asarray(cot, dtype=np.float64), "; ".join(notes)


def _flag(value: object, path: Path) -> bool:
    if isinstance(value, bool | np.bool_):
        return bool(value)
    text = str(value).strip().lower()
    if text in _TRUE:
        return True
    if text in _FALSE:
        return False
    raise ValueError(f"{path}: feasible must be true/false, got {value!r}")


def _from_csv(path: Path) -> dict[str, list[str]]:
    with path.open(encoding="utf-8", newline="") as fh:
        reader = csv.DictReader(fh)
        if reader.fieldnames is None:
            raise ValueError(f"{path}: empty file")
        rows = list(reader)
    return {k.strip(): [r[k] for r in rows] for k in reader.fieldnames}


def _from_gait_library(path: Path) -> dict[str, Any] | None:
    """The gait library's own reader, when its package is installed; else None."""
    try:
        study = importlib.import_module("gaitpref.gaits.study")
        library = importlib.import_module("gaitpref.gaits.library")
    except ImportError:
        return None
    try:
        lib = library.GaitLibrary.load(path, allow_infeasible=True)
        curve = study.cot_over_step_length(lib)
    except ValueError as exc:  # GaitLibraryError is a ValueError
        raise ValueError(f"{path}: {exc}") from None
    return {"step_length": curve.step_length, "cot": curve.cot, "feasible": curve.feasible}


def _from_json(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not valid JSON: {exc}") from None
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a JSON object")
    if not isinstance(data.get("gaits"), list):
        return dict(data)
    if "speed" in data and data["speed"] is None:
        raise ValueError(
            f"{path}: COT over step length needs a library built at a fixed speed "
            "(this one has a step_duration axis)"
        )
    by_length: dict[float, tuple[object, object]] = {}
    for k, g in enumerate(data["gaits"]):
        if not isinstance(g, dict):
            raise ValueError(f"{path}: gaits[{k}] must be an object")
        params = g.get("parameters", g)
        if not isinstance(params, dict) or "step_length" not in params or "cot" not in g:
            raise ValueError(f"{path}: gaits[{k}] needs step_length (or parameters) and cot")
        x = float(params["step_length"])
        entry = (g["cot"], g.get("feasible", True))
        if x in by_length and by_length[x] != entry:
            raise ValueError(f"{path}: gaits at step length {x} differ in cot or feasibility")
        by_length[x] = entry
    return {
        "step_length": list(by_length),
        "cot": [np.nan if c is None else c for c, _ in by_length.values()],
        "feasible": [f for _, f in by_length.values()],
    }
