"""Export a session to plain files, and rebuild a session from such an export.

An export folder is readable without gaitpref:

- ``manifest.json``: format and version, software version, config name and hash, seed, the
  session's row, the features (name, unit), a posterior summary, and the SHA-256 of every file;
- ``config.toml``: the config exactly as the session was given it (and a copy of the gait
  library it names, when there is one: at the same relative path, or at
  ``gait_library/<file name>`` for an absolute path or one with ``..``; ``manifest.json``'s
  ``gait_library`` entry names it);
- ``events.jsonl``: the whole log, one JSON object per line (``seq``, ``kind``, ``at``,
  ``version`` (the payload's schema version), ``payload``);
- tables as CSV (``--format csv``) or JSON (``--format json``), every gait named as the terminal
  and the console name it (``gait``: the library's id, or ``G<action>``): ``trials`` (with
  ``unsafe`` flags and their reasons; values and gait id as the trial's event logged them),
  ``comparisons`` (with ``tie``, ``undone`` and ``excluded`` flags), ``suggestions``,
  ``posterior`` (mean and standard deviation of every action), ``validation`` and ``confidence``
  (after every answer, undo and exclusion: ``seq`` of its last event, ``answers`` and ``trials``
  in force, whether a preference is ``learned`` (false: no confidence stated, the fields after
  it empty), the recommended ``action`` and ``gait``, whether its gait was ``made`` (gaits made
  on demand), the ``probability`` that it is within ``tolerance`` of the range of the best, the
  expected shortfall ``regret`` in utility units and ``relative_regret`` as a fraction of the
  range, the posterior ``samples`` behind them, ``at``); and one table per
  other feedback kind the session holds (its kind's
  :attr:`~gaitpref.feedback.FeedbackKind.export` table: ``seq``, ``query``, the kind's
  columns, ``undone``, ``excluded``, ``at``).

:func:`import_session` needs only the manifest, the config and the events: it replays them in
memory first (checking every step and the exported posterior summary) and only then writes the
session into the target database, under a new id, in one transaction.  With gaits made on
demand, ``events.jsonl`` carries them (``gait_made`` version 2): both replays take them from the
log and none is made again; the target database's gait cache gets them as replay puts them.
The imported session reads its gait library where the exported one did when that file is the
same, else the export's copy: copied again beside a SQLite database (``lab.db.libraries/``), read
from the export's folder for a database that is not a local file.  An import refused after it
wrote that copy (already imported, a database error) removes it, never a copy that was there
before (an earlier import's) nor one a session in the database reads by then.  An import holds
the copy's lock (:func:`gaitpref.content_lock.content_lock`,
``lab.db.libraries/.<sha256>.lock``, left there) from finding or writing it until its session is
committed or the copy removed, so that two imports of one library at once (two processes) take
turns: the second finds a copy that stays, or writes it anew.
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import functools
import hashlib
import io
import json
import os
import shutil
import tempfile
from collections.abc import Callable, Sequence
from datetime import datetime
from pathlib import Path
from typing import Any, Final, Literal

import numpy as np

from gaitpref.atomic import write_bytes_atomic
from gaitpref.content_lock import content_lock
from gaitpref.errors import ExportError, ReplayError, StorageError
from gaitpref.feedback import kind_for_event
from gaitpref.gaits.library_io import MAX_LIBRARY_BYTES as MAX_LIBRARY_BYTES
from gaitpref.loop.stopping import preference_learned
from gaitpref.model.threads import one_blas_thread
from gaitpref.sessions import events as log
from gaitpref.sessions.records import Trial
from gaitpref.sessions.session import Session
from gaitpref.storage import (
    MemoryStorage,
    NewEvent,
    SessionRecord,
    SessionSpec,
    Storage,
    open_storage,
)
from gaitpref.storage.base import check_event, check_status

FORMAT = "gaitpref-session-export"
FORMAT_VERSION = 1
Format = Literal["csv", "json"]
TABLES = ("trials", "comparisons", "suggestions", "posterior", "validation", "confidence")
#: the most an import reads into memory: ``events.jsonl`` (a 150-trial log is about 75 kB, with
#: the gaits a generator made), and ``manifest.json`` and ``config.toml`` each; other listed files
#: are only hashed, a block at a time
MAX_EVENTS_BYTES = 256 * 2**20
MAX_EVENTS = 1_000_000  # and events (about 600 in a 150-trial log)
MAX_TEXT_BYTES = 64 * 2**20
#: and the export's copy of the gait library, which the import reads whole (about 1 kB a gait):
#: :data:`gaitpref.gaits.library_io.MAX_LIBRARY_BYTES`, imported above
#: the keys of an ``events.jsonl`` line (``version`` is absent from 0.1.0's exports: 1)
EVENT_KEYS = frozenset({"seq", "kind", "at", "payload"})


# -- export ------------------------------------------------------------------------------------
def export_session(
    session: Session,
    out: str | Path,
    fmt: Format = "csv",
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Write ``session`` to the folder ``out`` (new or empty; a path, or its text); returns the
    manifest's path.
    ``progress(done, total)``: the events replayed for the confidence table so far, and their
    number (``Session.confidence_history``; the long part of a long session's export).

    The files are written into a folder in a hidden one beside ``out``, renamed to ``out`` once
    all are written: an export that fails (a full disk, text that cannot be written) leaves no
    half-written folder behind, and may be run again.  An empty ``out`` that is there (a link
    to a folder, a mount point) is kept: the hidden folder is made in it and its files moved up,
    ``manifest.json`` last.  The session is brought up to date first
    and every file is of the same event, however other writers move it on meanwhile.
    """
    if fmt not in ("csv", "json"):
        raise ExportError(f"format must be csv or json, got {fmt!r}")
    out = Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise ExportError(f"{str(out)!r} exists and is not an empty folder; choose a new one")
    if out.name in ("", ".", "..") or out.resolve() == Path.cwd().resolve():
        # the export replaces the folder: not the one the command runs in
        raise ExportError(f"{str(out)!r} is the working folder; give a new folder's name")
    # an empty folder that cannot be replaced (a symbolic link to one, a mount point such as a
    # USB drive's) is filled: the export is written in a hidden folder inside it and moved up,
    # manifest.json last; otherwise it is written beside ``out`` and renamed to it
    fill = out.is_dir() and (out.is_symlink() or os.path.ismount(out))
    if not out.exists():
        out.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out if fill else out.parent))
    try:
        partial = work / "export"
        partial.mkdir()  # its mode by the umask, as out's would be (mkdtemp's is 0700)
        if out.exists() and not fill:
            shutil.copymode(out, partial)
        # one consistent view: the log, tables and manifest of the same event, however other
        # writers move the session on meanwhile
        try:
            session.read(lambda s: _write_export(s, partial, fmt, progress))
        except OSError as exc:  # a full disk, a quota: named by the export, not the hidden folder
            written = Path(exc.filename).name if exc.filename else "its files"
            raise ExportError(
                f"could not write the export {str(out)!r} ({written}: "
                f"{exc.strerror or exc}); nothing was left there"
            ) from None
        if fill:
            names = sorted(p.name for p in partial.iterdir() if p.name != "manifest.json")
            for name in [*names, "manifest.json"]:
                if (out / name).exists():  # another export into it meanwhile
                    raise ExportError(f"{str(out)!r} is no longer empty; choose a new folder")
                (partial / name).rename(out / name)
        else:
            if out.exists():
                out.rmdir()  # empty, checked above
            partial.rename(out)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return out / "manifest.json"


