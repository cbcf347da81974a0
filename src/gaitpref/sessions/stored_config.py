"""A session's config as stored: parsed again, checked against its hash and its gait library.

The database keeps the config text exactly as given (and its SHA-256); a config that names a gait
library also leaves, in the session's metadata, the folder its relative library path is taken
from, the library's absolute path and its SHA-256, so that reopening the session finds the same
library, or refuses with :class:`~gaitpref.sessions.records.ReplayError`.
"""

from __future__ import annotations

import difflib
import hashlib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np

from gaitpref.config import ConfigError, ExperimentConfig, load_config, parse_config
from gaitpref.errors import ReplayError
from gaitpref.space import Space
from gaitpref.storage import SessionRecord, Storage

if TYPE_CHECKING:  # gaits/ loads SciPy's optimizers: only when a library is used
    from gaitpref.gaits.gait_cache import GaitCache
    from gaitpref.gaits.library import GaitLibrary

#: what names the gait of each grid action: a gait library, a list of ids or an action -> id map
GaitLibraryLike: TypeAlias = "GaitLibrary | Sequence[str] | Mapping[int, str]"


def software_version() -> str:
    from gaitpref import __version__

    return __version__


def config_of(record: SessionRecord) -> ExperimentConfig:
    digest = hashlib.sha256(record.config_text.encode()).hexdigest()
    if digest != record.config_sha256:
        raise ReplayError(
            f"session {record.id}: the stored config text does not match its hash "
            f"({digest[:12]} != {record.config_sha256[:12]}); the database was altered"
        )
    meta = record.meta
    try:
        cfg = parse_config(
            record.config_text,
            default_name=record.config_name,
            base_dir=meta.get("config_dir"),
            defaults=meta.get("config_defaults", "0.1"),  # 0.1 sessions relied on 0.1's
        )
    except ConfigError as exc:
        if meta.get("library_path"):
            raise ReplayError(
                f"session {record.id} needs its gait library {meta['library_path']} (sha256 "
                f"{str(meta.get('library_sha256'))[:12]}), which cannot be loaded: {exc}"
            ) from None
        raise ReplayError(
            f"session {record.id}: its config no longer parses with gaitpref {software_version()} "
            f"(recorded with {record.software_version}): {exc}"
        ) from None
    if meta.get("library_sha256") and cfg.library_sha256 != meta["library_sha256"]:
        raise ReplayError(
            f"session {record.id}: the gait library {cfg.library_path} is not the one the "
            f"session was run with (sha256 {str(cfg.library_sha256)[:12]}, recorded "
            f"{meta['library_sha256'][:12]})"
        )
    return cfg


def library_meta(cfg: ExperimentConfig) -> dict[str, Any]:
    """What replay needs besides the text: the version of the defaults the config relies on (if
    it leaves a changed default to them), and where its gait library is (folder, path, hash)."""
    defaults = {"config_defaults": cfg.defaults_version} if cfg.relies_on_changed_defaults else {}
    if cfg.library_path is None:
        return defaults
    import tomllib

    given = Path(tomllib.loads(cfg.text)["gaits"]["library"])
    where = Path(cfg.library_path)
    base = where
    for _ in given.parts:
        base = base.parent
    if not given.is_absolute() and (base / given).resolve() != where:
        raise ValueError(
            f"cannot tell which folder the config's gait library path {str(given)!r} is "
            "relative to; load the config from its file"
        )
    return {
        **defaults,
        "config_dir": str(base),
        "library_path": str(where),
        "library_sha256": cfg.library_sha256,
    }


def check_same_config(record: SessionRecord, config: str | Path | ExperimentConfig) -> None:
    given = config if isinstance(config, ExperimentConfig) else load_config(config)
    if given.sha256 == record.config_sha256:
        return
    diff = "".join(
        difflib.unified_diff(
            record.config_text.splitlines(keepends=True),
            given.text.splitlines(keepends=True),
            fromfile=f"session {record.id} ({record.config_name})",
            tofile=f"given ({given.name})",
        )
    )
    raise ReplayError(f"session {record.id} was run with another config:\n{diff}")


def gait_ids_of(library: GaitLibraryLike | None, space: Space) -> list[str] | None:
    """The gait id of each action of ``space`` (None: no library).  A library with a grid of
    its own (:class:`~gaitpref.gaits.GaitLibrary`) must have ``space``'s: its ids would name
    other gaits."""
    if library is None:
        return None
    size = len(space)
    ids: list[Any]
    if isinstance(library, Mapping):
        missing = [a for a in range(size) if a not in library]
        if missing:
            raise ValueError(f"the gait library names no gait for action {missing[0]}")
        ids = [library[a] for a in range(size)]
    elif isinstance(library, Sequence) and not isinstance(library, str):
        if len(library) != size:
            raise ValueError(f"the gait library has {len(library)} gaits; the grid has {size}")
        ids = list(library)
    elif hasattr(library, "gait_id"):
        if hasattr(library, "space"):
            _same_grid(library.space(), space)
        ids = [library.gait_id(a) for a in range(size)]
    else:
        raise TypeError("library must map each action to a gait id (or have gait_id(action))")
    if not all(isinstance(g, str) and g for g in ids):
        raise ValueError("gait ids must be non-empty strings")
    return [str(g) for g in ids]


def _same_grid(grid: Space, space: Space) -> None:
    """Refuse a library whose grid (features, values within 1e-9) is not the config's."""

    def words(s: Space) -> str:
        return "; ".join(
            f"{f.name} {f.values[0]:g}..{f.values[-1]:g} ({len(f.values)} values)"
            for f in s.features
        )

    same = grid.names == space.names and all(
        not f.continuous
        and len(f.values) == len(g.values)
        and np.allclose(f.values, g.values, rtol=1e-9, atol=0.0)
        for f, g in zip(space.features, grid.features, strict=True)
    )
    if not same:
        raise ValueError(
            f"the gait library's grid ({words(grid)}) is not the config's ({words(space)}): "
            "its gait ids would name other gaits"
        )


#: the folder beside a SQLite database that caches gaits made on demand: ``lab.db.gaits/``
GAIT_CACHE_SUFFIX = ".gaits"


def gait_cache_of(storage: Storage, config: ExperimentConfig) -> GaitCache | None:
    """The cache of gaits made on demand for ``config`` (None when it names no generator).

    A folder next to the database (``lab.db.gaits/``, one JSON file per gait, named by its
    content address) rather than a table: the cache is derived data (the log carries every gait,
    and replay of an older log makes a missing gait again), so it needs none of the event
    store's guarantees or migrations; files can be read, copied or deleted without gaitpref, and
    every session of the database shares them.  A database that is not a local file (memory,
    PostgreSQL) caches in memory, per session object.
    """
    if config.generator is None:
        return None
    from gaitpref.gaits.gait_cache import GaitCache

    return GaitCache(storage.folder_beside(GAIT_CACHE_SUFFIX))
