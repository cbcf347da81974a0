"""The grid of a config: ``[space.<feature>]`` tables or a ``[gaits]`` library, sized first.

A feature with ``min`` and ``max`` and no ``num`` is continuous, and so is one whose ``num`` is
past what any grid holds (issue 13); no array of its values is built.  The grid's size is
computed from the config's numbers (:func:`grid_too_large`) before the loop is made: a space that
does not fit the full-grid path runs on the line path, or fails with the sizes and the key to set
when the config asks for the full grid.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from gaitpref.config.schema import FEATURE, MAX_FEATURE_VALUES, MAX_FEATURES, check_table
from gaitpref.config.specs import clipped, fail
from gaitpref.space import Feature, Space

if TYPE_CHECKING:
    from gaitpref.gaits.library import GaitLibrary


def parse_gaits(
    gaits: dict[str, Any], base_dir: str | Path | None, library_file: str | Path | None = None
) -> tuple[GaitLibrary, str]:
    """The gait library ``[gaits].library`` names (relative to ``base_dir``) and its path; read
    from ``library_file`` instead when given (an imported session's copy of it)."""
    name = gaits["library"]
    if not name:
        fail("gaits", "library", "must be the path of a gait library file")
    if "\x00" in name:  # open() raised ValueError "embedded null byte", naming no key
        fail("gaits", "library", "a path holds no NUL character (U+0000)")
    path = Path(name) if library_file is None else Path(library_file)
    if not path.is_absolute():
        path = Path(base_dir if base_dir is not None else ".") / path
    from gaitpref.errors import GaitLibraryError
    from gaitpref.gaits.library import GaitLibrary

    try:
        return GaitLibrary.load(path), str(path.resolve())
    except (GaitLibraryError, OSError) as exc:
        fail("gaits", "library", str(exc))


def _count(name: str, spec: dict[str, Any], max_actions: int) -> tuple[int | None, str]:
    """How many values feature ``name`` has (None: continuous), and the key that says so."""
    table = f"space.{name}"
    if spec["values"] is not None:
        if any(spec[k] is not None for k in ("min", "max", "num")):
            fail(table, "values", "give either values or min/max/num, not both")
        return len(spec["values"]), "values"
    for key in ("min", "max"):
        if spec[key] is None:
            fail(table, key, "missing (give min and max, with num for a grid, or values)")
    if spec["num"] is None or spec["num"] > max_actions:
        if not spec["max"] > spec["min"]:
            fail(table, "max", f"must be greater than min ({spec['min']:g}), got {spec['max']:g}")
        return None, "max"  # continuous: no num, or more values than any grid holds
    if spec["num"] > 1 and not spec["max"] > spec["min"]:
        fail(table, "max", f"must be greater than min ({spec['min']:g}), got {spec['max']:g}")
    return int(spec["num"]), "num"


def parse_space(raw: object, max_actions: int, grid: bool = False) -> Space:
    """The space of ``[space]``: every table checked; a feature with ``min`` and ``max`` and no
    ``num`` (or a ``num`` past ``max_actions``) is continuous.  With ``grid`` (the config asks
    for the full grid) a grid past ``max_actions`` fails at the key that passes it, before any
    array is built; otherwise whether it fits is the caller's question (:func:`grid_too_large`).
    """
    if not isinstance(raw, dict) or not raw:
        fail("space", None, "needs one table per feature, e.g. [space.step_length]")
    if len(raw) > MAX_FEATURES:
        fail("space", None, f"has {len(raw)} features; at most {MAX_FEATURES} are allowed")
    specs: dict[str, dict[str, Any]] = {}
    for name, table in raw.items():
        if not name.isidentifier():
            fail(f"space.{name}", None, "a feature's name must be an identifier (letters, _)")
        specs[name], _ = check_table(table, f"space.{name}", FEATURE)
    if grid:
        _check_size(specs, max_actions)
    features = []
    for name, spec in specs.items():
        count, key = _count(name, spec, max_actions)
        extra = {"coactive": spec["coactive"], "words": spec["words"]}
        if count is None:
            features.append(
                Feature.interval(name, spec["min"], spec["max"], unit=spec["unit"], **extra)
            )
            continue
        values = spec["values"]
        if values is None:
            values = np.linspace(spec["min"], spec["max"], spec["num"])
        if len(values) > 1 and not np.all(np.diff(values) > 0):
            fail(f"space.{name}", key, "the values must be strictly increasing (and distinct)")
        features.append(Feature(name, values, spec["unit"], **extra))
    return Space(features)


def _check_size(specs: dict[str, dict[str, Any]], max_actions: int) -> None:
    """Fail at the first key whose feature takes the grid past ``max_actions`` actions, or has
    more than :data:`MAX_FEATURE_VALUES` values itself."""
    actions = 1
    for name, spec in specs.items():
        given = spec["values"] is not None
        count = len(spec["values"]) if given else spec["num"]
        key = "values" if given else "num"
        if count is None:
            fail(f"space.{name}", "num", "missing: the full grid (subspace = 'grid') needs num")
        actions *= count
        if actions > max_actions:
            fail(
                f"space.{name}",
                key,
                f"the grid would have {actions} or more actions (the product of every "
                f"feature's size); at most {max_actions} are allowed on the full grid "
                "(subspace = 'line' runs without one)",
            )
        if count > MAX_FEATURE_VALUES:
            fail(
                f"space.{name}",
                key,
                f"gives {count} values; the full grid takes at most {MAX_FEATURE_VALUES} a "
                "feature (its kernel factor is n x n, built at every fit): use fewer, or "
                "subspace = 'line'",
            )


def grid_too_large(space: Space, max_actions: int) -> str | None:
    """Why ``space`` cannot run on the full-grid path (None: it can)."""
    if space.continuous:
        names = ", ".join(clipped(f.name) for f in space.features if f.continuous)
        return f"the features {names} are continuous (min and max, no num)"
    wide = [f for f in space.features if len(f.values) > MAX_FEATURE_VALUES]
    if wide:
        return (
            f"the feature {clipped(wide[0].name)} has {len(wide[0].values):,} values and at most "
            f"{MAX_FEATURE_VALUES:,} a feature fit the full-grid path (its kernel factor is n x n)"
        )
    size = space.grid_size
    assert size is not None
    if size > max_actions:
        return (
            f"the grid would have {size:,} actions (the product of every feature's size; "
            f"{size * 8 * (space.ndim + 1) / 2**30:,.1f} GiB for its points alone) and at most "
            f"{max_actions:,} fit the full-grid path"
        )
    return None