def _write_export(
    session: Session, out: Path, fmt: Format, progress: Callable[[int, int], None] | None
) -> None:
    events = [e for e in session.events() if e.seq <= session.last_seq]  # as the state holds
    walked = {e.seq: e.payload for e in events if e.kind == log.TRIAL}
    with one_blas_thread():  # the posterior's sd, as ask, tell and the confidence (threads.py)
        tables = _tables(session, {e.seq: e.at.isoformat() for e in events}, walked, progress)
    written: dict[str, str] = {}

    def put(name: str, text: str) -> None:
        data = text.encode()  # the bytes hashed, "\n" line ends on every system
        (out / name).write_bytes(data)
        written[name] = hashlib.sha256(data).hexdigest()

    put("config.toml", session.record.config_text)
    put(
        "events.jsonl",
        "".join(
            json.dumps(
                {
                    "seq": e.seq,
                    "kind": e.kind,
                    "at": e.at.isoformat(),
                    "version": e.version,
                    "payload": e.payload,
                },
                allow_nan=False,
            )
            + "\n"
            for e in events
        ),
    )
    for name, rows in tables.items():
        if fmt == "json":
            put(f"{name}.json", json.dumps(rows, indent=1, allow_nan=False) + "\n")
        else:
            put(f"{name}.csv", _csv(rows))
    library = _copy_library(session, out, written)
    if library is not None:
        written[library[0]] = library[1]
    manifest = _manifest(session, written)  # posterior_summary: on one BLAS thread too
    if library is not None:
        manifest["gait_library"] = {"file": library[0], "sha256": library[1]}
    put("manifest.json", json.dumps(manifest, indent=2) + "\n")


#: where an export keeps a gait library the config names by an absolute path or a path with
#: ``..`` (or one that would clash with the export's own files): ``gait_library/<its file name>``
LIBRARY_FOLDER: Final = "gait_library"


def _copy_library(session: Session, out: Path, written: dict[str, str]) -> tuple[str, str] | None:
    """Copy the config's gait library into the export: at the path the config names when that
    is relative and inside the export, else at ``gait_library/<file name>``; ``written`` names
    the export's other files.  Returns the copy's path in the export and its SHA-256."""
    path = session.record.meta.get("library_path")
    if not path:
        return None
    given = _library_named(session.record.config_text)
    inside = not given.is_absolute() and ".." not in given.parts
    if not inside or given.as_posix() in written or given.as_posix() == "manifest.json":
        name = given.name if given.name not in ("", ".", "..") else "gaits.json"
        given = Path(LIBRARY_FOLDER, name)
    data = Path(path).read_bytes()
    (out / given).parent.mkdir(parents=True, exist_ok=True)
    (out / given).write_bytes(data)
    return given.as_posix(), hashlib.sha256(data).hexdigest()


def _manifest(session: Session, files: dict[str, str]) -> dict[str, Any]:
    from gaitpref import __version__

    rec = session.record
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "software_version": __version__,
        "exported_at": datetime.now().astimezone().isoformat(),
        "config_name": rec.config_name,
        "config_sha256": rec.config_sha256,
        "seed": rec.seed,
        "session": {
            "id": rec.id,
            "subject": rec.subject,
            "status": session.status,
            "software_version": rec.software_version,
            "created_at": rec.created_at.isoformat(),
            "last_seq": session.last_seq,
            "meta": rec.meta,
        },
        "features": [{"name": f.name, "unit": f.unit} for f in session.config.space.features],
        "posterior": posterior_summary(session),
        "files": files,
    }


