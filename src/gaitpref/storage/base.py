"""The storage interface for experiment sessions, and its contract.

A database holds subjects, sessions and, per session, an append-only log of events.  Storage
knows nothing of numerics: an event is a ``kind`` (a short string) and a JSON ``payload``;
``gaitpref.sessions.session`` gives them meaning.

The contract every backend keeps (``tests/storage/test_contract.py`` checks it against the
in-memory store, SQLite and PostgreSQL):

1. **Append-only.**  Events are never edited or deleted.  Each session's events carry the
   sequence numbers ``1, 2, 3, ...`` without gaps, in the order they were appended.
2. **Atomic batches.**  :meth:`Storage.append` writes a batch of events (and an optional new
   status) in one transaction: all of it or none of it.
3. **Optimistic concurrency.**  ``append(session_id, after, ...)`` succeeds only if the session's
   last sequence number is still ``after``; otherwise it raises :class:`ConflictError` and writes
   nothing.  Two writers that both saw event ``n`` cannot both append event ``n + 1``.
4. **Durable on return.**  When ``append`` or ``create_session`` returns, the data is committed
   (SQLite: WAL journal with ``synchronous=FULL``), so a crash right after loses nothing.
5. **JSON only.**  Payloads and metadata are JSON objects (str keys; str, int, float, bool, None,
   lists, objects; no NaN or infinity); what is read back equals what was written.  Nothing is
   pickled.  A payload that is not such JSON is refused with :class:`StorageError` before
   anything is written.
6. **Closed when finished.**  A session whose status is ``"finished"`` takes no more events
   (:class:`SessionFinishedError`).
7. **Errors name the problem** and leave the data as it was: :class:`SessionNotFoundError`,
   :class:`ConflictError`, :class:`SchemaError` (a database written by a newer gaitpref, or one
   that needs ``gaitpref db upgrade``), :class:`StorageConnectError` (cannot connect).

Notation: ``seq`` is an event's sequence number within its session; ``last_seq`` a session's
highest (0 for none).
"""

from __future__ import annotations

import json
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Literal, get_args

from gaitpref.errors import StorageError

#: the most a writer waits for its turn on a session before :class:`SessionBusyError` (seconds)
WRITER_WAIT_S = 5.0

Status = Literal["active", "paused", "finished"]
STATUSES: tuple[Status, ...] = get_args(Status)
JSONObject = dict[str, Any]


class SessionNotFoundError(StorageError, LookupError):
    """No session with that id in this database."""


class SessionFinishedError(StorageError):
    """The session is finished and takes no more events."""


class ConflictError(StorageError):
    """Another writer appended to the session since this one last read it."""


class SessionBusyError(StorageError):
    """Another writer held the session's turn past the bounded wait; nothing was written."""


class SchemaError(StorageError):
    """The database's schema is not the one this gaitpref writes (newer, older or foreign)."""


class StorageConnectError(StorageError):
    """The database could not be reached or opened."""


class StorageFailureError(StorageError):
    """The database failed while it was in use (a disk I/O error, a locked, damaged, removed or
    replaced SQLite file, ...): the storage's fault, not the request's; nothing was written."""


@dataclass(frozen=True)
class NewEvent:
    """An event to append: its ``kind``, JSON ``payload``, for imports only its time, and the
    schema ``version`` of its payload (``gaitpref.payloads``)."""

    kind: str
    payload: JSONObject = field(default_factory=dict)
    at: datetime | None = None
    version: int = 1


@dataclass(frozen=True)
class EventRecord:
    """A stored event."""

    session_id: int
    seq: int
    kind: str
    payload: JSONObject
    at: datetime
    version: int = 1  # the payload's schema version


@dataclass(frozen=True)
class SessionSpec:
    """What a new session is made of (everything but its id, status and times)."""

    subject: str
    config_name: str
    config_text: str
    config_sha256: str
    seed: int
    software_version: str
    meta: JSONObject = field(default_factory=dict)


@dataclass(frozen=True)
class SessionRecord:
    """A stored session: its spec, status, times and the sequence number of its last event."""

    id: int
    subject: str
    config_name: str
    config_text: str
    config_sha256: str
    seed: int
    software_version: str
    status: Status
    created_at: datetime
    updated_at: datetime
    last_seq: int
    meta: JSONObject

    @property
    def origin(self) -> str | None:
        """``"imported from session N"`` for a session made by an import, else None."""
        origin = self.meta.get("imported_from")
        if not isinstance(origin, dict):
            return None
        return f"imported from session {origin.get('session_id')}"


