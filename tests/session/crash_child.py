"""A session process for the crash test: resume the session and answer until TARGET trials.

Usage: python crash_child.py URL SESSION_ID TARGET ACK_FILE

It prints ``ready`` once the session is rebuilt, and appends ``query trial`` to ACK_FILE after
each answer returns (that is, after it is committed).  The subject's answers depend only on the
query, so a resumed process answers exactly as an uninterrupted one would.
"""

from __future__ import annotations

import sys

from gaitpref import Session
from gaitpref.session_demo import SimulatedSubject, bump_utility


def main(url: str, session_id: int, target: int, ack: str) -> None:
    session = Session.open(url, session_id)
    subject = SimulatedSubject(session.config.space, bump_utility(session.config.space), seed=1)
    print("ready", flush=True)
    with open(ack, "a", encoding="utf-8") as log:
        while len(session.trials()) < target:
            query = session.next_query()
            comparisons, suggestions = subject.respond(query)
            session.answer(query.id, comparisons, suggestions)
            log.write(f"{query.id} {query.trials[0]}\n")
            log.flush()
    print("done", flush=True)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4])
