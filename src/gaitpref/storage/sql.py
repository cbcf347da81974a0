"""The SQLAlchemy 2 :class:`~gaitpref.storage.base.Storage`: SQLite (default) and PostgreSQL.

- SQLite: WAL journal, ``synchronous=FULL`` (a commit survives a power cut), a busy timeout,
  foreign keys on, and writes in ``BEGIN IMMEDIATE`` transactions so that concurrent writers
  queue instead of failing half-way.
- PostgreSQL (``postgresql+psycopg://user@host/db``): the session row is locked
  (``SELECT ... FOR UPDATE``) while a batch is appended.
- SQLite files: the writers of a session take turns (:mod:`gaitpref.storage.turns`, lock files in
  ``<db>.turns/``), so that two processes answering one session alternate instead of one
  starving the other.
- Both: the append is a compare-and-set on ``sessions.last_seq`` and ``(session_id, seq)`` is the
  events' primary key, so two writers can never both append the same sequence number.

Opening checks the connection and the schema (``migrate.check_schema``, in a read transaction
unless it creates the schema) and raises :class:`StorageConnectError` / :class:`SchemaError` with
the URL (password masked).
"""

from __future__ import annotations

import contextlib
import functools
import json
import os
import re
import sqlite3
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sqlalchemy import (
    Connection,
    Engine,
    Text,
    create_engine,
    event,
    func,
    insert,
    select,
    type_coerce,
    update,
)
from sqlalchemy.dialects.postgresql import insert as pg_insert
from sqlalchemy.dialects.sqlite import insert as sqlite_insert
from sqlalchemy.engine import URL, make_url
from sqlalchemy.exc import (
    ArgumentError,
    DatabaseError,
    DBAPIError,
    IntegrityError,
    OperationalError,
    SQLAlchemyError,
)
from sqlalchemy.pool import StaticPool

from gaitpref.errors import StorageError
from gaitpref.storage import base, migrate
from gaitpref.storage.base import (
    CheckedCreation,
    ConflictError,
    EventRecord,
    NewEvent,
    SchemaError,
    SessionBusyError,
    SessionFinishedError,
    SessionNotFoundError,
    SessionRecord,
    SessionsCheck,
    SessionSpec,
    Status,
    StorageConnectError,
    StorageFailureError,
    SubjectRecord,
    as_utc,
    check_event,
    check_status,
    now,
)
from gaitpref.storage.schema import events as events_t
from gaitpref.storage.schema import sessions as sessions_t
from gaitpref.storage.schema import subjects as subjects_t
from gaitpref.storage.turns import FileTurns
from gaitpref.wording import plural

BUSY_TIMEOUT_S = 30.0


def parse_url(url: str) -> URL:
    """``url`` as a SQLAlchemy URL; ``postgresql://`` means the psycopg 3 driver."""
    try:
        parsed = make_url(url)
    except (ArgumentError, ValueError) as exc:  # ValueError: a port that is not a number
        why = "" if isinstance(exc, ArgumentError) else f": {exc}"
        raise StorageConnectError(
            f"{_unparsed_masked(url)!r} is not a database URL{why} (expected e.g. "
            "sqlite:///gaitpref.db or "
            "postgresql+psycopg://user@host:5432/dbname)"
        ) from None
    if parsed.host is not None and "@" in parsed.host:
        # a password with an unencoded @ ("p@ss"): the URL reads as password "p", host "ss@h",
        # and the host (half the password) was printed, by the URL and the driver's error
        raise StorageConnectError(
            f"{_unparsed_masked(url)!r} has more than one @ before its host: a password or "
            "user name with an @ in it is URL-encoded, %40 for @ (and %3A for :, %2F for /, "
            "%3F for ?, %23 for #, %25 for %, %20 for a space)"
        )
    if parsed.drivername in ("postgresql", "postgres"):
        parsed = parsed.set(drivername="postgresql+psycopg")
    if parsed.get_backend_name() not in ("sqlite", "postgresql"):
        raise StorageConnectError(
            f"unsupported database {parsed.get_backend_name()!r} in {_masked(parsed)}: "
            "gaitpref stores sessions in SQLite or PostgreSQL"
        )
    if parsed.get_backend_name() == "sqlite" and parsed.query:
        # the driver ignores most of them silently (``?mode=ro`` still wrote), and the file's
        # lock files, fit cache and turns are found by its path
        raise StorageConnectError(
            f"{_masked(parsed)}: gaitpref does not apply SQLite URL parameters "
            f"({', '.join(sorted(parsed.query))}); give the file alone, e.g. sqlite:///lab.db "
            "(to read a database without writing to it, export its sessions or copy the file)"
        )
    return parsed


#: the first key of every session's advisory lock (``pg_advisory_xact_lock(space, session id)``):
#: "gait" in ASCII, so that other users of the server's advisory locks are not waited on
_TURN_SPACE = 0x67616974


#: libpq connection parameters whose values are secrets: the server password, the client key's
#: password (``sslpassword``) and an OAuth client's secret (libpq 18); the others are names,
#: modes and paths (``passfile``, ``sslkey``: the files, not what they hold). Never printed, never
#: in the pg_dump command; matched in any case (libpq refuses ``?SSLPassword=``, and the error
#: printed the URL with it)
SECRET_PARAMETERS = ("password", "sslpassword", "oauth_client_secret")


