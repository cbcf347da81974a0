"""Gaits on demand on the line path: when every point of a query's line is avoided (the
``avoid_radius`` neighbourhoods of gaits that cannot be made cover it), the loop draws another
line instead of stopping the session, while most of the space may still be proposed
(``loop/line.py``, ``LINE_DRAWS`` in ``loop/lines.py``)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import gaitpref.loop.line as line_module
from gaitpref import Session
from gaitpref.errors import NoSafeGaitError
from gaitpref.storage import MemoryStorage
from tests.sessions.gaitkit import FakeSteps, paired_line_session, prefer_shorter_pairs

#: (seed, suggest): sessions whose query stopped with NoSafeGaitError when one line was drawn
STOPPED = [(26, False), (6, True)]
QUERIES = 8
SPANS = np.array([1.0, 0.1])  # step_length 0..1, step_width 0.2..0.3


def _infeasible(events: list[Any]) -> list[tuple[np.ndarray, float]]:
    return [
        (np.array([p["values"]["step_length"], p["values"]["step_width"]]), p["radius"])
        for p in (e.payload for e in events if e.kind == "gait_infeasible")
    ]


def _free_share(events: list[Any]) -> float:
    """The share of a fine grid over the space that may still be proposed: outside every
    refused gait's neighbourhood (and the fake makes its gait: step length >= 0.3)."""
    steps, widths = np.meshgrid(np.linspace(0, 1, 101), np.linspace(0.2, 0.3, 11))
    grid = np.column_stack([steps.ravel(), widths.ravel()])
    free = grid[:, 0] >= FakeSteps.below
    for centre, radius in _infeasible(events):
        free &= np.linalg.norm((grid - centre) / SPANS, axis=1) > radius
    return float(free.mean())


@pytest.mark.parametrize(("seed", "suggest"), STOPPED)
def test_one_line_per_query_stopped_the_session_with_most_of_the_space_free(
    seed: int, suggest: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The defect as it was: one line per query, so a query whose line the refused gaits'
    neighbourhoods cover stops the session."""
    monkeypatch.setattr(line_module, "LINE_DRAWS", 1)
    s = paired_line_session(MemoryStorage(), seed)
    with pytest.raises(NoSafeGaitError, match="no gait was left that may be proposed"):
        prefer_shorter_pairs(s, QUERIES, suggest)  # its line had none: the ask stopped there
    assert s.events()[-1].kind == "query_stopped"  # its gaits that cannot be made are logged
    assert _free_share(list(s.events())) > 0.5  # while most of the space is free


@pytest.mark.parametrize(("seed", "suggest"), STOPPED)
def test_a_covered_line_is_drawn_again_and_the_session_goes_on(
    seed: int, suggest: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    covered: list[int] = []  # seeds of the lines with no point that may be proposed
    on_line = line_module.LineCoSpar._on_line

    def watched(self: Any, line: Any) -> Any:
        space, allowed = on_line(self, line)
        if not allowed.any():
            covered.append(line.seed)
        return space, allowed

    monkeypatch.setattr(line_module.LineCoSpar, "_on_line", watched)
    storage = MemoryStorage()
    s = paired_line_session(storage, seed)
    prefer_shorter_pairs(s, QUERIES, suggest)
    events = list(s.events())
    assert covered, "no line was covered: the case is not exercised"
    issued = [e for e in events if e.kind == "query_issued"]
    assert len(issued) == QUERIES
    assert {e.payload["line"]["seed"] for e in issued}.isdisjoint(covered)
    # every proposed point (and so every executed one) has its gait and lies outside the
    # neighbourhood of every gait refused before it was proposed
    for e in issued:
        refused = _infeasible([r for r in events if r.seq < e.seq])
        for point in e.payload["points"]:
            assert point[0] >= FakeSteps.below
            for centre, radius in refused:
                assert np.linalg.norm((np.array(point) - centre) / SPANS) > radius
    walked = [e.payload for e in events if e.kind == "trial_executed"]
    assert len(walked) == 2 * QUERIES and all(
        t["values"]["step_length"] >= FakeSteps.below for t in walked
    )
    # replay re-derives every query, the covered lines and the redraws included, and checks it
    again = Session.open(storage, s.id)
    np.testing.assert_array_equal(again.space.points, s.space.points)
    np.testing.assert_array_equal(again.posterior().mean, s.posterior().mean)
    q = s.next_query()
    assert again.pending is None
    again.refresh()
    assert again.pending == q and again.pending.points == q.points