def posterior_summary(session: Session) -> dict[str, Any]:
    """The posterior's best action, its value, and the pending query (JSON-ready).

    ``argmax`` is the highest posterior mean over every gait, which may be one that may not be
    proposed (flagged unsafe, near one, in the region of avoidance); ``recommended`` is the
    highest among those that may be (:meth:`Session.recommended`: the gait the confidence
    recommends, the best so far to walk; with gaits made on demand under ``[gaits] recommend =
    "made"``, the highest among the gaits made).  The ``argmax`` fields are None while the
    posterior has no point (the line path before a query: it lives on the points present); the
    ``recommended`` fields then too, and when no gait may be recommended
    (:meth:`Session.no_recommendation`).

    ``learned`` says whether a preference has been learned (:func:`preference_learned`: the
    posterior mean tells some gaits apart), exactly when ``session show`` names a best gait
    rather than "none yet": while it is False, ``argmax`` and ``recommended`` still name the flat
    prior's argmax (the first gait, the first that may be proposed) for no reason.  An import
    reads none of it (exports written before it was added lack it).

    ``argmax_made`` and ``recommended_made`` say, with gaits made on demand, whether this
    session made that gait (:meth:`Session.gait_made`, as the console API's ``made``): False for
    a point no query proposed (a coactive suggestion's), never walked, which may prove
    infeasible; None without gaits made on demand (a library's gaits, or none: nothing to
    make), and with the action they describe (exports and ``session show --json`` written
    before they were added lack them).

    Its numbers are computed on one BLAS thread, as ask, tell and the confidence are
    (``model/threads.py``)."""
    with one_blas_thread():
        return _posterior_summary(session)


def _posterior_summary(session: Session) -> dict[str, Any]:
    post = session.posterior()
    pending = session.pending
    best: int | None = post.argmax if len(session.space) else None
    rec = session.recommended()
    learned = best is not None and preference_learned(post.mean)
    return {
        "argmax": best,
        "argmax_values": None if best is None else session.space.values_of(best),
        "argmax_gait_id": None if best is None else session.gait_id(best),
        "mean_at_argmax": None if best is None else float(post.mean[best]),
        "sd_at_argmax": None if best is None else float(post.std[best]),
        "argmax_made": None if best is None else session.gait_made(best),
        "recommended": rec,
        "recommended_values": None if rec is None else session.space.values_of(rec),
        "recommended_gait_id": None if rec is None else session.gait_id(rec),
        "mean_at_recommended": None if rec is None else float(post.mean[rec]),
        "sd_at_recommended": None if rec is None else float(post.std[rec]),
        "recommended_made": None if rec is None else session.gait_made(rec),
        "learned": learned,
        "trials_in_force": len(session.trials()),
        "pending_query": None
        if pending is None
        else {"id": pending.id, "actions": list(pending.actions), "buffer": list(pending.buffer)},
    }


#: The columns of the tables that also carry one column per feature (trials, posterior,
#: validation, confidence): a feature of one of these names gets its column as ``NAME_value``.
FIXED_COLUMNS: Final = frozenset(
    {
        *("trial", "query", "action", "gait_id", "gait", "unsafe", "unsafe_reason", "excluded"),
        *("exclusion_reason", "exclusion_detail", "undone", "seq", "at", "mean", "sd", "round"),
        *("label", "role", "posterior_mean", "subject_rank", "model_rank", "agrees"),
        *("kendall_tau", "answers", "trials", "probability", "regret", "relative_regret"),
        *("tolerance", "samples", "opened_by", "learned", "made"),
    }
)


def feature_columns(names: Sequence[str]) -> dict[str, str]:
    """Each feature's column: its name, or ``NAME_value`` for a feature named as a fixed column
    (``mean``, ``action``, ...), which would overwrite that column or be overwritten by it
    (then ``NAME_value_2``, ... if those are features' names too)."""
    out: dict[str, str] = {}
    for name in names:
        column = name
        if name in FIXED_COLUMNS:
            column, k = f"{name}_value", 1
            while column in names or column in out.values() or column in FIXED_COLUMNS:
                k += 1
                column = f"{name}_value_{k}"
        out[name] = column
    return out


