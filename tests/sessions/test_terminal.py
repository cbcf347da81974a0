"""The operator's terminal loop, driven through a pseudo-terminal (pexpect)."""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path

import numpy as np
import pexpect

from gaitpref import Session
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG

_CLI = "from gaitpref.cli import main; main()"


def _spawn(*args: str) -> pexpect.spawn:
    env = {**os.environ, "NO_COLOR": "1", "TERM": "dumb", "COLUMNS": "200"}
    # generous: the runner imports numpy and scipy and may wait on a loaded machine
    child = pexpect.spawn(
        sys.executable, ["-c", _CLI, *args], env=env, encoding="utf-8", timeout=180
    )
    return child


def _at_prompt(child: pexpect.spawn, question: str) -> None:
    """Wait for ``question`` and then for the ``> `` input() writes as it starts reading, so that
    a signal sent next reaches a runner that is waiting for the operator's answer."""
    child.expect(question)
    child.expect_exact("> ")


def _answer(child: pexpect.spawn, comparison: str | None, suggestion: str) -> None:
    if comparison is not None:
        child.expect(r"1 this one, 2 the previous one, 0 no preference")
        child.sendline(comparison)
    child.expect(r"Suggestion for step_length: 1 longer, 2 slightly longer, 3 slightly shorter, "
                 r"4 shorter, 0 none")  # fmt: skip
    child.sendline(suggestion)
    child.expect(r"Write: .*y yes, n re-enter")
    child.sendline("y")


