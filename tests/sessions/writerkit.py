"""A writer process for the two-writer tests: answers one session's queries as fast as it can."""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import TypedDict

from gaitpref import QueryError, Session
from gaitpref.storage import SessionBusyError


class Answered(TypedDict):
    """What :func:`answer_loop` counted: answers accepted, stale and busy; each call's time."""

    accepted: int
    stale: int
    busy: int
    waits: list[float]


class Noted(TypedDict):
    """What :func:`note_loop` counted: notes written and refused as busy."""

    written: int
    busy: int


def answer_loop(
    url: str, session_id: int, attempts: int, barrier: str | None = None, writers: int = 2
) -> Answered:
    """Try ``attempts`` answers; count the accepted, the stale and the busy, and each call's time.

    Each attempt asks for the pending query and answers it (the first action preferred to the
    first buffered one); an attempt whose query the other writer answered first is "stale".
    With ``barrier`` (a folder), the writers start together: each leaves a file there and waits
    (at most 120 s) until all ``writers`` have, so a slow process start cannot let the other
    finish alone.
    """
    session = Session.open(url, session_id)
    if barrier is not None:
        folder = Path(barrier)
        (folder / f"ready-{os.getpid()}").touch()
        deadline = time.monotonic() + 120
        while len(list(folder.glob("ready-*"))) < writers and time.monotonic() < deadline:
            time.sleep(0.01)
    accepted = stale = busy = 0
    waits: list[float] = []
    for _ in range(attempts):
        start = time.perf_counter()
        try:
            q = session.next_query()
            pair = [(q.actions[0], q.buffer[0], "first")] if q.buffer else []
            session.answer(q.id, pair, [])
            accepted += 1
        except QueryError:
            stale += 1
        except SessionBusyError:
            busy += 1
        waits.append(time.perf_counter() - start)
    session.close()
    return {"accepted": accepted, "stale": stale, "busy": busy, "waits": waits}


def note_loop(url: str, session_id: int, notes: int, barrier: str, writers: int = 2) -> Noted:
    """Write ``notes`` notes as fast as possible (after the start barrier); count the busy."""
    session = Session.open(url, session_id)
    folder = Path(barrier)
    (folder / f"ready-{os.getpid()}").touch()
    deadline = time.monotonic() + 120
    while len(list(folder.glob("ready-*"))) < writers and time.monotonic() < deadline:
        time.sleep(0.01)
    written = busy = 0
    for k in range(notes):
        try:
            session.note(f"writer {os.getpid()} note {k}")
            written += 1
        except SessionBusyError:
            busy += 1
    session.close()
    return {"written": written, "busy": busy}