def _secret_keys(url: URL) -> list[str]:
    """The keys of ``url``'s parameters that hold a secret (see ``SECRET_PARAMETERS``)."""
    return [key for key in url.query if key.lower() in SECRET_PARAMETERS]


def _masked(url: URL) -> str:
    """``url`` to print: its password as ``***``, the value of every secret parameter too
    (``?password=``, ``?sslpassword=``: libpq takes them there, and they were printed whole)."""
    keys = _secret_keys(url)
    if not keys:
        return url.render_as_string(hide_password=True)
    hidden = url.update_query_dict(dict.fromkeys(keys, "***")).render_as_string(hide_password=True)
    for key in keys:
        hidden = hidden.replace(f"{key}=%2A%2A%2A", f"{key}=***")
    return hidden


def masked_url(url: str) -> str:
    """``url`` to print: its password and secret parameters (if any) shown as ``***``, whether
    it parses or not."""
    try:
        parsed = make_url(url)
    except (ArgumentError, ValueError):
        return _unparsed_masked(url)
    if parsed.host is not None and "@" in parsed.host:  # "p@ss" unencoded: "ss@" in the host
        return _unparsed_masked(url)
    return _masked(parsed) if parsed.password is not None or _secret_keys(parsed) else url


def _has_password(url: URL) -> bool:
    """Whether ``url`` holds a password: in its authority, or a ``?password=`` parameter."""
    return url.password is not None or "password" in url.query


_SECRET_PARAMETER = re.compile(
    r"([?&](?:" + "|".join(SECRET_PARAMETERS) + r")=)[^&#]*", flags=re.IGNORECASE
)


def _unparsed_masked(url: str) -> str:
    """``url``, which could not be parsed, with what may be a password (between ``user:`` and
    the last ``@`` of its authority) and the values of its secret parameters shown as ``***``: a
    URL with a port that is not a number was printed whole, password and all."""
    scheme, sep, rest = url.partition("://")
    if not sep:
        return url
    rest = _SECRET_PARAMETER.sub(r"\1***", rest)
    # the authority ends at the last @ before the parameters (the first = after a ?): a password
    # typed as it is may hold / ? # @ (a '/' in it printed it whole)
    question = rest.find("?")
    equals = rest.find("=", question) if question >= 0 else -1
    at = rest.rfind("@", 0, equals if equals >= 0 else len(rest))
    userinfo, host_and_path = rest[: max(at, 0)], rest[at + 1 :]
    if at < 0 or ":" not in userinfo:
        return f"{scheme}://{rest}"
    user = userinfo.split(":", 1)[0]
    return f"{scheme}://{user}:***@{host_and_path}"


