"""The terminal loop on a continuous space with gaits made on demand (compass-continuous-3d)."""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

import pexpect

from gaitpref import Session

_CLI = "from gaitpref.cli import main; main()"
_ID = r"L\d\.\d{3}-T\d\.\d{3}-W\d\.\d{3}#[0-9a-f]{8}"


def test_trials_show_the_made_gaits_ids_and_the_log_holds_them(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    Session.create(url, "compass-continuous-3d", "S01", seed=0).close()
    env = {**os.environ, "NO_COLOR": "1", "TERM": "dumb", "COLUMNS": "200"}
    child = pexpect.spawn(
        sys.executable,
        ["-c", _CLI, "session", "run", "1", "--db", url],
        env=env,
        encoding="utf-8",
        timeout=120,
    )
    shown: list[str] = []
    for trial in (1, 2, 3):
        child.expect(rf"Trial {trial}: run ({_ID}) \(step_length=")
        shown.append(child.match.group(1))
        while True:
            i = child.expect(
                [
                    r"1 this one, 2 the previous one, 0 no preference",
                    r"Suggestion for \w+: .*0 none",
                    r"Write: .*y yes, n re-enter",
                    rf"saved: trial {trial}",
                ]
            )
            if i == 3:
                break
            child.sendline(("1", "0", "y")[i])
    child.expect(r"Trial 4: run")
    child.sendline("q")
    child.expect("Paused")
    child.expect(pexpect.EOF)
    child.close()
    assert child.exitstatus == 0

    with Session.open(url, 1) as s:
        trials = s.trials()
        assert [s.gait_name(t.action) for t in trials] == shown
        made = {e.payload["gait_id"] for e in s.events() if e.kind == "gait_made"}
        assert set(shown) <= made
        assert all(re.fullmatch(_ID, g) for g in shown)
        assert len(s.comparisons()) == 2
