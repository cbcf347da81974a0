"""A content-addressed cache of gaits made on demand: one JSON file per gait, named by its key.

The key (:meth:`~gaitpref.gaits.generator.GaitGenerator.key`) is a SHA-256 of the generator's
name, its settings and the gait's parameters, so an entry never changes meaning: writers of the
same key write the same kind of document, and a rename makes each write atomic.  A session's
cache is the folder ``<database file>.gaits/`` next to a SQLite database (``gaitpref.sessions``
says why); without a folder (in-memory or server databases) it lives in memory only.

The cache is derived data: a session's log carries each gait it made (``gait_made`` version 2,
the ``gait`` part below: :func:`gait_document`, read back by :func:`read_gait`) and replay takes
it from there; for a log written before (version 1), an entry that is missing, unreadable or of
another format is made again (and rewritten), never trusted; :func:`read_entry` reads one,
naming what is wrong with it (besides its format: a document that does not hash to its key, a
gait of another step length, a feasible gait with non-finite numbers).  A folder that cannot be
written keeps the gaits in memory, with a :class:`GaitCacheWarning`.
Document (``format = "gaitpref-gait"``, schema version 1)::

    {"format", "schema_version", "key", "generator", "settings", "parameters",
     "warm_start": key | null, "gait": {"step_length", the fields of a gait in a library file}}

The generator's document (``generator``, ``settings``, ``parameters`` and any field a generator
of one's own adds) is written among the file's own fields (:data:`FILE_FIELDS`), so a document
that uses one of them is refused (:meth:`GaitCache.put`; ``on_demand.py`` says so as the
generator's fault before anything is made).
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from gaitpref.atomic import write_text_atomic
from gaitpref.errors import GaitLibraryError
from gaitpref.gaits.gait import Gait
from gaitpref.gaits.generator import content_key
from gaitpref.gaits.library import feasible_gait_problem
from gaitpref.gaits.library_io import Reader, gait_entry, read_bounded, read_gait_entry

FORMAT = "gaitpref-gait"
SCHEMA_VERSION = 1
#: the most bytes of a cache entry read (one gait: a few kB): a larger file is not read whole
#: but refused (:func:`read_entry`), so the cache goes without it and the gait is made again
MAX_ENTRY_BYTES = 16 * 2**20
#: the cache file's own fields: a gait's document (generator, settings, parameters and any field
#: a generator of one's own adds) is written among them, so it may use none of them
FILE_FIELDS = ("format", "schema_version", "key", "warm_start", "gait")


class GaitCacheWarning(UserWarning):
    """The cache's folder could not be written: gaits stay in memory (and in the log)."""


@dataclass(frozen=True, eq=False)
class CachedGait:
    """A gait with its key and the key of the gait it was warm-started from."""

    key: str
    gait: Gait
    warm_start: str | None


class GaitCache:
    """Gaits by key, in ``folder`` (created when first written) or, without one, in memory; an
    entry whose file cannot be written (:attr:`unwritable`) is kept in memory."""

    def __init__(self, folder: str | Path | None = None) -> None:
        self.folder = None if folder is None else Path(folder)
        self._memory: dict[str, CachedGait] = {}
        self.hits = 0
        self.misses = 0
        self.unwritable: str | None = None  # why the last write to the folder failed

    def path(self, key: str) -> Path | None:
        return None if self.folder is None else self.folder / f"{key}.json"

    def get(self, key: str) -> CachedGait | None:
        """The cached gait of ``key``, or None (missing or unreadable: make it again)."""
        found = self._memory.get(key) or self._read(key)
        if found is None:
            self.misses += 1
            return None
        self.hits += 1
        self._memory[key] = found
        return found

    def put(self, entry: CachedGait, document: dict[str, Any]) -> None:
        """Keep ``entry``; ``document`` (generator, settings, parameters) goes into its file.

        The file is written first and the entry remembered after.  A folder that cannot be
        written (an ``OSError``: read-only, a file in its place, a full disk) keeps the entry in
        memory only, with a :class:`GaitCacheWarning` naming it (once per cache): the cache is
        derived data, the session's log carries the gait, so reading or continuing a session
        never fails for it.  Any other failure of the write (an entry that cannot be written as
        JSON) is a ``ValueError`` naming the file, and nothing is kept.  A ``document`` that
        uses one of the file's own fields (:data:`FILE_FIELDS`) is a ``ValueError`` naming it,
        and nothing is kept."""
        field = file_field_in(document)
        if field is not None:
            raise ValueError(
                f"gait {entry.key}: its document has the field {field!r}, one of the gait cache "
                f"file's own ({', '.join(FILE_FIELDS)}); nothing is cached"
            )
        target = self.path(entry.key)
        if target is not None:
            try:
                self._write(target, entry, document)
            except OSError as exc:
                self._keep_in_memory(target, exc)
            except Exception as exc:
                raise ValueError(
                    f"gait cache file {target}: cannot be written ({type(exc).__name__}: {exc}); "
                    "nothing is cached"
                ) from exc
        self._memory[entry.key] = entry

    def _keep_in_memory(self, target: Path, exc: OSError) -> None:
        """The folder cannot be written: say so once (the entry is kept in memory only)."""
        if not self.unwritable:
            warnings.warn(
                f"gait cache {self.folder}: cannot write {target.name} "
                f"({exc.strerror or exc}); gaits are kept in memory and in the session's "
                "log, and other sessions will make them again",
                GaitCacheWarning,
                stacklevel=3,
            )
        self.unwritable = str(exc)

    def _write(self, target: Path, entry: CachedGait, document: dict[str, Any]) -> None:
        doc = {
            "format": FORMAT,
            "schema_version": SCHEMA_VERSION,
            "key": entry.key,
            **document,
            "warm_start": entry.warm_start,
            "gait": gait_document(entry.gait),
        }
        text = json.dumps(doc, indent=1, allow_nan=False) + "\n"
        target.parent.mkdir(parents=True, exist_ok=True)
        # a full disk leaves no partial file; the mode is by the umask, as open() would make it
        write_text_atomic(target, text, prefix=f".{entry.key[:16]}.")

    def _read(self, key: str) -> CachedGait | None:
        path = self.path(key)
        if path is None or not path.is_file():
            return None
        try:
            return read_entry(path, key)[0]
        except GaitLibraryError:
            return None