class SQLStorage(CheckedCreation):
    """Sessions in a SQL database through SQLAlchemy 2 (see the module docstring)."""

    def __init__(self, url: str, *, create: bool = True) -> None:
        parsed = parse_url(url)
        self.url = _masked(parsed)
        self._sqlite = parsed.get_backend_name() == "sqlite"
        if self._sqlite and not _sqlite_memory(parsed):
            path = Path(parsed.database or "")
            if not create and not path.exists():
                raise StorageConnectError(
                    f"no gaitpref database at {self.url} (the file {str(path)!r} does not "
                    "exist); create one with `gaitpref db upgrade` or `gaitpref session new`"
                )
            if not path.parent.is_dir():
                raise StorageConnectError(
                    f"cannot open {self.url}: the folder {str(path.parent)!r} does not exist"
                )
            _refuse_folder(path, self.url)
        self._turns: FileTurns | None = None
        self._file: Path | None = None
        if self._sqlite and not _sqlite_memory(parsed):
            path = Path(parsed.database or "").resolve()
            self._file = path
            self._turns = FileTurns(path.with_name(path.name + ".turns"), self.url)
        self.engine = _engine(parsed, create)
        self._identity: tuple[int, int] | None = None  # the file's (device, inode) once open
        try:
            # a read transaction unless the schema is to be made: opening a database to read it
            # does not wait for (or on SQLite, time out behind) another process's write lock
            with self._read() as conn:
                empty = migrate.current_revision(conn) is None
            with self._write() if empty and create else self._read() as conn:
                migrate.check_schema(conn, self.url, create)
            if self._file is not None:
                self._identity = _identity(self._file)
        except StorageError:
            self.engine.dispose()
            raise
        except (DBAPIError, SQLAlchemyError, OSError, ImportError) as exc:
            self.engine.dispose()
            raise StorageConnectError(f"cannot open {self.url}: {_reason(exc)}") from None

    # -- Storage -----------------------------------------------------------------------------
    def _create(
        self,
        spec: SessionSpec,
        events: Sequence[NewEvent],
        status: Status,
        check: SessionsCheck | None,
    ) -> SessionRecord:
        stamp = now()
        with self._write() as conn:
            ins = sqlite_insert if self._sqlite else pg_insert
            conn.execute(
                ins(subjects_t)
                .values(code=spec.subject, created_at=stamp)
                .on_conflict_do_nothing(index_elements=["code"])
            )
            if check is not None:
                # SQLite: BEGIN IMMEDIATE already holds the database's write lock.  PostgreSQL:
                # every creator of this subject's sessions locks its row, so the next one waits
                # here and then (READ COMMITTED) reads the sessions committed before it
                if not self._sqlite:
                    conn.execute(
                        select(subjects_t.c.code)
                        .where(subjects_t.c.code == spec.subject)
                        .with_for_update()
                    )
                mine = select(sessions_t).where(sessions_t.c.subject == spec.subject)
                check(
                    [
                        _session(r._mapping, self.url)
                        for r in conn.execute(mine.order_by(sessions_t.c.id))
                    ]
                )
            sid = conn.execute(
                insert(sessions_t)
                .values(
                    subject=spec.subject,
                    config_name=spec.config_name,
                    config_text=spec.config_text,
                    config_sha256=spec.config_sha256,
                    seed=spec.seed,
                    software_version=spec.software_version,
                    status=status,
                    created_at=stamp,
                    updated_at=stamp,
                    last_seq=len(events),
                    meta=spec.meta,
                )
                .returning(sessions_t.c.id)
            ).scalar_one()
            if events:
                conn.execute(insert(events_t), _rows(sid, 0, events, stamp))
            row = conn.execute(select(sessions_t).where(sessions_t.c.id == sid)).one()
        return _session(row._mapping, self.url)

    def get_session(self, session_id: int) -> SessionRecord:
        with self._read() as conn:
            row = conn.execute(
                select(sessions_t).where(sessions_t.c.id == _sid(session_id))
            ).first()
        if row is None:
            raise SessionNotFoundError(f"no session {session_id!r} in {self.url}")
        return _session(row._mapping, self.url)

    def list_sessions(self, subject: str | None = None) -> list[SessionRecord]:
        query = select(sessions_t).order_by(sessions_t.c.id)
        if subject is not None:
            query = query.where(sessions_t.c.subject == subject)
        with self._read() as conn:
            return [_session(r._mapping, self.url) for r in conn.execute(query)]

    def list_subjects(self) -> list[SubjectRecord]:
        with self._read() as conn:
            rows = conn.execute(select(subjects_t).order_by(subjects_t.c.code)).all()
        return [SubjectRecord(r.code, as_utc(r.created_at)) for r in rows]

    def append(
        self,
        session_id: int,
        after: int,
        events: Sequence[NewEvent],
        status: Status | None = None,
    ) -> list[EventRecord]:
        checked = [check_event(e, f"event {k}") for k, e in enumerate(events)]
        new_status = None if status is None else check_status(status)
        sid = _sid(session_id)
        stamp = now()
        try:
            with self._write() as conn:
                query = select(sessions_t.c.last_seq, sessions_t.c.status).where(
                    sessions_t.c.id == sid
                )
                row = conn.execute(query if self._sqlite else query.with_for_update()).first()
                if row is None:
                    raise SessionNotFoundError(f"no session {session_id!r} in {self.url}")
                if row.status == "finished":
                    raise SessionFinishedError(f"session {session_id} is finished")
                if row.last_seq != after:
                    raise _conflict(session_id, row.last_seq, after)
                rows = _rows(sid, after, checked, stamp)
                if rows:
                    conn.execute(insert(events_t), rows)
                values: dict[str, Any] = {"last_seq": after + len(rows), "updated_at": stamp}
                if new_status is not None:
                    values["status"] = new_status
                done = conn.execute(
                    update(sessions_t)
                    .where(sessions_t.c.id == sid, sessions_t.c.last_seq == after)
                    .values(**values)
                )
                if done.rowcount != 1:
                    raise _conflict(session_id, None, after)
        except IntegrityError:
            raise _conflict(session_id, None, after) from None
        return [
            EventRecord(sid, r["seq"], r["kind"], r["payload"], as_utc(r["at"]), r["version"])
            for r in rows
        ]

    def events(self, session_id: int, after: int = 0) -> list[EventRecord]:
        sid = _sid(session_id)
        with self._read() as conn:
            found = conn.execute(select(sessions_t.c.id).where(sessions_t.c.id == sid)).first()
            if found is None:
                raise SessionNotFoundError(f"no session {session_id!r} in {self.url}")
            raw = type_coerce(events_t.c.payload, Text).label("payload")  # parsed below, by row
            rows = conn.execute(
                select(
                    events_t.c.session_id,
                    events_t.c.seq,
                    events_t.c.kind,
                    raw,
                    events_t.c.at,
                    events_t.c.version,
                )
                .where(events_t.c.session_id == sid, events_t.c.seq > after)
                .order_by(events_t.c.seq)
            ).all()
        return [
            EventRecord(r.session_id, r.seq, r.kind, _payload(r, self.url), as_utc(r.at), r.version)
            for r in rows
        ]

    @contextmanager
    def writer_turn(self, session_id: int, wait_s: float | None = None) -> Iterator[None]:
        """SQLite files: a fair turn shared by every process (lock files in ``<db>.turns/``).

        PostgreSQL: the server's advisory lock of the session (``pg_advisory_xact_lock``,
        waiters served in turn, the wait bounded by ``lock_timeout``), held by a transaction of
        its own, which ends with the turn (or when its connection is lost; the server's
        ``idle_in_transaction_session_timeout`` is off for it).  Without it two
        writers of one session (the console and the terminal) raced: the one whose append lost
        the compare-and-set raised ``ConflictError`` ("another writer appended to it; reload
        it").
        """
        wait = base.WRITER_WAIT_S if wait_s is None else wait_s
        if self._turns is not None:
            with self._turns.turn(_sid(session_id), wait):
                yield
        elif self._sqlite:  # in memory: one process, the Session's own lock is enough
            yield
        else:
            with self._pg_turn(_sid(session_id), wait):
                yield

    @contextmanager
    def _pg_turn(self, session_id: int, wait_s: float) -> Iterator[None]:
        # a transaction's lock (pg_advisory_xact_lock), in a transaction of its own kept open
        # for the turn and rolled back to end it: it cannot outlive the turn, and a pooler in
        # transaction mode (PgBouncer) keeps the turn's server connection for that transaction
        with self._errors():  # only the taking: what the turn's holder raises passes as it is
            conn = self.engine.connect()
            try:
                timeout = f"{max(1, int(wait_s * 1000))}ms"
                # the transaction is idle while the session computes (a refit, a replay): a
                # server's idle_in_transaction_session_timeout ended it, and the turn with it,
                # mid-operation (another writer then wrote first); off for it alone (SET LOCAL)
                conn.execute(
                    select(
                        func.set_config("lock_timeout", timeout, True),
                        func.set_config("idle_in_transaction_session_timeout", "0", True),
                    )
                )
                conn.execute(select(func.pg_advisory_xact_lock(_TURN_SPACE, session_id)))
            except OperationalError as exc:
                conn.close()
                if getattr(exc.orig, "sqlstate", None) != "55P03":  # lock_not_available
                    raise
                raise SessionBusyError(
                    f"session {session_id} in {self.url} is busy: another writer held it for "
                    f"{wait_s:.1f} s (the most this one waits); nothing was written, try again"
                ) from None
            except BaseException:
                conn.close()
                raise
        try:
            yield
        finally:
            with contextlib.suppress(DBAPIError):  # a lost connection let it go already
                conn.rollback()  # ends the transaction: the lock is let go
            conn.close()

    def folder_beside(self, suffix: str) -> Path | None:
        return None if self._file is None else self._file.with_name(self._file.name + suffix)

    def close(self) -> None:
        self.engine.dispose()

    # -- transactions ------------------------------------------------------------------------
    @contextmanager
    def _write(self) -> Iterator[Connection]:
        """A write transaction (``BEGIN IMMEDIATE`` on SQLite), committed on leaving, and rolled
        back if the SQLite file was deleted or replaced since it was opened: the open connection
        would commit into the unlinked file, and the write would be lost.  A database error
        in it (locked past the busy timeout, a disk I/O error) rolls it back: the
        :class:`StorageFailureError` says nothing was written."""
        with self._errors(writing=True), self.engine.connect() as conn:
            conn.execution_options(gaitpref_write=True)
            with conn.begin():
                yield conn
                self._check_same_file()

    def _check_same_file(self) -> None:
        if self._file is None or self._identity is None:
            return
        try:
            same = _identity(self._file) == self._identity
        except OSError:
            same = False
        if not same:
            raise StorageFailureError(
                f"{self.url}: the database file {str(self._file)!r} was deleted, moved or "
                "replaced since it was opened; nothing was written (a write now would be lost "
                "with the old file): open the database again"
            )

    @contextmanager
    def _read(self) -> Iterator[Connection]:
        """A read transaction; refused, as a write is, once the SQLite file was deleted or
        replaced (a pooled connection reads the old file, a new one the file there now)."""
        with self._errors(), self.engine.connect() as conn, conn.begin():
            self._check_same_file()
            yield conn

    @contextmanager
    def _errors(self, writing: bool = False) -> Iterator[None]:
        try:
            yield
        except IntegrityError:
            raise
        except ValueError as exc:  # a stored value its column's type cannot read back
            raise StorageError(
                f"{self.url}: a stored value cannot be read ({exc}); the database was altered or "
                "damaged outside gaitpref: restore it from a backup"
            ) from None
        except DBAPIError as exc:
            if exc.connection_invalidated or _unreachable(str(exc.orig)):
                raise StorageConnectError(f"cannot connect to {self.url}: {_reason(exc)}") from None
            said = f"{self.url}: {_reason(exc)}{_hint(self._file, exc)}"
            if isinstance(exc, DatabaseError):  # OperationalError (disk I/O, locked, ...) too
                # a write's transaction was rolled back: say so, so that the operator who
                # confirmed an answer knows to give it again (a lost connection is not said:
                # whether a commit it cut short was applied is not known here)
                unwritten = "; nothing was written" if writing else ""
                raise StorageFailureError(said + unwritten) from None
            raise StorageError(said) from None


