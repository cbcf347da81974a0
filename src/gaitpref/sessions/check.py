"""``gaitpref db check``: replay every stored session with this gaitpref, writing nothing.

After upgrading gaitpref or restoring a backup, every session of the database is opened as
:meth:`Session.open` opens it (its log replayed and checked step by step), one at a time; a
session that fails is reported with its error and the others are still checked.

Read-only: the database is opened without creating it, no event is appended, and the caches
a session keeps beside a SQLite file (the fit memo ``<db>.fits/``, the gaits made on demand
``<db>.gaits/``, the writers' turns ``<db>.turns/``) are neither read nor written: the storage
answers :meth:`~gaitpref.storage.Storage.folder_beside` with None, as for a database that is not
a local file, so every session is rebuilt from its log alone (slower for a large warm-started
session, and a stricter check).  SQLite itself still makes its ``-wal``/``-shm`` files beside
the file while it is open, as for any reader; the database file's bytes are not changed.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from gaitpref.storage import SessionRecord, SQLStorage, StorageError

if TYPE_CHECKING:
    from sqlalchemy import Connection


@dataclass(frozen=True)
class SessionCheck:
    """One session's result: its ``id``, ``subject``, ``config`` (name), number of ``events``
    (its last sequence number), ``status``, ``ok``, and when not ok the ``error``'s class name
    and its message (a :class:`~gaitpref.sessions.ReplayError` names the event)."""

    id: int
    subject: str
    config: str
    events: int
    status: str
    ok: bool
    error: str | None = None
    error_type: str | None = None

    def as_json(self) -> dict[str, Any]:
        return asdict(self)


class ReadOnlySQLStorage(SQLStorage):
    """A :class:`SQLStorage` that never writes: no caches beside the file, no appends."""

    def __init__(self, url: str) -> None:
        super().__init__(url, create=False)

    def folder_beside(self, suffix: str) -> Path | None:
        return None

    @contextmanager
    def _write(self) -> Iterator[Connection]:  # every write of SQLStorage goes through it
        raise StorageError(f"{self.url} is open read-only (gaitpref db check)")
        yield  # pragma: no cover  (a generator, as the method it replaces)


def check_database(
    url: str, started: Callable[[int], None] | None = None
) -> Iterator[SessionCheck]:
    """Replay every session at ``url`` (a URL as :func:`~gaitpref.storage.resolve_url` gives),
    yielding each one's :class:`SessionCheck` in id order.  ``started(n)`` is called once with
    the number of sessions.  A database that cannot be opened (missing, at an older schema,
    not a gaitpref database) raises its :class:`StorageError` before anything is yielded."""
    from gaitpref.sessions.session import Session

    storage = ReadOnlySQLStorage(url)
    try:
        records = storage.list_sessions()
        if started is not None:
            started(len(records))
        for record in records:
            yield _check_one(Session, storage, record)
    finally:
        storage.close()


def _check_one(session_cls: Any, storage: SQLStorage, record: SessionRecord) -> SessionCheck:
    def result(error: Exception | None = None) -> SessionCheck:
        return SessionCheck(
            id=record.id,
            subject=record.subject,
            config=record.config_name,
            events=record.last_seq,
            status=record.status,
            ok=error is None,
            error=None if error is None else str(error),
            error_type=None if error is None else type(error).__name__,
        )

    try:
        session = session_cls.open(storage, record.id)
    except Exception as exc:  # any failure is this session's: the others are checked still
        return result(exc)
    session.close()  # does not close the storage it was given
    return result()


__all__ = ["ReadOnlySQLStorage", "SessionCheck", "check_database"]