@dataclass(frozen=True)
class SubjectRecord:
    """A subject: a pseudonymous code (never a name) and when it was first seen."""

    code: str
    created_at: datetime


#: a check of a subject's sessions before one more is created (raises to refuse it)
SessionsCheck = Callable[[list[SessionRecord]], None]


class Storage(ABC):
    """Subjects, sessions and their append-only event logs (see the module's contract)."""

    #: a printable description of where the data lives (passwords masked)
    url: str

    @abstractmethod
    def create_session(
        self,
        spec: SessionSpec,
        events: Sequence[NewEvent] = (),
        status: Status = "active",
    ) -> SessionRecord:
        """Create a session (and its subject, if new) with its first ``events``, atomically."""

    def create_session_checked(
        self,
        spec: SessionSpec,
        events: Sequence[NewEvent] = (),
        status: Status = "active",
        *,
        check: SessionsCheck,
    ) -> SessionRecord:
        """:meth:`create_session`, once ``check(the subject's sessions, by id)`` returned; what
        it raises is raised and nothing is written.

        The check and the creation are one step: the backends here run ``check`` inside the
        transaction that creates the session, while every other creator of a session of that
        subject waits (SQLite: ``BEGIN IMMEDIATE``; PostgreSQL: the subject's row locked
        ``FOR UPDATE``; memory: its lock), so that two creators cannot both pass it (two
        imports of one export).  This default, for a backend that does not override it, checks
        and then creates, without that guarantee.
        """
        check(self.list_sessions(spec.subject))
        return self.create_session(spec, events, status)

    @abstractmethod
    def get_session(self, session_id: int) -> SessionRecord:
        """The session, or :class:`SessionNotFoundError`."""

    @abstractmethod
    def list_sessions(self, subject: str | None = None) -> list[SessionRecord]:
        """Every session (of ``subject``, if given), by id."""

    @abstractmethod
    def list_subjects(self) -> list[SubjectRecord]:
        """Every subject, by code."""

    @abstractmethod
    def append(
        self,
        session_id: int,
        after: int,
        events: Sequence[NewEvent],
        status: Status | None = None,
    ) -> list[EventRecord]:
        """Append ``events`` (numbered ``after + 1, ...``) and set ``status``, atomically.

        Raises :class:`ConflictError` if the session's last event is not ``after``,
        :class:`SessionFinishedError` if it is finished, :class:`SessionNotFoundError`.
        """

    @abstractmethod
    def events(self, session_id: int, after: int = 0) -> list[EventRecord]:
        """The session's events with ``seq > after``, in order."""

    @contextmanager
    def writer_turn(self, session_id: int, wait_s: float | None = None) -> Iterator[None]:
        """Hold session ``session_id``'s turn among its writers (fair; waits at most ``wait_s``,
        default :data:`WRITER_WAIT_S`).

        Writers that take turns around catch-up, compute and append never lose the append's
        compare-and-set to each other, and alternate instead of starving (see
        :mod:`gaitpref.storage.turns`).  Raises :class:`SessionBusyError` past ``wait_s``.  The
        default holds nothing (one process: ``Session``'s own lock is enough); the optimistic
        append keeps the data right either way.
        """
        yield

    def folder_beside(self, suffix: str) -> Path | None:
        """A folder next to the database for data derived from its sessions (``<file><suffix>``,
        e.g. the cache of gaits made on demand); None when the database is not a local file."""
        return None

    def close(self) -> None:  # noqa: B027 - optional for backends that hold nothing
        """Release connections; the storage is not used afterwards."""

    def __enter__(self) -> Storage:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# -- checks shared by the backends -------------------------------------------------------------
def now() -> datetime:
    """The current time, UTC, to the microsecond."""
    return datetime.now(UTC)


def as_utc(value: datetime) -> datetime:
    """``value`` as an aware UTC time (naive times are taken to be UTC, as stored)."""
    return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


