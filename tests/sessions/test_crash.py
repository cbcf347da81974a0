"""Crash test: a session process killed with SIGKILL at random points, resumed each time.

Each session process is forked from the test (so it starts in milliseconds, with gaitpref already
imported), opens the session from SQLite, prints ``ready``, answers as a deterministic simulated
subject and prints ``ack QUERY`` after each answer returns (that is, after it is committed).  The
test kills it with SIGKILL a random moment after its k-th answer and starts the next one.
"""

from __future__ import annotations

import multiprocessing
import os
import sqlite3
import time
from collections import Counter
from pathlib import Path

import numpy as np

from gaitpref import Session
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG

TRIALS = 120  # room for KILLS interruptions however fast a child answers
KILLS = 12
SEED = 31


def _session_process(url: str, session_id: int, out: int) -> None:
    """The body of one session process: resume, answer until TRIALS trials, report on ``out``."""
    with os.fdopen(out, "w", buffering=1) as report:
        session = Session.open(url, session_id)
        space = session.config.space
        subject = SimulatedSubject(space, bump_utility(space), seed=1)
        report.write("ready\n")
        while len(session.trials()) < TRIALS:
            query = session.next_query()
            comparisons, suggestions = subject.respond(query)
            session.answer(query.id, comparisons, suggestions)
            report.write(f"ack {query.id}\n")
        report.write("done\n")


def _run_child(url: str, sid: int, acks: list[int], kill: tuple[int, float] | None) -> bool:
    """Run one session process; with ``kill = (k, s)``, SIGKILL it ``s`` seconds after its
    ``k``-th committed answer.  Collects the acknowledged query ids; True if it finished."""
    read, write = os.pipe()
    child = multiprocessing.get_context("fork").Process(
        target=_session_process, args=(url, sid, write)
    )
    child.start()
    os.close(write)
    finished, seen = False, 0
    with os.fdopen(read) as lines:
        for line in lines:
            if line.startswith("ack "):
                acks.append(int(line.split()[1]))
                seen += 1
            finished = finished or line.strip() == "done"
            if kill is not None and not finished and seen >= kill[0]:
                time.sleep(kill[1])
                child.kill()  # SIGKILL
                break
        acks.extend(int(x.split()[1]) for x in lines if x.startswith("ack "))
    child.join(timeout=120)
    if kill is None:
        assert child.exitcode == 0 and finished
    return finished


def test_sigkill_at_random_points_loses_and_duplicates_nothing(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'crash.db'}"
    with Session.create(url, CONFIG, "S01", seed=SEED) as created:
        sid = created.id
    rng = np.random.default_rng(2024)
    acks: list[int] = []
    killed = 0
    for _ in range(KILLS):  # killed after 0-3 answers, at a random moment of the next one
        if _run_child(url, sid, acks, (int(rng.integers(0, 4)), float(rng.uniform(0, 0.01)))):
            break
        killed += 1
    _run_child(url, sid, acks, None)  # the last one runs to the end
    assert killed == KILLS  # it really was interrupted, every time

    session = Session.open(url, sid)
    events = session.events()
    issued = [e.seq for e in events if e.kind == "query_issued"]
    answered = Counter(e.payload["query"] for e in events if e.kind == "trial_executed")
    trials = sorted(e.payload["trial"] for e in events if e.kind == "trial_executed")
    assert trials == list(range(1, TRIALS + 1))  # no trial lost or duplicated
    assert set(answered) == set(issued) and max(answered.values()) == 1
    assert set(acks) <= set(answered)  # every answer a process saw committed is there
    assert len(acks) == len(set(acks))  # and none was answered twice
    assert [e.seq for e in events] == list(range(1, len(events) + 1))
    with sqlite3.connect(tmp_path / "crash.db") as raw:
        assert raw.execute("PRAGMA integrity_check").fetchone() == ("ok",)

    # an uninterrupted run with the same answers ends in the same place, bit for bit
    ref = Session.create(MemoryStorage(), CONFIG, "S01", seed=SEED)
    subject = SimulatedSubject(ref.config.space, bump_utility(ref.config.space), seed=1)
    while len(ref.trials()) < TRIALS:
        q = ref.next_query()
        ref.answer(q.id, *subject.respond(q))
    np.testing.assert_array_equal(session.posterior().mean, ref.posterior().mean)
    np.testing.assert_array_equal(session.posterior().variance, ref.posterior().variance)
    assert session.next_query().actions == ref.next_query().actions
