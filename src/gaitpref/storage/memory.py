"""An in-memory :class:`~gaitpref.storage.base.Storage` for tests and dry runs.

It keeps the whole contract of ``storage/base.py`` (payloads go through JSON, batches are
atomic, appends are checked against the last sequence number) except durability: everything is
gone when the object is.  Thread-safe: one lock around every operation.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from dataclasses import replace

from gaitpref.storage.base import (
    CheckedCreation,
    ConflictError,
    EventRecord,
    NewEvent,
    SessionFinishedError,
    SessionNotFoundError,
    SessionRecord,
    SessionsCheck,
    SessionSpec,
    Status,
    SubjectRecord,
    as_utc,
    check_event,
    check_json,
    check_status,
    now,
)


class MemoryStorage(CheckedCreation):
    """Sessions and events in dictionaries (``url`` is ``memory://``)."""

    def __init__(self) -> None:
        self.url = "memory://"
        self._lock = threading.Lock()
        self._subjects: dict[str, SubjectRecord] = {}
        self._sessions: dict[int, SessionRecord] = {}
        self._events: dict[int, list[EventRecord]] = {}

    def _create(
        self,
        spec: SessionSpec,
        events: Sequence[NewEvent],
        status: Status,
        check: SessionsCheck | None,
    ) -> SessionRecord:
        with self._lock:
            if check is not None:  # under the lock: no other creator between check and create
                check(
                    [
                        _copy_session(s)
                        for _, s in sorted(self._sessions.items())
                        if s.subject == spec.subject
                    ]
                )
            stamp = now()
            sid = max(self._sessions, default=0) + 1
            self._subjects.setdefault(spec.subject, SubjectRecord(spec.subject, stamp))
            record = SessionRecord(
                id=sid,
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
            self._sessions[sid] = record
            self._events[sid] = [
                EventRecord(
                    sid, k + 1, e.kind, e.payload, as_utc(e.at) if e.at else stamp, e.version
                )
                for k, e in enumerate(events)
            ]
            return _copy_session(record)

    def get_session(self, session_id: int) -> SessionRecord:
        with self._lock:
            return _copy_session(self._get(session_id))

    def list_sessions(self, subject: str | None = None) -> list[SessionRecord]:
        with self._lock:
            return [
                _copy_session(s)
                for _, s in sorted(self._sessions.items())
                if subject is None or s.subject == subject
            ]

    def list_subjects(self) -> list[SubjectRecord]:
        with self._lock:
            return [self._subjects[c] for c in sorted(self._subjects)]

    def append(
        self,
        session_id: int,
        after: int,
        events: Sequence[NewEvent],
        status: Status | None = None,
    ) -> list[EventRecord]:
        checked = [check_event(e, f"event {k}") for k, e in enumerate(events)]
        new_status = None if status is None else check_status(status)
        with self._lock:
            record = self._get(session_id)
            if record.status == "finished":
                raise SessionFinishedError(f"session {session_id} is finished")
            if record.last_seq != after:
                raise ConflictError(
                    f"session {session_id} has events up to {record.last_seq}, not {after}: "
                    "another writer appended to it; reload it"
                )
            stamp = now()
            out = [
                EventRecord(
                    session_id, after + k + 1, e.kind, e.payload, as_utc(e.at or stamp), e.version
                )
                for k, e in enumerate(checked)
            ]
            self._events[session_id].extend(out)
            self._sessions[session_id] = replace(
                record,
                last_seq=after + len(out),
                updated_at=stamp,
                status=new_status or record.status,
            )
            return [_copy_event(e) for e in out]

    def events(self, session_id: int, after: int = 0) -> list[EventRecord]:
        with self._lock:
            self._get(session_id)
            return [_copy_event(e) for e in self._events[session_id] if e.seq > after]

    def _get(self, session_id: int) -> SessionRecord:
        try:
            return self._sessions[session_id]
        except (KeyError, TypeError):
            raise SessionNotFoundError(f"no session {session_id!r} in {self.url}") from None


def _copy_event(e: EventRecord) -> EventRecord:
    return replace(e, payload=check_json(e.payload, "payload"))


def _copy_session(s: SessionRecord) -> SessionRecord:
    return replace(s, meta=check_json(s.meta, "meta"))
