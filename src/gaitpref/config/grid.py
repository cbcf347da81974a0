"""The grid of a config: ``[space.<feature>]`` tables or a ``[gaits]`` library, sized first.

The number of actions is computed from the config's numbers (every feature's ``num`` or the
length of its ``values``) and checked against the limit before any array is built, so a config
asking for ``num = 1000000000`` fails at once with the key and the limit (issue 15, item 1).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from gaitpref.config.schema import FEATURE, MAX_FEATURES, check_table
from gaitpref.config.specs import fail
from gaitpref.space import Feature, Space

if TYPE_CHECKING:
    from gaitpref.gaits.library import GaitLibrary


def parse_gaits(gaits: dict[str, Any], base_dir: str | Path | None) -> tuple[GaitLibrary, str]:
    """The gait library ``[gaits].library`` names (relative to ``base_dir``) and its path."""
    name = gaits["library"]
    if not name:
        fail("gaits", "library", "must be the path of a gait library file")
    path = Path(name)
    if not path.is_absolute():
        path = Path(base_dir if base_dir is not None else ".") / path
    from gaitpref.errors import GaitLibraryError
    from gaitpref.gaits.library import GaitLibrary

    try:
        return GaitLibrary.load(path), str(path.resolve())
    except (GaitLibraryError, OSError) as exc:
        fail("gaits", "library", str(exc))


def _count(name: str, spec: dict[str, Any]) -> tuple[int, str]:
    """How many values feature ``name`` has, and the key that says so (nothing built)."""
    table = f"space.{name}"
    if spec["values"] is not None:
        if any(spec[k] is not None for k in ("min", "max", "num")):
            fail(table, "values", "give either values or min/max/num, not both")
        return len(spec["values"]), "values"
    for key in ("min", "max", "num"):
        if spec[key] is None:
            fail(table, key, "missing (give min, max and num, or values)")
    if spec["num"] > 1 and not spec["max"] > spec["min"]:
        fail(table, "max", f"must be greater than min ({spec['min']:g}), got {spec['max']:g}")
    return int(spec["num"]), "num"


def parse_space(raw: object, max_actions: int) -> Space:
    """The grid of ``[space]``: every table checked and the size bounded before building."""
    if not isinstance(raw, dict) or not raw:
        fail("space", None, "needs one table per feature, e.g. [space.step_length]")
    if len(raw) > MAX_FEATURES:
        fail("space", None, f"has {len(raw)} features; at most {MAX_FEATURES} are allowed")
    specs: dict[str, dict[str, Any]] = {}
    actions = 1
    for name, table in raw.items():
        if not name.isidentifier():
            fail(f"space.{name}", None, "a feature's name must be an identifier (letters, _)")
        specs[name], _ = check_table(table, f"space.{name}", FEATURE)
        count, key = _count(name, specs[name])
        actions *= count
        if actions > max_actions:
            fail(
                f"space.{name}",
                key,
                f"the grid would have {actions} or more actions (the product of every "
                f"feature's size); at most {max_actions} are allowed",
            )
    features = []
    for name, spec in specs.items():
        values = spec["values"]
        if values is None:
            values = np.linspace(spec["min"], spec["max"], spec["num"])
        key = "num" if spec["values"] is None else "values"
        if len(values) > 1 and not np.all(np.diff(values) > 0):
            fail(f"space.{name}", key, "the values must be strictly increasing (and distinct)")
        features.append(
            Feature(name, values, spec["unit"], coactive=spec["coactive"], words=spec["words"])
        )
    return Space(features)