def file_field_in(document: Mapping[str, Any]) -> str | None:
    """The first of the cache file's own fields (:data:`FILE_FIELDS`) that ``document`` uses,
    or None: written among them, it would replace the file's (its key, its format) or be
    replaced by them (the warm start, the gait)."""
    return next((name for name in FILE_FIELDS if name in document), None)


def gait_document(gait: Gait) -> dict[str, Any]:
    """The ``gait`` part of an entry's document: its step length and the fields of a gait in a
    library file (``library_io.gait_entry``); a session's log carries it too (``gait_made``)."""
    return {"step_length": gait.step_length, **gait_entry(gait)}


def read_gait(raw: Any, source: str) -> Gait:
    """The gait of a :func:`gait_document`; :class:`GaitLibraryError` names ``source`` and the
    field that is wrong."""
    return _read_gait(Reader(source), raw, "")


def _read_gait(r: Reader, raw: Any, where: str) -> Gait:
    degree = r.get(raw, "degree", where)
    if isinstance(degree, bool) or not isinstance(degree, int):
        raise r.fail(f"{where}degree", f"expected an integer, got {degree!r}")
    length = r.number(raw, "step_length", where)
    try:
        return read_gait_entry(r, raw, where, degree, length)
    except GaitLibraryError:
        raise
    except ValueError as exc:  # a Gait that does not hold together
        raise r.fail(where.rstrip(".") or "gait", str(exc)) from None


def read_entry(path: Path, key: str) -> tuple[CachedGait, dict[str, Any]]:
    """The gait in the file ``path`` under ``key`` and its document (generator, settings,
    parameters); :class:`GaitLibraryError` names the file and what is wrong with it."""
    r = Reader(str(path))
    data = read_bounded(path, MAX_ENTRY_BYTES, "cached gait")  # not read whole past it
    try:
        doc = json.loads(data.decode("utf-8"))
    except RecursionError:
        raise r.fail("file", "cannot be read as JSON (nested too deeply)") from None
    except (OSError, ValueError) as exc:  # a JSONDecodeError, bad UTF-8, too many digits
        raise r.fail("file", f"cannot be read as JSON ({exc})") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise r.fail("format", f"not a cached gait (expected format {FORMAT!r})")
    if doc.get("schema_version") != SCHEMA_VERSION:
        raise r.fail("schema_version", f"{doc.get('schema_version')!r}, expected {SCHEMA_VERSION}")
    if doc.get("key") != key:
        raise r.fail("key", f"{doc.get('key')!r}, expected {key}")
    document = {name: r.get(doc, name, "") for name in ("generator", "settings", "parameters")}
    try:
        address = content_key(document)
    except (TypeError, ValueError):  # not JSON numbers and text (NaN, say)
        address = None
    if address != key:
        raise r.fail("parameters", "the generator, settings and parameters are not the key's")
    gait = _read_gait(r, r.get(doc, "gait", ""), "gait.")
    params = document["parameters"]
    length = params.get("step_length") if isinstance(params, dict) else None
    if length is not None and length != gait.step_length:
        raise r.fail("gait.step_length", f"{gait.step_length}, the parameters ask {length}")
    problem = feasible_gait_problem(gait) if gait.feasible else None
    if problem is not None:
        raise r.fail("gait", problem)
    warm = doc.get("warm_start")
    return CachedGait(key, gait, warm if isinstance(warm, str) else None), document


__all__ = [
    "FILE_FIELDS",
    "FORMAT",
    "MAX_ENTRY_BYTES",
    "SCHEMA_VERSION",
    "CachedGait",
    "GaitCache",
    "GaitCacheWarning",
    "file_field_in",
    "gait_document",
    "read_entry",
    "read_gait",
]
