"""The compass-gait objective from the project's own HZD gaits: COT over step length.

The gait library (:mod:`gaitpref.gaits`; ``docs/gaits.md``, "COT over step length") optimises
one gait per step length at a fixed forward speed (0.2 m/s in the paper) and records its
mechanical cost of transport.
This module turns that into the objective of the compass-gait study:

- :func:`build_cot_curve`: build a fixed-speed library on the study's step lengths
  (``gaitpref.gaits.build.build_library``) and read its curve
  (``gaitpref.gaits.study.cot_over_step_length``);
- :func:`read_cot_curve`: read a saved library (``.json``, through ``GaitLibrary.load``), or a
  plain export: ``.csv`` with a header naming ``step_length`` (m) and ``cot`` (optionally
  ``feasible``: true/false/1/0), or ``.npz`` with those arrays.
- :func:`library_objective`: the COT on the study's grid.  Infeasible gaits are dropped and said
  so; if the library's step lengths are not the grid's, the study runs on the library's own step
  lengths within the grid's range, which the returned note says.

Every problem raises ``ValueError`` naming the file and the field.

Notation: ``n`` step lengths (m); COT dimensionless; ``feasible`` boolean, all ``(n,)``.
"""

from __future__ import annotations

import csv
import io
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from gaitpref.gaits.build import build_library
from gaitpref.gaits.library import GaitLibrary
from gaitpref.gaits.study import PAPER_SPEED, cot_over_step_length
from gaitpref.npz_sizes import npz_problem
from gaitpref.space import Feature, FloatArray, Space

CotCurveArrays = tuple[FloatArray, FloatArray, NDArray[np.bool_]]

#: the most bytes a ``.csv`` or ``.npz`` COT curve file may hold, and an ``.npz``'s arrays
#: unpacked (a curve is a few hundred step lengths: kilobytes); a ``.json`` library takes the
#: library's bound (``gaitpref.gaits.library_io.MAX_LIBRARY_BYTES``)
MAX_CURVE_BYTES = 64 * 2**20

_TRUE = {"true", "1", "yes", "y", "t"}
_FALSE = {"false", "0", "no", "n", "f"}


def build_cot_curve(
    step_lengths: FloatArray,
    speed: float = PAPER_SPEED,
    n_jobs: int = 1,
    save: str | Path | None = None,
) -> CotCurveArrays:
    """Optimise a gait per step length at ``speed``; optionally save the library to ``save``."""
    lib = build_library([float(v) for v in step_lengths], speed=speed, n_jobs=n_jobs)
    if save is not None:
        lib.save(save)
    curve = cot_over_step_length(lib)
    return curve.step_length, curve.cot, np.asarray(curve.feasible, dtype=bool)


def read_cot_curve(path: str | Path) -> CotCurveArrays:
    """``(step_length, cot, feasible)`` from a library file or export, sorted by step length."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such gait library file")
    if path.suffix == ".json":
        try:
            curve = cot_over_step_length(GaitLibrary.load(path, allow_infeasible=True))
        except ValueError as exc:  # GaitLibraryError is a ValueError
            raise ValueError(f"gait library {path}: {exc}") from None
        raw: dict[str, Any] = {
            "step_length": curve.step_length,
            "cot": curve.cot,
            "feasible": curve.feasible,
        }
    elif path.suffix in (".csv", ".npz"):
        try:
            raw = _from_csv(path) if path.suffix == ".csv" else _from_npz(path)
        except (OSError, ValueError, EOFError, csv.Error, zipfile.BadZipFile) as exc:
            # a truncated or foreign .npz, object arrays, bytes that are not UTF-8
            if str(exc).startswith(f"{path}: "):
                raise
            raise ValueError(f"{path}: cannot be read as {path.suffix[1:]} ({exc})") from None
    else:
        raise ValueError(f"{path}: a gait library must be .json (or a .csv/.npz export)")
    return _curve(raw, path)


def library_objective(
    curve: CotCurveArrays, grid: Space, source: str = "the library"
) -> tuple[Space, FloatArray, str]:
    """The curve's COT on ``grid`` (a 1-D step-length space), or on its own step lengths."""
    x, cot, feasible = curve
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
        return grid, np.asarray(cot, dtype=np.float64), "; ".join(notes)
    keep = (x >= feature.values[0] - 1e-9) & (x <= feature.values[-1] + 1e-9)
    if keep.sum() < 2:
        raise ValueError(
            f"{source}: fewer than 2 feasible gaits with step length in "
            f"[{feature.values[0]}, {feature.values[-1]}] m"
        )
    x, cot = x[keep], cot[keep]
    space = Space([Feature(feature.name, x, feature.unit, feature.coactive, feature.words)])
    notes.append(
        f"{source}'s {x.size} step lengths differ from the {len(feature)}-point grid: the study "
        "runs on the library's own step lengths"
    )
    return space, np.asarray(cot, dtype=np.float64), "; ".join(notes)


def _curve(raw: dict[str, Any], path: Path) -> CotCurveArrays:
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


def _flag(value: object, path: Path) -> bool:
    if isinstance(value, bool | np.bool_):
        return bool(value)
    text = str(value).strip().lower()
    if text in _TRUE:
        return True
    if text in _FALSE:
        return False
    raise ValueError(f"{path}: feasible must be true/false, got {value!r}")


def _check_file_size(path: Path) -> None:
    size = path.stat().st_size
    if size > MAX_CURVE_BYTES:
        raise ValueError(
            f"{path}: holds {size:,} bytes, more than the {MAX_CURVE_BYTES:,} a COT curve file "
            "may; it was not read"
        )


def _from_npz(path: Path) -> dict[str, Any]:
    _check_file_size(path)
    z = np.load(path, allow_pickle=False)
    if not isinstance(z, np.lib.npyio.NpzFile):
        raise ValueError("one array, not an archive of step_length, cot, ...")
    with z:
        _check_unpacked(z, path)
        return {k: z[k].tolist() for k in z.files}


def _check_unpacked(data: np.lib.npyio.NpzFile, path: Path) -> None:
    """Refuse an archive whose arrays unpack past :data:`MAX_CURVE_BYTES` (a small compressed
    file, a "zip bomb"), or whose header claims more than its member holds (allocated whole
    before it failed), before any array is read."""
    problem = npz_problem(data, MAX_CURVE_BYTES, "a COT curve file")
    if problem is not None:
        raise ValueError(f"{path}: {problem}; it was not read")


def _from_csv(path: Path) -> dict[str, list[str]]:
    _check_file_size(path)
    with path.open("rb") as raw_file:
        data = raw_file.read(MAX_CURVE_BYTES + 1)
    if len(data) > MAX_CURVE_BYTES:  # grown since it was measured
        _check_file_size(path)
        raise ValueError(f"{path}: more than {MAX_CURVE_BYTES:,} bytes; it was not read")
    with io.StringIO(data.decode("utf-8"), newline="") as fh:
        reader = csv.DictReader(fh)
        if reader.fieldnames is None:
            raise ValueError(f"{path}: empty file")
        rows = list(reader)
    return {k.strip(): [r[k] for r in rows] for k in reader.fieldnames}