#: what the driver says when no connection could be made at all: a refused or lost connection,
#: and a host name that does not resolve (libpq 16+: "failed to resolve host"; earlier: "could
#: not translate host name"), which was reported as a failed statement
_UNREACHABLE = ("connect", "resolve host", "translate host name")


def _unreachable(message: str) -> bool:
    said = message.lower()
    return any(words in said for words in _UNREACHABLE)


def upgrade_database(url: str) -> str:
    """Create the database's schema, or migrate it to the newest; returns the masked URL."""
    parsed = parse_url(url)
    if parsed.get_backend_name() == "sqlite" and not _sqlite_memory(parsed):
        folder = Path(parsed.database or "").parent
        if not folder.is_dir():
            raise StorageConnectError(
                f"cannot open {_masked(parsed)}: the folder {str(folder)!r} does not exist"
            )
        _refuse_folder(Path(parsed.database or ""), _masked(parsed))
    engine = _engine(parsed)
    try:
        with engine.connect() as conn:
            conn.execution_options(gaitpref_write=True)
            with conn.begin():
                migrate.upgrade(conn)
    except (DBAPIError, SQLAlchemyError, OSError, ImportError) as exc:
        file = None if _sqlite_memory(parsed) else Path(parsed.database or "")
        hint = _hint(file, exc) if parsed.get_backend_name() == "sqlite" else ""
        raise StorageConnectError(f"cannot open {_masked(parsed)}: {_reason(exc)}{hint}") from None
    finally:
        engine.dispose()
    SQLStorage(url).close()  # opens it the way every command will
    return _masked(parsed)


