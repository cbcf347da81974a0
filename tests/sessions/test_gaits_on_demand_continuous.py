"""Gaits on demand on a continuous 3-parameter space (issue 13): the real ``compass-hzd``
generator over continuous step length and step duration and a continuous step-width label, run
end to end in a session: gaits made per proposed point with ids that cannot collide, infeasible
proposals skipped and their neighbourhood kept off later lines, undo, reopen with and without the
gait cache, and export."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.sessions.export import export_session
from tests.sessions.gaitkit import prefer_short_steps

#: step lengths under about 0.05 m have no compass gait (a third of the range); a subject who
#: prefers short steps drives the lines there within a few queries
TEXT = """\
name = "compass-continuous-3d"
[space.step_length]
min = 0.02
max = 0.10
unit = "m"
[space.step_duration]
min = 0.4
max = 1.0
unit = "s"
[space.step_width]
min = 0.1
max = 0.3
unit = "m"
[gaits]
generator = "compass-hzd"
avoid_radius = 0.05
[model]
lengthscale = { step_length = 0.03, step_duration = 0.15, step_width = 0.08 }
signal_variance = 1e-4
noise = 0.01
jitter = 0.0
fit = "fixed"
[cospar]
strategy = "self-sparring"
seed = 0
line_points = 20
"""

ID = re.compile(r"^L\d\.\d{3}-T\d\.\d{3}-W\d\.\d{3}#[0-9a-f]{8}$")
SPAN = np.array([0.08, 0.6, 0.2])


def _run(url: str, queries: int) -> Session:
    s = Session.create(url, parse_config(TEXT), subject="S01")
    prefer_short_steps(s, queries)
    return s


def _point(values: dict[str, float]) -> np.ndarray:
    return np.array([values["step_length"], values["step_duration"], values["step_width"]])


def test_a_continuous_generator_session_runs_end_to_end(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = _run(url, 8)
    events = s.events()
    made = [e.payload for e in events if e.kind == "gait_made"]
    bad = s.infeasible_gaits()
    assert bad and all(b.reason.startswith("infeasible: ") for b in bad)
    # every made or refused gait has its own id: 3 decimals and a content hash of the point
    ids = [p["gait_id"] for p in made] + [b.gait_id for b in bad]
    assert all(ID.match(i) for i in ids) and len(set(ids)) == len(ids)
    assert len({p["key"] for p in made}) == len(made)  # distinct points, distinct gaits
    # the trials walked: gaits that were made, their ids logged as shown
    walked = {p["gait_id"] for p in made}
    trials = [e.payload for e in events if e.kind == "trial_executed"]
    assert trials and all(t["gait_id"] in walked for t in trials)
    assert [t["gait_id"] for t in trials] == [s.gait_name(t.action) for t in s.trials()]
    assert all(t["values"]["step_length"] > 0.04 for t in trials)
    # each refused point's neighbourhood (avoid_radius of the ranges) is off every later line
    for b in bad:
        k = next(i for i, e in enumerate(events) if e.seq == b.seq)
        centre = _point(events[k].payload["values"])
        later = [
            np.asarray(p)
            for e in events[k + 1 :]
            if e.kind == "query_issued"
            for p in e.payload.get("points", [])
        ]
        assert later, "queries follow the refused proposal"
        assert all(np.linalg.norm((p - centre) / SPAN) > 0.05 for p in later)
    # undo, then reopen from the cache and with no cache: the same session
    s.undo()
    before = (s.trials(include_undone=True), s.infeasible_gaits(), s.pending)
    assert Session.open(url, s.id).trials(include_undone=True) == before[0]
    shutil.rmtree(tmp_path / "lab.db.gaits")
    again = Session.open(url, s.id)
    assert (again.trials(include_undone=True), again.infeasible_gaits(), again.pending) == before
    q1 = again.next_query()
    assert q1 == s.next_query()
    # export: trials with their gait ids, the posterior over the visited points and the line
    folder = export_session(again, tmp_path / "export", "json").parent
    rows = json.loads((folder / "trials.json").read_text())
    assert [r["gait_id"] for r in rows] == [t["gait_id"] for t in trials]
    assert all(ID.match(r["gait_id"]) for r in rows) and rows[-1]["undone"]
    posterior = json.loads((folder / "posterior.json").read_text())
    assert len(posterior) == len(again.space) and all(ID.match(r["gait_id"]) for r in posterior)