def _tables(
    session: Session,
    at: dict[int, str],
    walked: dict[int, dict[str, Any]],
    progress: Callable[[int, int], None] | None = None,
) -> dict[str, list[dict[str, Any]]]:
    """The tables; a trial's values and gait id are its ``trial_executed`` event's (``walked``,
    by seq): on the line path an undone answer's rows can go to other points later (its query,
    pending again, withdrawn by an unsafe flag).  Comparisons and suggestions name their trials'
    gaits the same way; validation gaits are as their round showed them."""
    space = session.space
    columns = feature_columns([f.name for f in space.features])

    def valued(values: dict[str, Any]) -> dict[str, Any]:
        return {columns[name]: value for name, value in values.items()}

    unsafe = session.unsafe_flags()
    by_number: dict[int, list[Trial]] = {}
    for t in session.trials(include_undone=True):
        by_number.setdefault(t.number, []).append(t)

    def named(number: int, seq: int) -> str:
        """The gait trial ``number`` walked when the answer logged at ``seq`` named it: the
        latest such trial logged before (numbers are reused after an undo, and an undone
        answer's rows may name other points later)."""
        walked_then = [t for t in by_number.get(number, []) if t.seq < seq]
        if not walked_then:
            raise ExportError(f"event {seq} names trial {number}, which no earlier event ran")
        t = max(walked_then, key=lambda t: t.seq)
        return _walked_gait(session, t.action, walked[t.seq]) or f"G{t.action}"

    trials = [
        {
            "trial": t.number,
            "query": t.query,
            "action": t.action,
            **valued(walked[t.seq]["values"]),
            "gait_id": _walked_gait(session, t.action, walked[t.seq]),
            "gait": _walked_gait(session, t.action, walked[t.seq]) or f"G{t.action}",
            # a flag is of the trial of its number in force (an undo is refused while one is)
            "unsafe": not t.undone and t.number in unsafe,
            "unsafe_reason": "" if t.undone else unsafe.get(t.number, (0, ""))[1],
            "excluded": t.excluded is not None,
            "exclusion_reason": t.excluded,
            "exclusion_detail": t.exclusion_detail,
            "undone": t.undone,
            "seq": t.seq,
            "at": at.get(t.seq),
        }
        for t in session.trials(include_undone=True)
    ]
    comparisons = [
        {
            "seq": c.seq,
            "query": c.query,
            "first_trial": c.first_trial,
            "second_trial": c.second_trial,
            "first_action": c.first,
            "second_action": c.second,
            "first_gait": named(c.first_trial, c.seq),
            "second_gait": named(c.second_trial, c.seq),
            "outcome": c.outcome,
            "preferred_trial": None
            if c.tie
            else (c.first_trial if c.outcome == "first" else c.second_trial),
            "tie": c.tie,
            "undone": c.undone,
            "excluded": c.excluded,
            "at": at.get(c.seq),
        }
        for c in session.comparisons()
    ]
    suggestions = [
        {
            "seq": s.seq,
            "query": s.query,
            "trial": s.trial,
            "action": s.action,
            "gait": named(s.trial, s.seq),
            "feature": s.feature,
            "move": s.move,
            "target_action": s.target,
            "undone": s.undone,
            "excluded": s.excluded,
            "at": at.get(s.seq),
        }
        for s in session.suggestions()
    ]
    post = session.posterior()
    mean, sd = np.asarray(post.mean), np.asarray(post.std)
    posterior = [
        {
            "action": a,
            **valued(space.values_of(a)),
            "gait_id": session.gait_id(a),
            "gait": session.gait_name(a),
            "mean": float(mean[a]),
            "sd": float(sd[a]),
        }
        for a in range(len(space))
    ]
    # who opened each answered round: "rule", "operator", or None (logged before it was recorded)
    opened_by = {r.round: r.opened_by for r in session.validation_rounds() if r.answered}
    validation = [
        {
            "round": r.round,
            "label": label,
            "action": r.actions[label],
            "gait": shown[label].gait,
            **valued(shown[label].values),
            "role": r.roles[label],
            "posterior_mean": r.posterior_mean[label],
            "subject_rank": r.ranking.index(label) + 1,
            "model_rank": r.model_ranking.index(label) + 1,
            "agrees": r.agrees,
            "kendall_tau": r.kendall_tau,
            "opened_by": opened_by.get(r.round),
        }
        for r in session.validations()
        for shown in [{g.label: g for g in session.validation_gaits(r.round)}]
        for label in sorted(r.actions)
    ]
    confidence = [
        {
            **{k: v for k, v in row.items() if k != "values"},
            **valued(row["values"]),
            "at": at.get(row["seq"]),
        }
        for row in session.confidence_history(progress)
    ]
    return {
        "trials": trials,
        "comparisons": comparisons,
        "suggestions": suggestions,
        "posterior": posterior,
        "validation": validation,
        "confidence": confidence,
        **_other_feedback(session, at),
    }


def _walked_gait(session: Session, action: int, walked: dict[str, Any]) -> str | None:
    """The gait id a trial was logged with (logs of 0.1.0 have none: the library's then)."""
    logged: str | None = walked.get("gait_id")
    if logged is not None or (session.gait_ids is None and session.config.generator is None):
        return logged  # no ids to look up: an undone line-path trial's point may be gone since
    return session.gait_id(action)


def _other_feedback(session: Session, at: dict[int, str]) -> dict[str, list[dict[str, Any]]]:
    """One table per feedback kind besides comparisons and suggestions, from its kind."""
    tables: dict[str, list[dict[str, Any]]] = {}
    for entry in session.feedback():
        kind = kind_for_event(entry.kind)
        if kind is None:
            raise ExportError(f"event {entry.seq}: feedback kind {entry.kind!r} is not registered")
        columns = kind.export_row(kind.payload_type.parse(entry.payload, entry.kind))
        tables.setdefault(kind.export.name, []).append(
            {
                "seq": entry.seq,
                "query": entry.query,
                **{k: v for k, v in columns.items() if k != "query"},
                "undone": entry.undone,
                "excluded": entry.excluded,
                "at": at.get(entry.seq),
            }
        )
    return tables


def _csv(rows: Sequence[dict[str, Any]]) -> str:
    buf = io.StringIO()
    if rows:
        writer = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
        writer.writeheader()
        for row in rows:
            writer.writerow({k: _cell(v) for k, v in row.items()})
    return buf.getvalue()


#: A CSV text cell starting with one of these is read as a formula by spreadsheets ("=cmd|..."
#: runs a command in some): such a cell is written with a leading ``'`` (OWASP's advice), in the
#: CSV tables only; the event log, the JSON tables and import keep the text as it is.
FORMULA_STARTS: Final = ("=", "+", "-", "@", "\t", "\r")