def database_status(url: str) -> str:
    """One line on the database at ``url`` (creates nothing, writes nothing).

    Says which of these it is: missing; created or upgraded but interrupted before the schema
    was committed (an empty file, or leftover ``-wal``/``-journal`` files); a gaitpref database
    at the newest revision, with its counts; one that needs ``gaitpref db upgrade``; one from a
    newer gaitpref; or not a gaitpref database.
    """
    parsed = parse_url(url)
    where = _masked(parsed)
    _plain_engine(parsed).dispose()  # a driver that cannot be loaded is refused, as on opening
    if parsed.get_backend_name() == "sqlite" and not _sqlite_memory(parsed):
        path = Path(parsed.database or "")
        near = (path.with_name(path.name + suffix) for suffix in ("-wal", "-journal"))
        leftovers = [p.name for p in near if p.exists()]
        if not path.exists():
            return (
                f"{where}: no database (the file {str(path)!r} does not exist); create one with "
                "`gaitpref db upgrade`"
            )
        if path.stat().st_size == 0 or (leftovers and not _has_tables(parsed)):
            extra = f" (left over: {', '.join(leftovers)})" if leftovers else ""
            return (
                f"{where}: the file exists but holds no committed schema{extra}: its creation "
                "or upgrade was interrupted before it committed; nothing in it is lost "
                "(no session was ever written); run `gaitpref db upgrade` again"
            )
    try:
        store = SQLStorage(url, create=False)
    except StorageError as exc:
        if isinstance(exc, StorageConnectError) and parsed.get_backend_name() == "postgresql":
            # the server down, a wrong password, no database of that name: no state was read,
            # so an error (exit status 2), not a status line (exit status 0, the URL twice)
            raise
        text = str(exc)  # most name the database already
        return text if text.startswith(where) else f"{where}: {text}"
    try:
        sessions, subjects = len(store.list_sessions()), len(store.list_subjects())
    finally:
        store.close()
    return (
        f"{where}: schema revision {migrate.head_revision()} (the newest), "
        f"{plural(sessions, 'session')}, {plural(subjects, 'subject')}"
    )


@dataclass(frozen=True)
class Backup:
    """A verified copy of a SQLite database: where, and what it holds."""

    path: Path
    revision: str
    sessions: int
    events: int


