"""The gaits a session made on demand, carried by its export so that an import makes none again.

A session whose config names a gait generator (issue 13, item 4) has each gait its log names
(the ``key`` of its ``gait_made`` and ``gait_infeasible`` events) in the database's gait cache
(``gaits/gait_cache.py``).  :func:`write_made_gaits` writes them into the export as the cache
writes them, one file per gait under ``gaits/`` named by its content address; the manifest lists
each file with its SHA-256 under ``files`` (so that an edited file is refused, naming it) and
maps each key to its file under ``made_gaits``.

:func:`read_made_gaits` takes them back for :func:`~gaitpref.sessions.export.import_session`,
checking each against the log: its key must be one the log names, the SHA-256 of its document
(generator, settings, parameters; :func:`~gaitpref.gaits.generator.content_key`) must be that
key, and its verdict must be the log's (a ``gait_made`` gait feasible, a ``gait_infeasible`` one
not).  Their coefficients are trusted as the cache's are.  The import replays with them in the
cache and then writes them into the target database's cache (where it has a folder), keeping any
entry that is already there; a gait the export lacks (an export written before gaits were
carried) is made again, as replay makes a missing cache entry.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from gaitpref.errors import ExportError, GaitLibraryError
from gaitpref.sessions import events as log
from gaitpref.storage import NewEvent

if TYPE_CHECKING:  # gaits/ loads SciPy's optimizers: only for a session with a generator
    from gaitpref.gaits.gait_cache import CachedGait, GaitCache
    from gaitpref.sessions.session import Session

#: the export's folder of made gaits
FOLDER = "gaits"
#: an entry of the cache: the gait and its document (generator, settings, parameters)
Entry = tuple["CachedGait", dict[str, Any]]


def write_made_gaits(session: Session, out: Path) -> tuple[dict[str, str], dict[str, str]]:
    """Write the session's made gaits under ``out/gaits/``: (file -> SHA-256, key -> file)."""
    on_demand = session._state.on_demand
    if on_demand is None:
        return {}, {}
    from gaitpref.gaits.gait_cache import GaitCache

    cache = GaitCache(out / FOLDER)
    files: dict[str, str] = {}
    keys: dict[str, str] = {}
    for entry, document in on_demand.entries():
        cache.put(entry, document)
        name = f"{FOLDER}/{entry.key}.json"
        files[name] = hashlib.sha256((out / name).read_bytes()).hexdigest()
        keys[entry.key] = name
    return files, keys


def read_made_gaits(
    folder: Path, manifest: dict[str, Any], events: Sequence[NewEvent]
) -> list[Entry]:
    """The made gaits an export carries, each checked against ``events`` (the log).

    The files' SHA-256 are checked before (``export._check_files``); an :class:`ExportError`
    names the file that does not fit.
    """
    listed = manifest.get("made_gaits")
    if listed is None:
        return []
    if not isinstance(listed, dict):
        raise ExportError("manifest.json: made_gaits must map gait keys to files")
    verdicts = {
        e.payload.get("key"): e.kind == log.GAIT_MADE
        for e in events
        if e.kind in (log.GAIT_MADE, log.GAIT_INFEASIBLE)
    }
    from gaitpref.gaits.gait_cache import read_entry
    from gaitpref.gaits.generator import content_key

    out: list[Entry] = []
    for key, name in sorted(listed.items()):
        if not isinstance(name, str) or name not in manifest["files"]:
            raise ExportError(f"manifest.json: made gait {key} has no file listed with a SHA-256")
        if key not in verdicts:
            raise ExportError(f"{name}: the session's log names no gait {key}")
        try:
            entry, document = read_entry(folder / name, key)
            same = content_key(document) == key
        except (GaitLibraryError, KeyError, TypeError, ValueError) as exc:
            raise ExportError(f"{name} is not a gait this session made: {exc}") from None
        if not same:
            raise ExportError(
                f"{name}: its generator, settings and parameters do not hash to its key {key}"
            )
        if entry.gait.feasible != verdicts[key]:
            logged = "feasible" if verdicts[key] else "infeasible"
            raise ExportError(f"{name}: the log says the gait {key} is {logged}, the file does not")
        out.append((entry, document))
    return out


def filled(cache: GaitCache, entries: Sequence[Entry]) -> GaitCache:
    """``cache`` with every entry it lacks put in (written to its folder, if it has one)."""
    for entry, document in entries:
        if cache.get(entry.key) is None:
            cache.put(entry, document)
    return cache


__all__ = ["FOLDER", "filled", "read_made_gaits", "write_made_gaits"]