def _cell(value: object) -> object:
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str) and value.startswith(FORMULA_STARTS):
        return "'" + value
    return value


# -- import ------------------------------------------------------------------------------------
def import_session(
    db: str | Storage | None, folder: str | Path, *, as_new: bool = False
) -> Session:
    """Rebuild the exported session in ``db`` (a new id) from ``folder`` (a path, or its text);
    checked before anything is written.

    Every file the manifest lists must match its SHA-256.  A session already in ``db`` (imported
    from this export before, or the exported session itself) is refused unless ``as_new``; the
    new session's metadata says where it came from (``imported_from``, see :func:`origin_of`).
    """
    folder = Path(folder)
    manifest = _read_manifest(folder)
    _check_files(folder, manifest)
    config_text = _read_checked(folder, "config.toml", manifest, MAX_TEXT_BYTES)
    if hashlib.sha256(config_text.encode()).hexdigest() != manifest.get("config_sha256"):
        raise ExportError("config.toml does not match the manifest's config_sha256")
    events = _read_events(_read_checked(folder, "events.jsonl", manifest, MAX_EVENTS_BYTES))
    info = manifest["session"]
    _check_session_entry(manifest, len(events))
    meta = dict(info.get("meta", {}))
    library = _find_library(folder, manifest, meta, config_text)
    _refuse_warm_start(info, meta)
    texts = {
        "session.subject": info.get("subject"),
        "session.software_version": info.get("software_version"),
        "config_name": manifest.get("config_name"),
    }
    for key, value in texts.items():
        if not isinstance(value, str) or not value:
            raise ExportError(f"manifest.json: {key} must be a non-empty text, got {value!r}")
    try:
        status = check_status(info["status"])
        spec = SessionSpec(
            subject=info["subject"],
            config_name=manifest["config_name"],
            config_text=config_text,
            config_sha256=manifest["config_sha256"],
            seed=int(manifest["seed"]),
            software_version=info["software_version"],
            meta={
                **meta,
                "imported_from": {
                    "session_id": info["id"],
                    "exported_at": manifest.get("exported_at"),
                    "exported_by": manifest.get("software_version"),
                    "events_sha256": manifest["files"]["events.jsonl"],
                    "created_at": info.get("created_at"),
                },
            },
        )
    except (KeyError, TypeError, ValueError, RuntimeError) as exc:
        raise ExportError(f"manifest.json: bad session entry ({exc})") from None
    _check_created(events[0], spec)
    _check_gait_ids(events, spec.meta)
    # rebuild in memory first: nothing reaches the database unless replay is exact
    scratch = MemoryStorage()
    trial = Session.open(scratch, scratch.create_session(spec, events, status).id)
    if trial.status != status:  # the row's status must be the one its log ends in
        raise ExportError(
            f"manifest.json's session.status is {status!r}, but the log leaves the session "
            f"{trial.status}; nothing was written"
        )
    _check_summary(trial, manifest.get("posterior") or {})
    storage = open_storage(db)
    owns = not isinstance(db, Storage)
    made: list[Path] = []  # what this import wrote beside the database, in order
    try:
        # the copy's lock, held until the session reading it is committed or the copy removed
        with contextlib.ExitStack() as held:
            if library is not None:
                spec = _keep_library(storage, spec, *library, made, held)
            try:
                if as_new:
                    record = storage.create_session(spec, events, status)
                else:  # checked in the transaction that creates it: two imports cannot both pass
                    record = storage.create_session_checked(
                        spec,
                        events,
                        status,
                        check=functools.partial(
                            _check_not_imported, storage.url, spec, info, events[0].at
                        ),
                    )
            except BaseException:  # refused (already there, a database error): no session reads
                _unmake(storage, made)
                raise
        session = Session.open(storage, record.id)
    except BaseException:
        if owns:
            storage.close()
        raise
    session._owns = owns  # closing the session closes the database it opened
    return session


def _refuse_warm_start(info: dict[str, Any], meta: dict[str, Any]) -> None:
    """A warm-started session's model is rebuilt from the earlier sessions' logs, which an export
    does not carry (nor can an import in memory reach them): refused, naming them, before
    anything is written."""
    prior = meta.get("prior_from")
    if not prior:
        return
    try:
        named = ", ".join(f"{p['session']} ({p['subject']})" for p in prior)
    except (KeyError, TypeError):
        raise ExportError("manifest.json: bad prior_from in the session's meta") from None
    raise ExportError(
        f"session {info.get('id')} was warm-started from earlier sessions {named}: its model is "
        "rebuilt from their logs, which an export does not carry, so it cannot be imported "
        "(nothing was written); its answers are all in the export's tables"
    )