def backup_database(url: str, out: Path) -> Backup:
    """Copy the SQLite database at ``url`` to the new file ``out``, verified.

    The copy is made with SQLite's online backup API in one step inside a read transaction, so
    it is one consistent state of the database even while another process (the console) is
    writing; it is written to a temporary file beside ``out``, checked (``PRAGMA quick_check``,
    the same schema revision, the same numbers of sessions and events as the state it copied),
    and only then linked to ``out``, which must not exist.  SQLite's backup bumps three counters
    in the copy's header (the change counter, the schema cookie and its version-valid-for
    number): every page else is the original's.  PostgreSQL is refused with the ``pg_dump``
    command to use instead.
    """
    parsed = parse_url(url)
    where = _masked(parsed)
    if parsed.get_backend_name() != "sqlite":
        raise StorageError(
            f"{where}: gaitpref backs up SQLite files only; {_pg_dump_hint(parsed, out)}"
        )
    if _sqlite_memory(parsed):
        raise StorageError(f"{where} is an in-memory database: there is no file to back up")
    source = Path(parsed.database or "")
    if not source.exists():
        raise StorageConnectError(
            f"no gaitpref database at {where} (the file {str(source)!r} does not exist)"
        )
    _refuse_folder(source, where)
    if out.exists() or out.is_symlink():
        raise StorageError(f"{str(out)!r} exists: give a new file name (nothing was written)")
    if not out.parent.is_dir():
        raise StorageError(f"cannot write {str(out)!r}: its folder does not exist")
    import tempfile

    fd, tmp_name = tempfile.mkstemp(dir=out.parent, prefix=f".{out.name}.", suffix=".tmp")
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        os.chmod(tmp, source.stat().st_mode & 0o777)
        src = sqlite3.connect(source, timeout=BUSY_TIMEOUT_S, isolation_level=None)
        try:
            src.execute("BEGIN")  # one snapshot: the counts and the pages copied
            revision, sessions, events = _counts(src, where)
            dst = sqlite3.connect(tmp, isolation_level=None)
            try:
                src.backup(dst)  # pages=-1: every page in one step, from this snapshot
            finally:
                dst.close()
            src.execute("COMMIT")
        finally:
            src.close()
        with tmp.open("rb+") as fh:
            os.fsync(fh.fileno())
        copy = sqlite3.connect(tmp, isolation_level=None)
        try:
            check = copy.execute("PRAGMA quick_check").fetchall()
            got = _counts(copy, f"the copy {str(tmp)!r}")
        finally:
            copy.close()
        if check != [("ok",)] or got != (revision, sessions, events):
            raise StorageFailureError(
                f"the copy of {where} does not match it (quick_check {check[:3]}, revision, "
                f"sessions, events {got} instead of {(revision, sessions, events)}); nothing "
                f"was written to {str(out)!r}"
            )
        try:
            os.link(tmp, out)  # never over a file made meanwhile
        except FileExistsError:
            raise StorageError(
                f"{str(out)!r} exists: give a new file name (nothing was written)"
            ) from None
        _fsync_folder(out.parent)
    except sqlite3.Error as exc:
        raise StorageFailureError(f"cannot back up {where}: {exc}") from None
    finally:
        tmp.unlink(missing_ok=True)
    return Backup(out, revision, sessions, events)


def backup_before_upgrade(url: str) -> Backup | None:
    """The backup ``gaitpref db upgrade`` makes first: for a SQLite file at a schema revision
    this gaitpref knows and would migrate, a copy beside it named
    ``NAME.before-<newest revision>.bak`` (``-2``, ``-3``, ... before ``.bak`` when taken);
    None (nothing written) for PostgreSQL, a missing, empty or foreign file, or one at the
    newest revision or a newer gaitpref's (which the upgrade refuses)."""
    parsed = parse_url(url)
    if parsed.get_backend_name() != "sqlite" or _sqlite_memory(parsed):
        return None
    source = Path(parsed.database or "")
    if not source.is_file() or source.stat().st_size == 0:
        return None
    try:
        raw = sqlite3.connect(source, timeout=BUSY_TIMEOUT_S)
        try:
            rows = raw.execute("SELECT version_num FROM alembic_version").fetchall()
        finally:
            raw.close()
    except sqlite3.Error:  # no gaitpref schema, or not a database: the upgrade says which
        return None
    head = migrate.head_revision()
    if len(rows) != 1 or rows[0][0] == head or rows[0][0] not in migrate.known_revisions():
        return None
    name = f"{source.name}.before-{head}"
    target = source.with_name(f"{name}.bak")
    n = 1
    while target.exists() or target.is_symlink():
        n += 1
        target = source.with_name(f"{name}-{n}.bak")
    return backup_database(url, target)


def _counts(conn: sqlite3.Connection, where: str) -> tuple[str, int, int]:
    try:
        rows = conn.execute("SELECT version_num FROM alembic_version").fetchall()
        sessions = conn.execute("SELECT count(*) FROM sessions").fetchone()[0]
        events = conn.execute("SELECT count(*) FROM events").fetchone()[0]
    except sqlite3.DatabaseError as exc:
        if isinstance(exc, sqlite3.OperationalError) and "no such table" not in str(exc):
            raise  # locked, I/O: not a verdict on what the file is
        raise SchemaError(f"{where} is not a gaitpref database ({exc})") from None
    if len(rows) != 1:
        raise SchemaError(f"{where}: alembic_version holds {len(rows)} rows; expected exactly one")
    return str(rows[0][0]), int(sessions), int(events)