def check_json(value: object, where: str) -> JSONObject:
    """A deep copy of ``value`` through JSON; :class:`StorageError` if it is not a JSON object."""
    if not isinstance(value, Mapping):
        raise StorageError(f"{where}: must be a JSON object, got {type(value).__name__}")
    try:
        text = json.dumps(value, allow_nan=False, sort_keys=False)
    except (TypeError, ValueError) as exc:
        raise StorageError(f"{where}: not storable as JSON ({exc})") from None
    copy: JSONObject = json.loads(text)
    if copy != value and not _equal_json(copy, value):
        raise StorageError(f"{where}: does not survive a JSON round trip (non-string keys?)")
    return copy


def _equal_json(a: object, b: object) -> bool:
    if isinstance(b, tuple):
        b = list(b)
    if isinstance(a, dict) and isinstance(b, Mapping):
        return a.keys() == b.keys() and all(_equal_json(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_equal_json(x, y) for x, y in zip(a, b, strict=True))
    return a == b and type(a) is type(b)


def check_event(event: NewEvent, where: str) -> NewEvent:
    """``event`` with its payload checked and copied (see :func:`check_json`)."""
    if not isinstance(event, NewEvent):
        raise StorageError(f"{where}: expected a NewEvent, got {type(event).__name__}")
    if not isinstance(event.kind, str) or not 0 < len(event.kind) <= 32:
        raise StorageError(f"{where}: kind must be a string of 1 to 32 characters")
    v = event.version
    if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= 10_000:
        raise StorageError(f"{where}: version must be an integer from 1 to 10000, got {v!r}")
    return NewEvent(event.kind, check_json(event.payload, f"{where} payload"), event.at, v)


def check_spec(spec: SessionSpec) -> SessionSpec:
    """``spec`` checked: subject code, seed range, JSON metadata."""
    check_subject(spec.subject)
    if isinstance(spec.seed, bool) or not isinstance(spec.seed, int):
        raise StorageError(f"seed must be an integer, got {spec.seed!r}")
    if not 0 <= spec.seed < 2**63:
        raise StorageError(f"seed must be in 0 .. 2**63 - 1, got {spec.seed}")
    if len(spec.config_sha256) != 64:
        raise StorageError("config_sha256 must be a 64-character hex digest")
    if not spec.config_name or len(spec.config_name) > 200:
        raise StorageError("config_name must be 1 to 200 characters")
    return SessionSpec(
        spec.subject,
        spec.config_name,
        spec.config_text,
        spec.config_sha256,
        spec.seed,
        spec.software_version,
        check_json(spec.meta, "session meta"),
    )


def check_subject(code: object) -> str:
    """A subject code: 1-64 characters of letters, digits, ``-``, ``_`` and ``.``."""
    shown = repr(code) if len(repr(code)) <= 80 else repr(code)[:80] + "..."  # not megabytes
    if not isinstance(code, str) or not 0 < len(code) <= 64:
        raise StorageError(f"subject code must be 1 to 64 characters, got {shown}")
    if not all(c.isascii() and (c.isalnum() or c in "-_.") for c in code):
        raise StorageError(
            f"subject code {shown}: use letters, digits, '-', '_' and '.' only "
            "(a pseudonymous code such as S01, never a name)"
        )
    return code


def check_status(status: object) -> Status:
    if status not in STATUSES:
        raise StorageError(f"status must be one of {', '.join(STATUSES)}; got {status!r}")
    return status


class CheckedCreation(Storage):
    """A backend that runs ``create_session_checked``'s check inside the transaction creating
    the session: both creators forward to :meth:`_create` (``check`` None: no check)."""

    def create_session(
        self, spec: SessionSpec, events: Sequence[NewEvent] = (), status: Status = "active"
    ) -> SessionRecord:
        return self.create_session_checked(spec, events, status, check=None)

    def create_session_checked(
        self,
        spec: SessionSpec,
        events: Sequence[NewEvent] = (),
        status: Status = "active",
        *,
        check: SessionsCheck | None,
    ) -> SessionRecord:
        spec = check_spec(spec)
        checked = [check_event(e, f"event {k}") for k, e in enumerate(events)]
        return self._create(spec, checked, check_status(status), check)

    @abstractmethod
    def _create(
        self,
        spec: SessionSpec,
        events: Sequence[NewEvent],
        status: Status,
        check: SessionsCheck | None,
    ) -> SessionRecord:
        """Create the session, running ``check`` (if any) under the creating transaction;
        ``spec``, ``events`` and ``status`` come checked."""