def _check_created(first: NewEvent, spec: SessionSpec) -> None:
    """The log's ``created`` event says what the manifest says the session was made of (replay
    reads them from the session's row): an edited seed, subject or config would make a session
    whose row disagrees with its own log, and whose next queries are not the original's."""
    if first.kind != log.CREATED:
        raise ExportError(f"events.jsonl line 1: a {first.kind!r} event, not 'created'")
    made = first.payload
    manifest = {
        "subject": ("session.subject", spec.subject),
        "config_name": ("config_name", spec.config_name),
        "config_sha256": ("config_sha256", spec.config_sha256),
        "seed": ("seed", spec.seed),
        "software_version": ("session.software_version", spec.software_version),
    }
    for key, (name, value) in manifest.items():
        if made.get(key) != value or type(made.get(key)) is not type(value):
            raise ExportError(
                f"manifest.json's {name} is {value!r}, but the session's created event "
                f"(events.jsonl line 1) says {made.get(key)!r}; nothing was written"
            )
    if made.get("prior_from") and not spec.meta.get("prior_from"):
        raise ExportError(
            "the session's created event (events.jsonl line 1) records a warm start that "
            "manifest.json's session.meta lacks; nothing was written"
        )
    ids = spec.meta.get("gait_ids")
    if bool(made.get("gait_library")) != (ids is not None):
        have = "names no gait library" if ids is None else "names a gait library"
        raise ExportError(
            f"manifest.json's session.meta {have} (gait_ids), but the session's created event "
            f"(events.jsonl line 1) says gait_library = {made.get('gait_library')!r}; nothing "
            "was written"
        )


def _check_gait_ids(events: Sequence[NewEvent], meta: dict[str, Any]) -> None:
    """Each trial walked a gait of the manifest's library, by the id its event logged (replay
    names gaits by the library in the session's meta)."""
    ids = meta.get("gait_ids")
    if ids is None:
        return
    if not isinstance(ids, list) or not all(isinstance(g, str) for g in ids):
        raise ExportError("manifest.json: session.meta.gait_ids must be a list of texts")
    for k, event in enumerate(events, start=1):
        logged, action = event.payload.get("gait_id"), event.payload.get("action")
        if event.kind != log.TRIAL or logged is None or not isinstance(action, int):
            continue
        named = ids[action] if 0 <= action < len(ids) else None
        if named != logged:
            raise ExportError(
                f"events.jsonl line {k}: trial {event.payload.get('trial')} walked gait "
                f"{logged!r} (action {action}), but manifest.json's session.meta.gait_ids names "
                f"it {named!r}; nothing was written"
            )


def origin_of(record: SessionRecord) -> str | None:
    """``"imported from session N"`` for a session made by :func:`import_session`, else None."""
    return record.origin


def _check_not_imported(
    where: str,
    spec: SessionSpec,
    info: dict[str, Any],
    made: datetime | None,
    sessions: list[SessionRecord],
) -> None:
    """Refuse an export whose session is among the subject's ``sessions`` in the database
    ``where`` (imported, or the original).  An original is known by its creation time: the
    exported session's, or its log's ``created`` event's (``made``), which every import keeps,
    so that an export of an imported copy is refused where its original is."""
    mine = spec.meta["imported_from"]
    for rec in sessions:
        origin = rec.meta.get("imported_from")
        again = isinstance(origin, dict) and origin.get("events_sha256") == mine["events_sha256"]
        same = rec.config_sha256 == spec.config_sha256 and rec.seed == spec.seed
        itself = same and rec.created_at.isoformat() == info.get("created_at")
        copied = same and made is not None and rec.created_at == made
        if again or itself or copied:
            how = (
                "imported before as"
                if again
                else "the exported session itself, as"
                if itself
                else "the session it is a copy of, as"
            )
            raise ExportError(
                f"this export (session {info.get('id')} of subject {spec.subject}) is already in "
                f"{where}: {how} session {rec.id}; nothing was written.  To keep a second "
                "copy under a new id, import it with --as-new"
            )


def _check_files(folder: Path, manifest: dict[str, Any]) -> None:
    """Every file the manifest lists is inside the folder and matches its SHA-256."""
    files = dict(manifest["files"])
    library = manifest.get("gait_library")
    if library is not None:
        if not (
            isinstance(library, dict)
            and isinstance(library.get("file"), str)
            and isinstance(library.get("sha256"), str)
        ):
            raise ExportError(f"manifest.json: bad gait_library entry {library!r}")
        files.setdefault(library["file"], library["sha256"])
    for name in ("config.toml", "events.jsonl"):
        if name not in files:
            raise ExportError(f"manifest.json lists no {name}")
    root = folder.resolve()
    hashed: dict[Path, str] = {}  # each file once, however many names (``./a``, ``a``) list it
    for name, expected in sorted(files.items()):
        path = (folder / str(name)).resolve()
        given = Path(str(name))
        if given.is_absolute() or ".." in given.parts or not path.is_relative_to(root):
            raise ExportError(f"manifest.json lists {name!r}, which is not inside the export")
        if path.is_dir():
            raise ExportError(f"{name}, which manifest.json lists, is a folder, not a file")
        if not path.is_file():
            raise ExportError(f"the export lacks {name}, which manifest.json lists")
        if path not in hashed:
            hashed[path] = _sha256(path)
        if hashed[path] != expected:
            raise ExportError(
                f"{name} does not match its SHA-256 in manifest.json (was it edited?); "
                "nothing was written"
            )


