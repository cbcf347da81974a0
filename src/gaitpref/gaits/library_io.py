"""The gait library's file format: one JSON document, readable without gaitpref.

Schema version 1 (``docs/gaits.md`` has the full description)::

    {"format": "gaitpref-gait-library", "schema_version": 1, "created_by": "gaitpref 0.1.0",
     "model": {"name": "compass_gait", "parameters": {hip_mass, leg_mass, leg_com, leg_length,
               gravity}},
     "formulation": {HZDSettings fields..., "phase_variable": "stance_leg_angle",
                     "outputs": ["hip_angle"], "objective": "mechanical_cot"},
     "speed": 0.2 | null,
     "axes": [{"name": "step_length", "unit": "m", "values": [...]}, ...],
     "grid_order": "C",
     "gaits": [{"index", "id", "parameters": {axis: value}, "degree", "alpha": [[M + 1 numbers]],
                "phase_start", "phase_end", "step_duration", "orbit_state": [phi1, q2, phi1d, q2d],
                "cot", "delta_squared", "feasible", "solver_status", "solver_message",
                "min_normal_force", "max_friction_ratio"}, ...]}

Gaits are listed in flat grid order (C order over ``axes``); non-finite numbers are ``null``.
Loading checks the format tag, schema version, every field's type and shape and, unless told
otherwise, that every gait is feasible; each failure raises :class:`GaitLibraryError` naming the
file and the field.

Notation: ``M`` Bezier degree.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from gaitpref.atomic import write_text_atomic
from gaitpref.errors import GaitLibraryError
from gaitpref.gaits.gait import Gait, HZDSettings
from gaitpref.gaits.library import (
    AXES,
    MAX_GAIT_ID,
    GaitLibrary,
    grid_size,
)
from gaitpref.gaits.params import CompassGaitParams

FORMAT = "gaitpref-gait-library"
SCHEMA_VERSION = 1
#: the most bytes of a gait library file read (about 1 kB a gait): a larger one is refused,
#: naming the file, before it is read whole (the export's copy of a library and the console's
#: upload take the same bound: ``gaitpref.sessions.export``)
MAX_LIBRARY_BYTES = 256 * 2**20
#: the longest solver message :func:`entry_bytes_bound` allows for (the optimiser's own are a
#: few hundred characters; a longer one makes a file larger than the bound, which
#: :func:`save_library` still refuses)
MESSAGE_ALLOWANCE = 1_000
#: a gait's scalar numbers, in the order a library entry lists them
GAIT_NUMBERS = (
    "phase_start",
    "phase_end",
    "step_duration",
    "cot",
    "delta_squared",
    "min_normal_force",
    "max_friction_ratio",
)


def _num(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def gait_entry(g: Gait) -> dict[str, Any]:
    """One gait's fields as stored in a library (and in a gait cache): ``degree`` to
    ``max_friction_ratio``, without its grid index, id and parameters."""
    entry: dict[str, Any] = {
        "degree": g.degree,
        "alpha": [[_num(v) for v in row] for row in g.alpha],
    }
    entry.update({k: _num(getattr(g, k)) for k in GAIT_NUMBERS[:3]})
    entry["orbit_state"] = [_num(v) for v in g.orbit_state]
    entry.update({k: _num(getattr(g, k)) for k in GAIT_NUMBERS[3:]})
    entry.update({"feasible": g.feasible, "solver_status": g.status, "solver_message": g.message})
    return entry


def to_document(lib: GaitLibrary) -> dict[str, Any]:
    """The library as a JSON-ready dictionary (schema version 1)."""
    gaits = []
    for i, g in enumerate(lib.gaits):
        entry = {"index": i, "id": lib.gait_id(i), "parameters": lib.parameters(i)}
        gaits.append({**entry, **gait_entry(g)})
    import gaitpref  # late: gaitpref/__init__ may still be importing this package

    formulation: dict[str, Any] = dict(lib.settings.to_dict())
    formulation.update(
        {
            "phase_variable": "stance_leg_angle",
            "outputs": ["hip_angle"],
            "objective": "mechanical_cot",
        }
    )
    return {
        "format": FORMAT,
        "schema_version": SCHEMA_VERSION,
        "created_by": f"gaitpref {gaitpref.__version__}",
        "model": {"name": "compass_gait", "parameters": lib.params.to_dict()},
        "formulation": formulation,
        "speed": lib.speed,
        "axes": [{"name": n, "unit": AXES[n].unit, "values": list(v)} for n, v in lib.axes],
        "grid_order": "C",
        "gaits": gaits,
    }


def entry_bytes_bound(degree: int) -> int:
    """At most how many bytes one gait of Bezier degree ``degree`` adds to a library file: its
    ``degree + 18`` numbers (``alpha``, ``orbit_state``, three parameters, the rest) at 32 bytes
    each (a float's 24 characters at most, with indentation and separator), 800 for keys and
    layout, its id (at most ``MAX_GAIT_ID`` characters) and a solver message of up to
    :data:`MESSAGE_ALLOWANCE` characters."""
    return 800 + MAX_GAIT_ID + MESSAGE_ALLOWANCE + 32 * (degree + 18)


def max_gaits_in_file(degree: int) -> int:
    """The most gaits of Bezier degree ``degree`` whose library file is sure to be read back
    (at most :data:`MAX_LIBRARY_BYTES`): what ``gaitpref gaits build`` may be asked for."""
    return MAX_LIBRARY_BYTES // entry_bytes_bound(degree)


def save_library(lib: GaitLibrary, path: str | Path) -> None:
    """Write ``lib`` to ``path`` (atomically: a temporary file, then a rename; a write that
    fails leaves neither a partial library nor the temporary file).  Its mode is what a plain
    ``open`` would give it: by the umask, or the mode of the file it replaces
    (:mod:`gaitpref.atomic`).  A library whose file would be larger than
    :data:`MAX_LIBRARY_BYTES` (which :func:`load_library` refuses) is a
    :class:`GaitLibraryError` and nothing is written."""
    target = Path(path)
    text = json.dumps(to_document(lib), indent=1, allow_nan=False) + "\n"
    size = len(text.encode())
    if size > MAX_LIBRARY_BYTES:
        raise GaitLibraryError(
            f"{target}: the library's {len(lib):,} gaits take {size:,} bytes, more than the "
            f"{MAX_LIBRARY_BYTES:,} a gait library file may (it could not be read back); "
            "nothing was written: save it in parts, or with shorter ids and messages"
        )
    write_text_atomic(target, text, prefix=f".{target.name}.")


def read_bounded(file: Path, limit: int, what: str) -> bytes:
    """The bytes of ``file``, read no further than ``limit`` (+1, to see it is larger): a file
    larger than that, or one that cannot be read, is :class:`GaitLibraryError` naming it and
    ``what`` it is."""
    try:
        with file.open("rb") as fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise GaitLibraryError(f"{file}: cannot be read ({exc.strerror or exc})") from None
    if len(data) > limit:
        raise GaitLibraryError(
            f"{file}: larger than the {limit:,} bytes a {what} may hold; it was not read"
        )
    return data


def read_json(file: Path) -> Any:
    """The JSON document in ``file``, or :class:`GaitLibraryError` naming it: besides a file
    that cannot be read or is larger than :data:`MAX_LIBRARY_BYTES`, a syntax error or bytes
    that are not UTF-8, a number past Python's integer digits limit (a ValueError) and arrays
    nested past the recursion limit (a RecursionError)."""
    data = read_bounded(file, MAX_LIBRARY_BYTES, "gait library file")
    try:
        return json.loads(data.decode("utf-8"))
    except RecursionError:
        raise GaitLibraryError(f"{file}: not valid JSON (nested too deeply)") from None
    except (UnicodeDecodeError, ValueError) as exc:  # json.JSONDecodeError is a ValueError
        why = str(exc).split(";")[0]  # not the advice to raise the interpreter's limit
        raise GaitLibraryError(f"{file}: not valid JSON ({why})") from None


class Reader:
    """Typed access to a parsed document; every error names the source and the field."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, field: str, problem: str) -> GaitLibraryError:
        return GaitLibraryError(f"{self.source}: {field}: {problem}")

    def get(self, obj: dict[str, Any], key: str, where: str) -> Any:
        if not isinstance(obj, dict) or key not in obj:
            raise self.fail(f"{where}{key}", "missing")
        return obj[key]

    def number(self, obj: dict[str, Any], key: str, where: str, nullable: bool = False) -> float:
        value = self.get(obj, key, where)
        if value is None and nullable:
            return math.nan
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(f"{where}{key}", f"expected a number, got {value!r}")
        try:
            return float(value)
        except OverflowError:  # an integer past a float's range
            raise self.fail(f"{where}{key}", "expected a number, got one too large") from None

    def matrix(self, value: Any, shape: tuple[int, ...], field: str) -> np.ndarray[Any, Any]:
        try:
            arr = np.array(value, dtype=np.float64)  # null -> nan
        except (TypeError, ValueError, OverflowError):
            raise self.fail(field, f"expected numbers of shape {shape}") from None
        if arr.shape != shape:
            raise self.fail(field, f"expected shape {shape}, got {arr.shape}")
        return arr


def from_document(
    data: Any, source: str = "<document>", allow_infeasible: bool = False
) -> GaitLibrary:
    """Validate a parsed document and build the :class:`GaitLibrary`."""
    r = Reader(source)
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise r.fail("format", f"not a gait library (expected format {FORMAT!r})")
    version = data.get("schema_version")
    if version != SCHEMA_VERSION:
        raise r.fail(
            "schema_version", f"{version!r} is not supported (this gaitpref reads {SCHEMA_VERSION})"
        )
    model = r.get(data, "model", "")
    raw_params = r.get(model, "parameters", "model.")
    if not isinstance(raw_params, dict):  # a list or a text was read as its items' names
        raise r.fail(
            "model.parameters",
            f"expected an object of numbers by name, got {type(raw_params).__name__}",
        )
    try:
        params = CompassGaitParams.from_dict(raw_params)
    except (ValueError, OverflowError) as exc:
        raise r.fail("model.parameters", str(exc)) from None
    formulation = r.get(data, "formulation", "")
    fields = HZDSettings.__dataclass_fields__
    raw_settings = {k: r.get(formulation, k, "formulation.") for k in fields}
    try:
        settings = HZDSettings(**raw_settings)
    except (TypeError, ValueError, OverflowError) as exc:
        raise r.fail("formulation", str(exc)) from None
    speed_raw = r.get(data, "speed", "")
    speed = None if speed_raw is None else r.number(data, "speed", "")
    axes_raw = r.get(data, "axes", "")
    if not isinstance(axes_raw, list):
        raise r.fail("axes", "expected a list")
    axes = []
    for k, axis in enumerate(axes_raw):
        name = r.get(axis, "name", f"axes[{k}].")
        values = r.get(axis, "values", f"axes[{k}].")
        if not isinstance(values, list) or not values:
            raise r.fail(f"axes[{k}].values", "expected a non-empty list of numbers")
        axes.append((str(name), tuple(r.matrix(values, (len(values),), f"axes[{k}].values"))))
    if r.get(data, "grid_order", "") != "C":
        raise r.fail("grid_order", "only C order (last axis fastest) is defined")
    gaits_raw = r.get(data, "gaits", "")
    if not isinstance(gaits_raw, list):
        raise r.fail("gaits", "expected a list")
    expected = grid_size([len(v) for _, v in axes]) if axes else 0
    if len(gaits_raw) != expected:
        raise r.fail("gaits", f"{len(gaits_raw)} gaits for a grid of {expected} points")
    gaits = [_gait(r, entry, k, settings.degree) for k, entry in enumerate(gaits_raw)]
    try:
        lib = GaitLibrary(params, settings, tuple(axes), tuple(gaits), speed)
    except GaitLibraryError as exc:
        raise GaitLibraryError(f"{source}: {exc}") from None
    for k, entry in enumerate(gaits_raw):
        if entry["parameters"] != lib.parameters(k) or entry.get("id") != lib.gait_id(k):
            raise r.fail(f"gaits[{k}]", "parameters or id do not match the grid at this index")
    bad = lib.infeasible()
    if bad and not allow_infeasible:
        listed = "; ".join(f"{lib.gait_id(i)}: {lib.gaits[i].message}" for i in bad[:3])
        more = f" (and {len(bad) - 3} more)" if len(bad) > 3 else ""
        raise GaitLibraryError(
            f"{source}: {len(bad)} of {len(lib)} gaits are infeasible{more}: {listed}. "
            "Load with allow_infeasible=True to inspect them."
        )
    return lib


def _gait(r: Reader, entry: Any, k: int, degree: int) -> Gait:
    where = f"gaits[{k}]."
    if not isinstance(entry, dict):
        raise r.fail(f"gaits[{k}]", "expected an object")
    if r.get(entry, "index", where) != k:
        raise r.fail(f"{where}index", f"expected {k} (gaits are stored in grid order)")
    if not isinstance(r.get(entry, "parameters", where), dict):
        raise r.fail(f"{where}parameters", "expected an object")
    length = r.number(r.get(entry, "parameters", where), "step_length", f"{where}parameters.")
    return read_gait_entry(r, entry, where, degree, length)


def read_gait_entry(r: Reader, entry: Any, where: str, degree: int, step_length: float) -> Gait:
    """The :class:`Gait` stored as :func:`gait_entry` wrote it (every field checked)."""
    if not isinstance(entry, dict):
        raise r.fail(where.rstrip("."), "expected an object")
    if r.get(entry, "degree", where) != degree:
        raise r.fail(f"{where}degree", f"expected {degree} (the formulation's degree)")
    feasible = r.get(entry, "feasible", where)
    status = r.get(entry, "solver_status", where)
    message = r.get(entry, "solver_message", where)
    if (
        not isinstance(feasible, bool)
        or isinstance(status, bool)
        or not isinstance(status, int)
        or not isinstance(message, str)
    ):
        raise r.fail(where.rstrip("."), "feasible must be a boolean, solver_status an integer, "
                     "solver_message a string")  # fmt: skip
    nums = {key: r.number(entry, key, where, nullable=True) for key in GAIT_NUMBERS}
    return Gait(
        step_length=step_length,
        alpha=r.matrix(r.get(entry, "alpha", where), (1, degree + 1), f"{where}alpha"),
        orbit_state=r.matrix(r.get(entry, "orbit_state", where), (4,), f"{where}orbit_state"),
        feasible=feasible,
        status=status,
        message=message,
        **nums,
    )


def load_library(path: str | Path, *, allow_infeasible: bool = False) -> GaitLibrary:
    """Read and validate a library file; :class:`GaitLibraryError` names any problem."""
    file = Path(path)
    if not file.is_file():
        raise GaitLibraryError(f"{file}: no such gait library file")
    return from_document(read_json(file), str(file), allow_infeasible)