def test_a_few_trials_undo_and_quit_then_resume(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    seed = 3
    Session.create(url, CONFIG, "S01", seed=seed).close()
    child = _spawn("session", "run", "1", "--db", url)
    child.expect("Session 1, subject S01, exo-1d-step-length: 0 trials so far")
    child.expect(r"Trial 1: run G\d+ \(step_length=")
    _answer(child, None, "2")  # trial 1: slightly longer
    child.expect("saved: trial 1")
    child.expect(r"Trial 2: run G\d+ \(step_length=\S+ m\)")
    child.expect(r"compare with trial 1: G\d+ \(step_length=")
    child.expect(r"Trial 2 against trial 1: 1 this one")
    child.sendline("7")  # not a key
    child.expect("'7' is not one of: 1, 2, 0, u, q")
    _answer(child, "1", "0")
    child.expect("saved: trial 2")
    child.expect("Trial 3: run")
    child.sendline("u")  # the operator pressed the wrong key on trial 2
    child.expect(r"Undo the last answer \(trial 2\)\?  y yes, n no")
    child.sendline("y")
    child.expect("Undone: the answer to trial 2 is asked again")
    child.expect("Trial 2: run")
    _answer(child, "2", "4")  # the previous one was better; shorter
    child.expect("saved: trial 2")
    child.expect("Trial 3: run")
    child.sendline("q")
    child.expect(f"Paused.  Resume with: gaitpref session run 1 --db {url}")
    child.expect(pexpect.EOF)
    child.close()
    assert child.exitstatus == 0

    s = Session.open(url, 1)
    assert s.status == "paused" and len(s.trials()) == 2
    assert [(c.outcome, c.undone) for c in s.comparisons()] == [("first", True), ("second", False)]
    assert [(x.move, x.undone) for x in s.suggestions()] == [
        ("+small", False),
        ("-big", False),
    ]
    # the same answers given through the API give the same model
    ref = Session.create(MemoryStorage(), CONFIG, "S01", seed=seed)
    q = ref.next_query()
    ref.answer(q.id, [], [(q.actions[0], "step_length", "+small")])
    q = ref.next_query()
    ref.answer(
        q.id, [(q.actions[0], q.buffer[0], "second")], [(q.actions[0], "step_length", "-big")]
    )
    np.testing.assert_array_equal(s.posterior().mean, ref.posterior().mean)
    s.close()

    child = _spawn("session", "run", "1", "--db", url)
    child.expect("2 trials so far")
    child.expect("Trial 3: run")
    child.sendeof()  # closing the terminal pauses too
    child.expect("Paused")
    child.expect(pexpect.EOF)
    child.close()
    assert child.exitstatus == 0


def test_ctrl_c_and_a_closed_terminal_pause_the_session(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    Session.create(url, CONFIG, "S01", seed=5).close()
    child = _spawn("session", "run", "1", "--db", url)
    child.expect(r"Trial 1: run G\d+ \(step_length=")
    _answer(child, None, "0")
    child.expect("saved: trial 1")
    _at_prompt(child, r"Trial 2 against trial 1")
    child.sendintr()  # Ctrl-C
    child.expect(f"Paused.  Resume with: gaitpref session run 1 --db {url}")
    child.expect(pexpect.EOF)
    child.close()
    assert child.exitstatus == 0
    with Session.open(url, 1) as s:
        assert s.status == "paused" and len(s.trials()) == 1

    child = _spawn("session", "run", "1", "--db", url)
    _at_prompt(child, r"Trial 2 against trial 1")
    child.kill(signal.SIGHUP)  # the terminal window was closed
    child.expect(pexpect.EOF)
    child.close()
    with Session.open(url, 1) as s:
        assert s.status == "paused" and len(s.trials()) == 1
        assert [e.kind for e in s.events()][-2:] == ["resumed", "paused"]


def _one_trial_then_undo_asked(tmp_path: Path) -> tuple[str, pexpect.spawn]:
    """Seed 5: trial 1 answered in the terminal, then ``u`` at trial 2: the undo question."""
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    Session.create(url, CONFIG, "S01", seed=5).close()
    child = _spawn("session", "run", "1", "--db", url)
    _answer(child, None, "1")
    child.expect("saved: trial 1")
    child.expect(r"Trial 2 against trial 1")
    child.sendline("u")
    child.expect(r"Undo the last answer \(trial 1\)\?  y yes, n no")
    return url, child


def test_undo_in_the_terminal_asks_first(tmp_path: Path) -> None:
    url, child = _one_trial_then_undo_asked(tmp_path)
    child.sendline("n")
    child.expect("not undone")
    child.expect(r"Trial 2 against trial 1")  # asked again, nothing changed
    child.sendline("q")
    child.expect("Paused")
    child.expect(pexpect.EOF)
    child.close()
    with Session.open(url, 1) as s:
        assert [x.undone for x in s.suggestions()] == [False] and len(s.trials()) == 1


def test_an_undo_whose_query_a_flag_withdrew_says_so(tmp_path: Path) -> None:
    """Seed 1 of the unsafe tests walks gait 6 then 8, near it; trial 1 is flagged, then the
    operator undoes trial 2: its query is withdrawn and a new trial 2 proposed away from 6."""
    from gaitpref.config import parse_config
    from gaitpref.loop.safety import near
    from tests.sessions.test_unsafe import CONFIG as UNSAFE
    from tests.sessions.test_unsafe import _answer as answer

    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with Session.create(url, parse_config(UNSAFE), "S01") as s:
        answer(s, 0)
        answer(s, 1)
        first = s.trials()[0].action
        s.flag_unsafe(1, "hip pain")
    child = _spawn("session", "run", "1", "--db", url)
    child.expect(r"Trial 3: run")
    child.expect(r"Trial 3 against trial 2")
    child.sendline("u")
    child.expect(r"Undo the last answer \(trial 2\)\?  y yes, n no")
    child.sendline("y")
    child.expect("Undone; its query proposed a gait flagged unsafe since, or in the region of")
    child.expect(r"Trial 2: run")
    child.expect(r"Trial 2 against trial 1")
    child.sendline("q")
    child.expect("Paused")
    child.expect(pexpect.EOF)
    child.close()
    with Session.open(url, 1) as s:
        pending = s.pending
        assert pending is not None and pending.trials == (2,)
        assert not near(s.config.space, {first}, 0.15)[pending.actions[0]]


def test_u_and_q_keep_their_meaning_at_the_undo_question_and_the_unsafe_reason(
    tmp_path: Path,
) -> None:
    url, child = _one_trial_then_undo_asked(tmp_path)
    child.sendline("u")  # a traceback before
    child.expect("undo is being asked: y yes, n no")
    child.sendline("n")
    child.expect("not undone")
    child.expect(r"Trial 2 against trial 1")
    child.sendline("1")
    child.expect("Suggestion for step_length")
    child.sendline("0")
    child.expect(r"Write: .*x write and flag trial 2 unsafe")
    child.sendline("x")
    child.expect(r"Why is it unsafe\?")
    child.sendline("q")  # pauses; it was taken for the reason before
    child.expect("Paused")
    child.expect(pexpect.EOF)
    child.close()
    with Session.open(url, 1) as s:
        assert s.unsafe_flags() == {} and len(s.trials()) == 1 and s.status == "paused"


def test_a_closed_output_pauses_the_session_and_exits_cleanly(tmp_path: Path) -> None:
    """``gaitpref session run ID | head``: 'error: [Errno 32] Broken pipe', the session left
    active.  Now the confirmed answer is kept, the session pauses and the status is 0."""
    import subprocess

    url = f"sqlite:///{tmp_path / 'lab.db'}"
    Session.create(url, CONFIG, "S01", seed=5).close()
    env = {**os.environ, "NO_COLOR": "1", "TERM": "dumb", "COLUMNS": "200"}
    proc = subprocess.Popen(
        [sys.executable, "-c", _CLI, "session", "run", "1", "--db", url],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
        text=True,
    )
    assert proc.stdin is not None and proc.stdout is not None and proc.stderr is not None
    proc.stdin.write("0\ny\n")  # trial 1: no suggestion, confirmed
    proc.stdin.flush()
    while "saved: trial 1" not in proc.stdout.readline():
        pass
    proc.stdout.close()  # the reader goes away (head has its lines)
    proc.stdin.write("0\n0\ny\n")
    proc.stdin.close()
    err = proc.stderr.read()
    assert proc.wait(timeout=60) == 0, err
    assert "Broken pipe" not in err and "Traceback" not in err
    assert f"output closed; Paused.  Resume with: gaitpref session run 1 --db {url}" in err
    with Session.open(url, 1) as s:
        assert s.status == "paused" and len(s.trials()) == 1