def _sha256(path: Path) -> str:
    """The file's SHA-256, read a block at a time: a huge file costs no memory."""
    with path.open("rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def _find_library(
    folder: Path, manifest: dict[str, Any], meta: dict[str, Any], config_text: str
) -> tuple[Path, str] | None:
    """Point ``meta`` at the exported copy of the gait library unless the original is intact;
    returns the copy and the original's path when ``meta`` points at the copy.

    A copy at the path the config names, taken from the export's folder (every export of a
    config naming its library by a relative path inside its folder), is found as the config
    names it (``config_dir``: the export's folder); a copy elsewhere (``gait_library/``: a
    config naming it by an absolute path or one with ``..``) is read from where it is, the
    session's meta saying so (``library_copied_from``: the path the exported session read).
    """
    original, sha = meta.get("library_path"), meta.get("library_sha256")
    if not original:
        return None
    if not isinstance(original, str):
        raise ExportError(
            f"manifest.json: session.meta.library_path must be a text, got {original!r}"
        )
    path = Path(original)
    if path.is_file() and _sha256(path) == sha:
        return None
    copy = manifest.get("gait_library")
    if not isinstance(copy, dict) or not (folder / str(copy.get("file"))).is_file():
        raise ExportError(
            f"the session's gait library {original} is missing or changed, and the export "
            "holds no copy of it"
        )
    _check_size(folder / copy["file"], copy["file"], MAX_LIBRARY_BYTES)
    if _sha256(folder / copy["file"]) != sha:
        raise ExportError(f"the exported gait library {copy['file']} does not match its SHA-256")
    where = (folder / copy["file"]).resolve()
    meta["library_path"] = str(where)
    if (folder / _library_named(config_text)).resolve() == where:  # as the config names it
        meta["config_dir"] = str(folder.resolve())
        meta.pop("library_copied_from", None)
    else:
        meta["library_copied_from"] = original
    return where, original


def _library_named(config_text: str) -> Path:
    """The gait library's path as the config names it (in the text, taken from nowhere)."""
    import tomllib

    try:
        return Path(str(tomllib.loads(config_text)["gaits"]["library"]))
    except (ValueError, KeyError, TypeError):  # replay names what is wrong with the config
        return Path()


#: the folder beside a SQLite database that keeps the gait libraries of imported sessions:
#: ``lab.db.libraries/<sha256>.json``
LIBRARY_COPY_SUFFIX: Final = ".libraries"


def _keep_library(
    storage: Storage,
    spec: SessionSpec,
    copy: Path,
    original: str,
    made: list[Path],
    held: contextlib.ExitStack,
) -> SessionSpec:
    """``spec`` reading its gait library from a copy of the export's ``copy`` next to a SQLite
    database (``lab.db.libraries/<sha256>.json``, shared by every session of that library), so
    that the imported session does not need the export's folder; ``spec`` as it is for a
    database that is not a local file (memory, PostgreSQL): it reads the export's copy.

    The file, when this call creates it (not when it was there: a copy is an earlier import's,
    whose session reads it), is appended to ``made``, for :func:`_unmake` to remove if the
    import is then refused.  The copy's lock (``.<sha256>.lock`` in the folder) is entered into
    ``held`` before the copy is looked for: the caller holds it until the session reading the
    copy is committed or :func:`_unmake` has run.  The folder, once made, stays (it holds the
    lock file, which is never removed: that would race)."""
    folder = storage.folder_beside(LIBRARY_COPY_SUFFIX)
    if folder is None:
        return spec
    sha = str(spec.meta["library_sha256"])
    target = folder / f"{sha}.json"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        held.enter_context(content_lock(folder, sha))
        if not (target.is_file() and _sha256(target) == sha):
            data = copy.read_bytes()
            if hashlib.sha256(data).hexdigest() != sha:
                raise OSError(f"{copy} changed after it was checked")
            new = not target.exists()  # a damaged copy replaced is not this import's own
            # whole, or not there: a concurrent import of the same library writes alike
            write_bytes_atomic(target, data, prefix=f".{sha[:16]}.")
            if new:
                made.append(target)
    except OSError as exc:
        raise ExportError(
            f"cannot copy the gait library into {folder} ({exc}); nothing was written"
        ) from None
    meta = dict(spec.meta)
    meta["library_copied_from"] = original  # the path the exported session read
    meta["library_path"] = str(target.resolve())
    return dataclasses.replace(spec, meta=meta)


def _unmake(storage: Storage, made: Sequence[Path]) -> None:
    """Remove what a refused import wrote beside the database (``made``, by
    :func:`_keep_library`), with the copy's lock held: its library copy, unless a session in the
    database already reads it (kept too when the database cannot say; a concurrent import of the
    same library waits for the lock, so none has found the copy and not yet committed).  Best
    effort: the refusal is what the caller sees."""
    for path in reversed(made):
        try:
            where = str(path.resolve())
            if any(r.meta.get("library_path") == where for r in storage.list_sessions()):
                return  # read by a session: keep it
        except Exception:  # the database cannot say: keep the copy
            return
        with contextlib.suppress(OSError):
            path.unlink()


def _read_manifest(folder: Path) -> dict[str, Any]:
    path = folder / "manifest.json"
    if not folder.exists():
        raise ExportError(f"{str(folder)!r} does not exist")
    if not folder.is_dir():
        raise ExportError(
            f"{str(folder)!r} is a file, not an export's folder (give the folder that holds "
            "manifest.json)"
        )
    if not path.is_file():
        raise ExportError(f"{str(folder)!r} is not a gaitpref export (no manifest.json)")
    _check_size(path, "manifest.json", MAX_TEXT_BYTES)
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (ValueError, RecursionError) as exc:  # UnicodeDecodeError is a ValueError
        raise ExportError(f"manifest.json is not JSON: {exc}") from None
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise ExportError(f"manifest.json is not a {FORMAT} manifest")
    version = manifest.get("format_version")
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise ExportError(
            f"manifest.json: format_version must be an integer from 1 to {FORMAT_VERSION}, "
            f"got {version!r}"
        )
    if version > FORMAT_VERSION:
        raise ExportError(
            f"export format version {version!r} is newer than this gaitpref reads "
            f"({FORMAT_VERSION}); use a newer gaitpref"
        )
    if not isinstance(manifest.get("files"), dict) or not isinstance(manifest.get("session"), dict):
        raise ExportError("manifest.json lacks its files or session entries")
    return manifest


