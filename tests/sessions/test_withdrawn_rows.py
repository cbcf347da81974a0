"""Gaits on demand on the line path with two gaits per query: a proposal withdrawn because one of
its gaits cannot be made frees its rows of the point table for the points proposed next, so a row
logged with a made gait may later name another point (a coactive suggestion's, never made) or
none.  Blind validation, the trials and the export must still show only gaits that were made,
each with its own values and gait id; and an undone answer's query withdrawn by an unsafe flag
frees its rows too, so the export takes a trial's gait from its ``trial_executed`` event."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from gaitpref import Session
from gaitpref.sessions.export import export_session
from gaitpref.sessions.validation import validation_actions
from gaitpref.storage import MemoryStorage
from tests.sessions.gaitkit import paired_line_session, prefer_shorter_pairs


def _run(storage: MemoryStorage, seed: int, queries: int, suggest: bool) -> Session:
    """n = 2 on the line path; a subject who prefers the shorter step (and, with ``suggest``,
    asks for a shorter one still) drives the proposals into the steps that have no gait."""
    s = paired_line_session(storage, seed)
    prefer_shorter_pairs(s, queries, suggest)
    return s


def _made(s: Session) -> list[dict[str, Any]]:
    return [e.payload for e in s.events() if e.kind == "gait_made"]


def _shown(s: Session, action: int) -> tuple[str | None, dict[str, float]]:
    return s.gait_id(action), s.space.values_of(action)


def _check_validation_shows_made_gaits(s: Session) -> None:
    made = {p["gait_id"]: p["values"] for p in _made(s)}
    plan = s.start_validation()
    for g in plan.gaits:
        gait_id, values = _shown(s, g.action)
        assert gait_id in made, f"gait {g.label} ({s.describe(g.action)}) was never made"
        assert values == made[gait_id]
    again = Session.open(s.storage, s.id)  # replay derives the same plan
    assert again.validation_plan == plan


@pytest.mark.parametrize("seed", [14, 20])
def test_validation_never_shows_a_withdrawn_row_that_now_names_an_unmade_point(seed: int) -> None:
    s = _run(MemoryStorage(), seed, 4, suggest=True)
    made = _made(s)
    # the case: a row logged with a made gait now names a point whose gait was never made
    ids = {p["gait_id"] for p in made}
    moved = [
        p["action"]
        for p in made
        if p["action"] < len(s.space) and s.gait_id(p["action"]) not in ids
    ]
    assert moved, "a withdrawn proposal's made gait lost its row to an unmade point"
    # picking among the rows as logged would show such a gait
    logged = sorted({p["action"] for p in made})
    assert set(validation_actions(s.posterior().mean, logged)) & set(moved)
    _check_validation_shows_made_gaits(s)
    # the walked trials keep their rows: trials, export and console show what was walked
    walked = [e.payload for e in s.events() if e.kind == "trial_executed"]
    assert [(t["gait_id"], t["values"]) for t in walked] == [
        _shown(s, t.action) for t in s.trials()
    ]
    # a refused point is looked up by its values and id, not by its row (which moved on)
    bad = s.infeasible_gaits()
    assert bad and any(s.gait_id(b.action) != b.gait_id for b in bad if b.action < len(s.space))


@pytest.mark.parametrize("seed", [15, 33])
def test_validation_starts_when_a_withdrawn_made_gait_has_no_row_yet(seed: int) -> None:
    s = _run(MemoryStorage(), seed, 4, suggest=False)
    made = _made(s)
    assert any(p["action"] >= len(s.space) for p in made), "a made gait's row left the table"
    _check_validation_shows_made_gaits(s)


def test_the_export_shows_an_undone_trial_as_walked_after_its_rows_moved_on(
    tmp_path: Path,
) -> None:
    s = _run(MemoryStorage(), 38, 4, suggest=False)
    q = s.undo()  # its query is pending again, on its rows of the table
    near = min(s.trials(), key=lambda t: abs(s.space.points[t.action][0] - q.points[0][0]))
    s.flag_unsafe(near.number, "knee pain")
    assert s.pending is None  # the flag withdrew the pending query: its rows left the table
    s.next_query()  # and went to the points proposed next
    walked = {e.seq: e.payload for e in s.events() if e.kind == "trial_executed"}
    undone = [t for t in s.trials(include_undone=True) if t.undone]
    assert any(s.gait_id(t.action) != walked[t.seq]["gait_id"] for t in undone)
    folder = export_session(s, tmp_path / "export", "json").parent
    rows = json.loads((folder / "trials.json").read_text())
    assert [r["undone"] for r in rows] == [t.undone for t in s.trials(include_undone=True)]
    for r, t in zip(rows, s.trials(include_undone=True), strict=True):
        assert (r["gait_id"], r["gait"]) == (walked[t.seq]["gait_id"], walked[t.seq]["gait_id"])
        assert {k: r[k] for k in walked[t.seq]["values"]} == walked[t.seq]["values"]
