"""Configs and gait libraries as a client gives them to the console, read without trusting paths.

- a **shipped config** by name (``exo-1d-step-length``);
- **TOML text** (API body or uploaded file).  A ``[gaits].library`` it names must be a relative
  path inside the console's library folder (``--libraries``, default ``gait-libraries/`` beside a
  SQLite database): the console never opens a file a client names anywhere else;
- an **uploaded gait library** (JSON, ``gaitpref gaits build``) is checked by the gait library's
  own loader, then kept in ``<libraries>/<sha256 prefix>/<file name>`` so that the session finds
  it again when it is reopened.  A config that names a library must name the uploaded file; a
  config with its own ``[space]`` must have exactly the library's grid (the library then only
  names the gait of every action).

Sessions share an uploaded library file (it is named by its content); a refused creation removes
the file it wrote (:func:`discard`).  So that it never removes one a concurrent creation has
found there and reads, each creation holds the content's lock
(:func:`gaitpref.content_lock.content_lock`, ``<libraries>/.<sha256 prefix>.lock``) from finding
or writing the file until its session is committed or the file removed: :meth:`Chosen.release`.
"""

from __future__ import annotations

import contextlib
import hashlib
import re
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gaitpref.atomic import write_bytes_atomic
from gaitpref.config import (
    ExperimentConfig,
    load_config,
    parse_config,
    read_toml,
    shipped_configs,
)
from gaitpref.config.schema import MAX_ACTIONS as LIBRARY_ACTIONS
from gaitpref.console.errors import InputError, quoted
from gaitpref.console.limits import MAX_LIBRARY_BYTES
from gaitpref.content_lock import content_lock
from gaitpref.gaits import GaitLibrary, GaitLibraryError

#: grids larger than this are refused at creation (the console draws and sends every action)
MAX_ACTIONS = 250_000
#: the most values a config's features may have in all (every feature's values are sent with the
#: session, GET /api/sessions/{id}); a continuous feature (no num) has none
MAX_VALUES = 250_000


def default_library_dir(url: str) -> Path:
    """``gait-libraries/`` beside a SQLite database file, else in the working folder."""
    if url.startswith("sqlite:///") and url != "sqlite:///:memory:":
        return Path(url[len("sqlite:///") :]).resolve().parent / "gait-libraries"
    return Path.cwd() / "gait-libraries"


def _safe_name(name: str | None, fallback: str) -> str:
    base = Path(name or "").name
    clean = re.sub(r"[^A-Za-z0-9._-]", "_", base)[:100].lstrip(".")
    return clean or fallback


@dataclass(frozen=True)
class Chosen:
    """A config ready for ``Session.create``, with the library that names its gaits (if any)."""

    config: ExperimentConfig
    library: GaitLibrary | None
    #: the library file this choice wrote (None: none, or it was there before); see :func:`discard`
    written: Path | None = None
    #: the uploaded library's content lock, held until :meth:`release`
    held: contextlib.ExitStack | None = field(default=None, compare=False, repr=False)

    def release(self) -> None:
        """Release the uploaded library's lock: call it once the session reading the library is
        committed, or after :func:`discard` ing ``written`` (calling it again does nothing)."""
        if self.held is not None:
            self.held.close()


def discard(written: Path | None) -> None:
    """Remove a library file that a refused session creation wrote (and its emptied folder)."""
    if written is None:
        return
    written.unlink(missing_ok=True)
    with contextlib.suppress(OSError):  # not empty: another session's file of that prefix
        written.parent.rmdir()


def store_library(
    folder: Path, data: bytes, filename: str | None, held: contextlib.ExitStack
) -> tuple[Path, GaitLibrary, bool]:
    """Check an uploaded gait library and keep it under ``folder`` (content-addressed).

    Returns its path, the library, and whether this call wrote the file (it was not there).  The
    content's lock is entered into ``held`` before the file is looked for, for the caller to
    hold until a session reading it is committed or the file it wrote is removed.
    """
    if len(data) > MAX_LIBRARY_BYTES:
        raise InputError("library_file", f"larger than {MAX_LIBRARY_BYTES // 1_000_000} MB")
    name = _safe_name(filename, "gaits.json")
    with tempfile.TemporaryDirectory() as tmp:
        probe = Path(tmp) / name
        probe.write_bytes(data)
        try:
            GaitLibrary.load(probe)
        except (GaitLibraryError, ValueError, OSError) as exc:
            raise InputError("library_file", f"not a usable gait library: {exc}") from None
    prefix = hashlib.sha256(data).hexdigest()[:16]
    target = folder / prefix / name
    folder.mkdir(parents=True, exist_ok=True)
    held.enter_context(content_lock(folder, prefix))
    wrote = not target.exists()
    if wrote:
        target.parent.mkdir(parents=True, exist_ok=True)
        write_bytes_atomic(target, data, prefix=f".{name}.")  # a unique temporary file each
    return target, GaitLibrary.load(target), wrote


def _named_library(raw: dict[str, Any]) -> str | None:
    gaits = raw.get("gaits")
    if isinstance(gaits, dict) and isinstance(gaits.get("library"), str):
        return str(gaits["library"])
    return None


