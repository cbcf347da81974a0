"""A session's config as stored: parsed again, checked against its hash and its gait library.

The database keeps the config text exactly as given (and its SHA-256); a config that names a gait
library also leaves, in the session's metadata, the folder its relative library path is taken
from, the library's absolute path and its SHA-256, so that reopening the session finds the same
library, or refuses with :class:`~gaitpref.sessions.records.ReplayError`.  An imported session
reading a copy of its library away from the config's path (``gaitpref.sessions.export``) also
has ``library_copied_from``: its library is then read from ``library_path``.
"""

from __future__ import annotations

import difflib
import hashlib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np

from gaitpref.checks import hidden_in
from gaitpref.config import ConfigError, ExperimentConfig, load_config, parse_config
from gaitpref.errors import ReplayError
from gaitpref.gaits.library import MAX_GAIT_ID
from gaitpref.space import Space
from gaitpref.storage import SessionRecord, Storage

if TYPE_CHECKING:  # gaits/ loads SciPy's optimizers: only when a library is used
    from gaitpref.gaits.gait_cache import GaitCache
    from gaitpref.gaits.library import GaitLibrary

#: what names the gait of each grid action: a gait library, a list of ids or an action -> id map
GaitLibraryLike: TypeAlias = "GaitLibrary | Sequence[str] | Mapping[int, str]"


def software_version() -> str:
    """The gaitpref version a new session records (``gaitpref.__version__``)."""
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
    for key in ("config_dir", "config_defaults", "library_path", "library_copied_from"):
        value = meta.get(key)
        if value is not None and not isinstance(value, str):
            raise ReplayError(
                f"session {record.id}: its meta's {key} must be a text, got {value!r}; the "
                "database (or the export it was imported from) was altered"
            )
    if meta.get("library_copied_from") and not meta.get("library_path"):
        raise ReplayError(
            f"session {record.id}: its meta names library_copied_from but no library_path; the "
            "database (or the export it was imported from) was altered"
        )
    try:
        cfg = parse_config(
            record.config_text,
            default_name=record.config_name,
            base_dir=meta.get("config_dir"),
            defaults=meta.get("config_defaults", "0.1"),  # 0.1 sessions relied on 0.1's
            # an imported session whose library is a copy, not where the config names it
            library_file=meta["library_path"] if meta.get("library_copied_from") else None,
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


#: what a session's row duplicates of its ``created`` event: the event's field -> where the row
#: keeps it (a column, or a ``meta`` key; ``gait_library``: whether the meta names gait ids)
ROW_OF_CREATED: dict[str, str] = {
    "subject": "subject",
    "config_name": "config_name",
    "config_sha256": "config_sha256",
    "seed": "seed",
    "software_version": "software_version",
    "gait_library": "meta.gait_ids",
    "prior_from": "meta.prior_from",
    "prior_rho": "meta.prior_rho",
    "prior_terms": "meta.prior_terms",
    "prior_relearn_every": "meta.prior_relearn_every",
    "prior_share_gate": "meta.prior_share_gate",
}


def check_row(record: SessionRecord, created: Mapping[str, Any]) -> None:
    """Refuse a session whose row (``record``) says other than its ``created`` event's payload
    on what both record (:data:`ROW_OF_CREATED`): the row, edited by hand or damaged, would be
    replayed as another session than the one its log made (replay reads seed, config and warm
    start from the row).  :class:`ReplayError` names every field that differs.  Every release
    wrote both from the same values (warm-start keys absent from both when cold), so a stored
    session whose row is intact always passes."""
    meta = record.meta
    row: dict[str, Any] = {
        "subject": record.subject,
        "config_name": record.config_name,
        "config_sha256": record.config_sha256,
        "seed": record.seed,
        "software_version": record.software_version,
        "gait_library": meta.get("gait_ids") is not None,
        "prior_from": meta.get("prior_from") or [],
    }
    event = {key: created.get(key) for key in ROW_OF_CREATED}
    event["gait_library"] = created.get("gait_library", False)
    event["prior_from"] = created.get("prior_from") or []
    differ = []
    for key, where in ROW_OF_CREATED.items():
        mine = row[key] if key in row else meta.get(key)
        theirs = event[key]
        if mine != theirs or type(mine) is not type(theirs):
            differ.append(
                f"{where} is {_short(mine)} in the row, {_short(theirs)} in the event"
                if key != "gait_library"
                else f"{where} {'names a' if mine else 'names no'} gait library in the row, the "
                f"event's gait_library is {_short(theirs)}"
            )
    if differ:
        raise ReplayError(
            f"session {record.id}: its row does not match its created event (event 1): "
            f"{'; '.join(differ)}.  The database was altered (edited by hand or damaged); the "
            "session is not replayed as another one"
        )


def _short(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def library_meta(cfg: ExperimentConfig) -> dict[str, Any]:
    """What replay needs besides the text: the version of the defaults the config relies on (if
    it leaves a changed default to them), and where its gait library is (folder, path, hash)."""
    defaults = {"config_defaults": cfg.defaults_version} if cfg.relies_on_changed_defaults else {}
    if cfg.library_path is None:
        return defaults
    import tomllib

    given = Path(tomllib.loads(cfg.text)["gaits"]["library"])
    where = Path(cfg.library_path)
    if cfg.base_dir is not None:  # the folder the config was read from
        base = Path(cfg.base_dir)
    else:  # a config made by hand: the folder, traced back from the library's path
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
    seen: dict[str, int] = {}
    for action, gait in enumerate(ids):
        if len(gait) > MAX_GAIT_ID:
            raise ValueError(
                f"gait id {gait[:40]!r}... (action {action}) has {len(gait):,} characters: "
                f"gait ids have at most {MAX_GAIT_ID}"
            )
        if gait in seen:  # one id for two gaits: answers and flags would name either
            raise ValueError(
                f"gait id {gait!r} is given twice (actions {seen[gait]} and {action}): each "
                "gait of the library needs its own id"
            )
        seen[gait] = action
    for action, gait in enumerate(ids):  # shown by the terminal loop, the console and exports
        hidden = hidden_in(gait, name=True)
        if hidden:
            code = ord(hidden[0][1])
            raise ValueError(
                f"gait id {gait!r} (action {action}) holds U+{code:04X}: gait ids must "
                "not hold control, format or line-break characters (ESC, NUL, tabs, newlines, "
                "bidirectional overrides, ...)"
            )
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
