"""A writer process for the two-writer tests: answers one session's queries as fast as it can."""

from __future__ import annotations

import time

from gaitpref import QueryError, Session
from gaitpref.storage import SessionBusyError


def answer_loop(url: str, session_id: int, attempts: int) -> dict[str, object]:
    """Try ``attempts`` answers; count the accepted, the stale and the busy, and each call's time.

    Each attempt asks for the pending query and answers it (the first action preferred to the
    first buffered one); an attempt whose query the other writer answered first is "stale".
    """
    session = Session.open(url, session_id)
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