def _values_given(raw: dict[str, Any]) -> int:
    """The values the features of a config's TOML will have in all, counted in the text before
    any is made, as the session reads it (a ``num`` past the library's limit on actions is a
    continuous feature, no values); tables that are not features are left to the parser."""
    space = raw.get("space")
    if not isinstance(space, dict):
        return 0
    total = 0
    for table in space.values():
        if not isinstance(table, dict):
            continue
        values, num = table.get("values"), table.get("num")
        if isinstance(values, list):
            total += len(values)
        elif isinstance(num, int) and not isinstance(num, bool) and 0 < num <= LIBRARY_ACTIONS:
            total += num
    return total


def _too_many_values(total: int) -> InputError:
    return InputError(
        "config",
        f"the features have {total:,} values in all; the console serves at most {MAX_VALUES:,} "
        "(it sends every feature's values): give fewer, or leave out num (a continuous "
        "feature, min and max only)",
    )


def _inside(base: Path, name: str) -> Path:
    if "\x00" in name:  # no file has one: Path.resolve raised "embedded null byte" (unnamed)
        raise InputError(
            "config",
            f"[gaits].library {quoted(name)}: a path holds no NUL character (U+0000 at "
            f"character {name.index(chr(0)) + 1})",
        )
    given = Path(name)
    where = (base / given).resolve()
    if given.is_absolute() or not where.is_relative_to(base.resolve()):
        raise InputError(
            "config",
            f"[gaits].library {quoted(name)}: a config given to the console names a library "
            f"inside its library folder ({base}) by a relative path, or comes with the library "
            "uploaded",
        )
    return where


def _same_grid(config: ExperimentConfig, library: GaitLibrary) -> None:
    mine, theirs = config.space, library.space()
    same = mine.names == theirs.names and mine.shape == theirs.shape
    if same:
        same = all(
            np.allclose(a.array, b.array, rtol=1e-9, atol=1e-12)
            for a, b in zip(mine.features, theirs.features, strict=True)
        )
    if not same:
        raise InputError(
            "library_file",
            f"the library's grid ({' x '.join(map(str, theirs.shape))} over "
            f"{', '.join(theirs.names)}) is not the config's ({' x '.join(map(str, mine.shape))} "
            f"over {', '.join(mine.names)})",
        )


def choose_config(
    source: str,
    *,
    library_dir: Path,
    name: str | None = None,
    library: tuple[bytes, str | None] | None = None,
) -> Chosen:
    """The config (and library) for a new session; :class:`InputError` names what is wrong.

    An uploaded library is kept only if the choice succeeds; the caller :func:`discard` s
    ``Chosen.written`` if the session is then not created, so a refused upload leaves nothing,
    and in either case then calls :meth:`Chosen.release` (the library's lock is held till then).
    """
    if library is None:
        return _choose(source, library_dir, name, None)
    held = contextlib.ExitStack()
    try:
        path, lib, wrote = store_library(library_dir, *library, held)
        try:
            chosen = _choose(source, library_dir, name, (path, lib))
        except BaseException:
            discard(path if wrote else None)
            raise
    except BaseException:
        held.close()
        raise
    return Chosen(chosen.config, chosen.library, path if wrote else None, held)


def _choose(
    source: str, library_dir: Path, name: str | None, uploaded: tuple[Path, GaitLibrary] | None
) -> Chosen:
    if source in shipped_configs():
        cfg = load_config(source)
    else:
        if "\n" not in source and "=" not in source:
            raise InputError(
                "config",
                f"{quoted(source)} is neither a shipped config ({', '.join(shipped_configs())}) "
                "nor TOML config text",
            )
        stem = _safe_name(name, "uploaded")
        raw = read_toml(source)  # a ConfigError: 422 at config
        if _values_given(raw) > MAX_VALUES:
            raise _too_many_values(_values_given(raw))
        named = _named_library(raw)
        base: Path | None = None
        if named is not None and uploaded is not None:
            if Path(named).name != uploaded[0].name or len(Path(named).parts) != 1:
                raise InputError(
                    "config",
                    f"[gaits].library names {named!r}, but the uploaded library is "
                    f"{uploaded[0].name!r}: name the uploaded file",
                )
            base = uploaded[0].parent
        elif named is not None:
            _inside(library_dir, named)
            base = library_dir
        # read as the session will read the stored text (Session.open), with the library's
        # limits: with the console's own, a subspace of 'auto' or a num past them resolved
        # otherwise here than in the session that then ran
        cfg = parse_config(source, default_name=stem, base_dir=base)
    values = sum(len(f.values) for f in cfg.space.features if not f.continuous)
    if values > MAX_VALUES:  # a gait library's grid
        raise _too_many_values(values)
    if cfg.subspace == "grid" and len(cfg.space) > MAX_ACTIONS:
        raise InputError(
            "config",
            f"the grid has {len(cfg.space):,} actions; the console serves at most "
            f"{MAX_ACTIONS:,} on the full grid (with [cospar] subspace = 'line' it runs on "
            "lines through it)",
        )
    if uploaded is not None and cfg.library is None:
        _same_grid(cfg, uploaded[1])
        return Chosen(cfg, uploaded[1])
    return Chosen(cfg, None)