def _fsync_folder(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _pg_dump_hint(url: URL, out: Path) -> str:
    """The ``pg_dump`` command for ``url``'s database (the password never shown)."""
    import shlex

    def given(key: str) -> str | None:  # ?host=/run/postgresql (a socket folder), ?port=5433
        value = url.query.get(key)
        return value if isinstance(value, str) and value else None

    parts = ["pg_dump", "--format=custom", f"--file={shlex.quote(str(out))}"]
    # the host and port of a socket URL (postgresql+psycopg://lab@/gaitlab?host=/run/...) are
    # its parameters: left out, pg_dump dumped the database of the default socket's server
    host, port = url.host or given("host"), url.port or given("port")
    if host:
        parts.append(f"--host={shlex.quote(host)}")
    if port:
        parts.append(f"--port={shlex.quote(str(port))}")
    if url.username:
        parts.append(f"--username={shlex.quote(url.username)}")
    # the URL's other libpq parameters (?sslmode=require&sslrootcert=...) were left out, and
    # pg_dump has no flag for most: the database is then a conninfo string that carries them
    # (its values override nothing the flags give); no secret is among them (SECRET_PARAMETERS:
    # the password, the client key's, which libpq asks for when it is not given)
    secrets = _secret_keys(url)
    extra = {k: v for k, v in url.query.items() if k not in ("host", "port", *secrets)}
    if extra:
        pairs = {"dbname": url.database or "", **extra}
        parts.append(shlex.quote(" ".join(f"{k}={_conninfo_value(v)}" for k, v in pairs.items())))
    else:
        parts.append(shlex.quote(url.database or ""))
    secret = " (the password: $PGPASSWORD or ~/.pgpass)" if _has_password(url) else ""
    return (
        f"back a PostgreSQL database up with its own tool, e.g. `{' '.join(parts)}`{secret}; "
        "restore with pg_restore"
    )


def _conninfo_value(value: str | tuple[str, ...]) -> str:
    """A libpq ``key=value`` connection string's value, quoted where it must be (empty, or with
    a space, ``'`` or ``\\``); a repeated URL parameter: its values joined by commas, as libpq
    reads several hosts."""
    joined = value if isinstance(value, str) else ",".join(value)
    if joined and not any(c.isspace() or c in "'\\" for c in joined):
        return joined
    return "'" + joined.replace("\\", "\\\\").replace("'", "\\'") + "'"


def _has_tables(url: URL) -> bool:
    """Whether the SQLite file holds a table; True too when it cannot be read (not a database,
    unreadable): opening it then names the problem, as without leftover files."""
    engine = _plain_engine(url)
    try:
        with engine.connect() as conn:
            return bool(conn.exec_driver_sql("SELECT name FROM sqlite_master").first())
    except DBAPIError:
        return True
    finally:
        engine.dispose()


# -- helpers -----------------------------------------------------------------------------------
#: What to do with a file SQLite cannot read as a database (by its message's words).
DAMAGED = {
    "file is not a database": (
        "the file is not a SQLite database, or its first page is damaged: check that --db "
        "names the database; if it does, restore it from a backup (gaitpref db backup makes "
        "them) and keep this file as it is"
    ),
    "database disk image is malformed": (
        "the file is damaged: restore it from a backup (gaitpref db backup makes them) and "
        "keep this file as it is"
    ),
}


def _hint(file: Path | None, exc: BaseException) -> str:
    """Why SQLite could not open the file: its folder is read-only (an existing file's -wal and
    -shm files, or a new database, cannot be made there), or the file is not a database or is
    damaged (:data:`DAMAGED`: what to do)."""
    if file is None:
        return ""
    reason = _reason(exc)
    for words, what in DAMAGED.items():
        if words in reason:
            return f" ({what})"
    if "unable to open database file" not in reason:
        return ""
    folder = file.resolve().parent
    if not folder.is_dir() or os.access(folder, os.W_OK):
        return ""
    if file.is_file():
        return (
            f" (the folder {str(folder)!r} is read-only: SQLite creates the database's -wal "
            "and -shm files beside it even to read; copy the database to a writable folder)"
        )
    if not file.exists():
        return (
            f" (the folder {str(folder)!r} is read-only: a new database cannot be made in it; "
            "name a file in a writable folder)"
        )
    return ""


def _refuse_folder(path: Path, where: str) -> None:
    if path.is_dir():
        raise StorageConnectError(
            f"cannot open {where}: {str(path)!r} is a folder, not a database file; name a file "
            "in it (e.g. sqlite:///lab/gaitpref.db)"
        )


def _identity(path: Path) -> tuple[int, int]:
    """The file's (device, inode): another file at the same path has another."""
    stat = path.stat()
    return stat.st_dev, stat.st_ino


def _sqlite_memory(url: URL) -> bool:
    return url.database in (None, "", ":memory:")


def _plain_engine(url: URL, **options: Any) -> Engine:
    """``create_engine(url, **options)`` (it connects to nothing), or
    :class:`StorageConnectError` naming a driver that is not installed or unknown."""
    try:
        return create_engine(url, **options)
    except (ImportError, ArgumentError) as exc:
        # psycopg is an extra: the docs' `pip install 'gaitpref[postgres]'` was not said
        missing = isinstance(exc, ImportError) and url.drivername == "postgresql+psycopg"
        advice = (
            "install PostgreSQL support with `pip install 'gaitpref[postgres]'`"
            if missing
            else "gaitpref uses sqlite:///PATH or postgresql+psycopg://user@host/dbname"
        )
        raise StorageConnectError(
            f"cannot open {_masked(url)}: its driver {url.drivername!r} cannot be loaded "
            f"({exc}); {advice}"
        ) from None


def _engine(url: URL, create: bool = True) -> Engine:
    """The engine for ``url``; ``create=False``: an empty SQLite file is left as it is (a
    reader that finds no schema refuses it; setting WAL would have written its first page)."""
    serializer = functools.partial(json.dumps, allow_nan=False)
    if url.get_backend_name() == "postgresql":
        return _plain_engine(
            url,
            json_serializer=serializer,
            connect_args={"connect_timeout": 10},
            pool_pre_ping=True,
        )
    memory = _sqlite_memory(url)
    engine = _plain_engine(
        url,
        json_serializer=serializer,
        connect_args={"timeout": BUSY_TIMEOUT_S, "check_same_thread": False},
        **({"poolclass": StaticPool} if memory else {}),
    )

    @event.listens_for(engine, "connect")
    def _on_connect(dbapi_connection: Any, _record: object) -> None:
        dbapi_connection.isolation_level = None  # transactions are begun below, explicitly
        cursor = dbapi_connection.cursor()
        cursor.execute("PRAGMA foreign_keys = ON")
        cursor.execute(f"PRAGMA busy_timeout = {int(BUSY_TIMEOUT_S * 1000)}")
        if not memory:
            # WAL only in a new file (when making one) or a gaitpref database of a revision
            # this gaitpref knows: a connection about to find another program's file is not a
            # gaitpref database, or that a newer gaitpref wrote it, must leave its journal
            # alone, and a reader of an empty file its bytes
            tables = {
                row[0]
                for row in cursor.execute("SELECT name FROM sqlite_master WHERE type = 'table'")
            }
            if (not tables and create) or (
                "alembic_version" in tables
                and {r[0] for r in cursor.execute("SELECT version_num FROM alembic_version")}
                <= set(migrate.known_revisions())
            ):
                cursor.execute("PRAGMA journal_mode = WAL")
            cursor.execute("PRAGMA synchronous = FULL")
        cursor.close()

    @event.listens_for(engine, "begin")
    def _on_begin(conn: Connection) -> None:
        write = conn.get_execution_options().get("gaitpref_write", False)
        conn.exec_driver_sql("BEGIN IMMEDIATE" if write else "BEGIN")

    return engine


def _sid(session_id: object) -> int:
    if isinstance(session_id, bool) or not isinstance(session_id, int):
        raise SessionNotFoundError(f"session ids are integers, got {session_id!r}")
    if not 0 <= session_id < 2**63:  # past SQL's INTEGER: no such session (an OverflowError)
        raise SessionNotFoundError(f"no session {session_id}: ids are 1 to {2**63 - 1}")
    return session_id


def _rows(sid: int, after: int, events: Sequence[NewEvent], stamp: Any) -> list[dict[str, Any]]:
    return [
        {
            "session_id": sid,
            "seq": after + k + 1,
            "kind": e.kind,
            "payload": e.payload,
            "at": as_utc(e.at) if e.at is not None else stamp,
            "version": e.version,
        }
        for k, e in enumerate(events)
    ]


def _payload(row: Any, where: str) -> dict[str, Any]:
    """An event's stored payload as a JSON object, or an error naming session, event, problem."""
    value = row.payload
    if isinstance(value, str | bytes):
        try:
            value = json.loads(value)
        except ValueError as exc:
            raise StorageError(
                f"session {row.session_id}, event {row.seq} ({row.kind}) in {where}: the stored "
                f"payload is not JSON ({exc}); the database was altered or damaged outside "
                "gaitpref: restore it from a backup"
            ) from None
    if not isinstance(value, dict):
        raise StorageError(
            f"session {row.session_id}, event {row.seq} ({row.kind}) in {where}: the stored "
            f"payload is a JSON {type(value).__name__}, not an object; the database was altered "
            "or damaged outside gaitpref: restore it from a backup"
        )
    return value


def _session(row: Any, where: str) -> SessionRecord:
    """A session's row as a record, or an error naming the session and the damaged column."""

    def damaged(what: str) -> StorageError:
        return StorageError(
            f"session {row['id']} in {where}: the stored {what}; the database was altered or "
            "damaged outside gaitpref: restore it from a backup"
        )

    if not isinstance(row["meta"], dict):
        raise damaged(f"meta is a JSON {type(row['meta']).__name__}, not an object")
    seed = row["seed"]
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise damaged(f"seed {seed!r} is not an integer")
    if row["status"] not in base.STATUSES:
        raise damaged(f"status {row['status']!r} is none of {', '.join(base.STATUSES)}")
    return SessionRecord(
        id=row["id"],
        subject=row["subject"],
        config_name=row["config_name"],
        config_text=row["config_text"],
        config_sha256=row["config_sha256"],
        seed=seed,
        software_version=row["software_version"],
        status=row["status"],
        created_at=as_utc(row["created_at"]),
        updated_at=as_utc(row["updated_at"]),
        last_seq=row["last_seq"],
        meta=row["meta"],
    )


def _conflict(session_id: int, last: int | None, after: int) -> ConflictError:
    have = "more events" if last is None else f"events up to {last}"
    return ConflictError(
        f"session {session_id} has {have}, not {after}: another writer appended to it; reload it"
    )


def _reason(exc: BaseException) -> str:
    orig = getattr(exc, "orig", None)
    text = str(orig if orig is not None else exc).strip().splitlines()
    reason = text[0] if text else type(exc).__name__
    if "password authentication failed" in reason:
        # a password typed into the URL as it is: "p@ss" is read as user "p", host "ss@..."
        reason += (
            " (in the URL, a password's @ : / ? # % and spaces are URL-encoded: %40 for @, "
            "%3A for :, %2F for /, %3F for ?, %23 for #, %25 for %, %20 for a space)"
        )
    return reason
