"""Crash test: a session process killed with SIGKILL at random points, resumed each time."""

from __future__ import annotations

import signal
import sqlite3
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from gaitpref import Session
from gaitpref.session_demo import SimulatedSubject, bump_utility
from gaitpref.storage import MemoryStorage
from tests.session.sessionkit import CONFIG

CHILD = Path(__file__).with_name("crash_child.py")
TRIALS = 40
KILLS = 8
SEED = 31


def _run_child(args: list[str], kill_after: float | None) -> bool:
    """Run one child; SIGKILL it ``kill_after`` s after it is ready. True if it finished."""
    child = subprocess.Popen([sys.executable, str(CHILD), *args], stdout=subprocess.PIPE, text=True)
    assert child.stdout is not None
    ready = child.stdout.readline().strip()
    if ready != "ready":  # it died before it was ready: say why
        child.wait(timeout=60)
        pytest.fail(f"the session process failed to start (exit {child.returncode})")
    if kill_after is None:
        assert child.wait(timeout=120) == 0
        return True
    time.sleep(kill_after)
    child.send_signal(signal.SIGKILL)
    child.wait(timeout=60)
    child.stdout.close()
    return child.returncode == 0


@pytest.mark.slow
def test_sigkill_at_random_points_loses_and_duplicates_nothing(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'crash.db'}"
    ack = tmp_path / "acks.txt"
    ack.touch()
    sid = Session.create(url, CONFIG, "S01", seed=SEED).id
    args = [url, str(sid), str(TRIALS), str(ack)]
    rng = np.random.default_rng(2024)
    progress = []
    for _ in range(KILLS):
        if _run_child(args, kill_after=float(rng.uniform(0.0, 0.12))):
            break
        progress.append(len(ack.read_text().splitlines()))
    _run_child(args, kill_after=None)  # the last one runs to the end
    print("answers committed when each process was killed:", progress)
    assert len(progress) >= KILLS - 2 and progress[-1] < TRIALS  # it really was interrupted

    session = Session.open(url, sid)
    events = session.events()
    issued = [e.seq for e in events if e.kind == "query_issued"]
    answered = Counter(e.payload["query"] for e in events if e.kind == "trial_executed")
    trials = sorted(e.payload["trial"] for e in events if e.kind == "trial_executed")
    assert trials == list(range(1, TRIALS + 1))  # no trial lost or duplicated
    assert set(answered) == set(issued) and max(answered.values()) == 1
    acked = {int(line.split()[0]) for line in ack.read_text().splitlines()}
    assert acked <= set(answered)  # every answer the process saw committed is there
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