def _read_checked(folder: Path, name: str, manifest: dict[str, Any], limit: int) -> str:
    """The text of ``name``: at most ``limit`` bytes, matching its SHA-256, UTF-8."""
    path = folder / name
    if not path.is_file():
        raise ExportError(f"the export lacks {name}")
    _check_size(path, name, limit)
    data = path.read_bytes()
    expected = manifest["files"].get(name)
    if hashlib.sha256(data).hexdigest() != expected:
        raise ExportError(f"{name} does not match its SHA-256 in manifest.json (was it edited?)")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ExportError(f"{name} is not UTF-8 text ({exc})") from None


def _check_size(path: Path, name: str, limit: int) -> None:
    size = path.stat().st_size
    if size > limit:
        raise ExportError(
            f"{name} holds {size:,} bytes, more than the {limit:,} an import reads; "
            "nothing was written"
        )


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _read_events(text: str) -> list[NewEvent]:
    """The events of ``events.jsonl``: one object a line with exactly the keys an export writes,
    numbered 1, 2, 3, ... in order."""
    lines = io.StringIO(text, newline="\n")  # one at a time, split at "\n" only
    out = []
    for k, line in enumerate(lines, start=1):
        where = f"events.jsonl line {k}"
        if k > MAX_EVENTS:
            raise ExportError(
                f"events.jsonl holds more than {MAX_EVENTS:,} events, the most an import reads; "
                "nothing was written"
            )
        try:
            row = json.loads(line)
        except (ValueError, RecursionError) as exc:
            raise ExportError(f"{where}: not JSON ({exc})") from None
        if not isinstance(row, dict):
            raise ExportError(f"{where}: a JSON {type(row).__name__}, not an object")
        missing, extra = EVENT_KEYS - row.keys(), row.keys() - EVENT_KEYS - {"version"}
        if missing or extra:
            raise ExportError(
                f"{where}: "
                + "; ".join(
                    [f"lacks {', '.join(sorted(missing))}"] * bool(missing)
                    + [f"has keys an export does not write: {', '.join(sorted(extra))}"]
                    * bool(extra)
                )
            )
        seq = row["seq"]
        if not _is_int(seq):
            raise ExportError(f"{where}: seq must be an integer, got {seq!r}")
        if seq != k:
            raise ExportError(
                f"{where}: seq {seq} where {k} was expected (the events are numbered 1, 2, 3, "
                "... in order, each once)"
            )
        if not isinstance(row["at"], str):
            raise ExportError(f"{where}: at must be an ISO time text, got {row['at']!r}")
        try:
            at = datetime.fromisoformat(row["at"])
        except ValueError as exc:
            raise ExportError(f"{where}: at: {exc}") from None
        event = NewEvent(row["kind"], row["payload"], at, row.get("version", 1))
        try:
            out.append(check_event(event, where))
        except StorageError as exc:
            raise ExportError(str(exc)) from None
    if not out:
        raise ExportError("events.jsonl is empty")
    return out


def _check_session_entry(manifest: dict[str, Any], events: int) -> None:
    """The manifest's seed and session entry have the types an export writes, and the session
    has as many events as ``events.jsonl`` holds."""
    info = manifest["session"]
    if not _is_int(manifest.get("seed")):
        raise ExportError(f"manifest.json: seed must be an integer, got {manifest.get('seed')!r}")
    if not _is_int(info.get("id")):
        raise ExportError(f"manifest.json: session.id must be an integer, got {info.get('id')!r}")
    if not isinstance(info.get("meta", {}), dict):
        raise ExportError(
            f"manifest.json: session.meta must be an object, got {type(info['meta']).__name__}"
        )
    last = info.get("last_seq")
    if last is not None and last != events:
        raise ExportError(
            f"events.jsonl holds {events} events but manifest.json's session.last_seq is "
            f"{last!r}: the log was cut short or added to (or an earlier gaitpref exported it "
            "while another writer went on); nothing was written"
        )


def _check_summary(session: Session, summary: object) -> None:
    """The replayed posterior's best action and its mean are the exported summary's."""
    if not summary:
        return
    if not isinstance(summary, dict):
        raise ExportError(
            f"manifest.json: posterior must be an object, got {type(summary).__name__}"
        )
    exported, argmax = summary.get("mean_at_argmax"), summary.get("argmax")
    if not (exported is None or isinstance(exported, int | float)) or isinstance(exported, bool):
        raise ExportError(
            f"manifest.json: posterior.mean_at_argmax must be a number, got {exported!r}"
        )
    post = session.posterior()
    if not len(session.space):  # the line path before its first query: no point, no argmax
        if argmax is not None:
            raise ReplayError(
                f"the imported session's posterior has no point yet; the export names best "
                f"action {argmax!r}"
            )
        return
    best = post.argmax
    if best != argmax or not np.isclose(
        float(post.mean[best]),
        float(exported if exported is not None else np.nan),
        rtol=1e-9,
        atol=1e-12,
    ):
        raise ReplayError(
            f"the imported session's posterior differs from the exported summary: best action "
            f"{best} (mean {float(post.mean[best])!r}) here, {argmax!r} "
            f"(mean {exported!r}) in the export"
        )
