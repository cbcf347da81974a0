"""A coactive suggestion that asks to go past the edge of its feature's range is clipped there
(to the edge, or back to the same gait, stored but not modelled); the operator is told so, and
what is stored is the suggestion as given."""

from __future__ import annotations

from io import StringIO

import pytest
from rich.console import Console

from gaitpref import Session
from gaitpref.config import load_config, parse_config
from gaitpref.feedback.suggestion import clipped_note
from gaitpref.space import Feature, Move
from gaitpref.storage import MemoryStorage
from gaitpref.terminal import Terminal
from tests.sessions.sessionkit import CONFIG

#: "slightly longer" moves half the range, "longer" all of it: only "longer" from the shortest
#: step stays inside
WIDE = load_config(CONFIG).text.replace("coactive = [0.1, 0.2]", "coactive = [0.5, 1.0]")


@pytest.mark.parametrize(
    ("value", "move", "clipped"),
    [
        (1.0, "+small", True),  # at the edge already
        (0.9, "+big", True),  # 1.1: clipped to 1.0
        (0.8, "+big", False),  # 1.0 exactly (0.8 + 0.2 rounds past it): within
        (0.1, "-big", True),
        (0.5, "-small", False),
        (0.0, "+big", False),
    ],
)
def test_a_move_is_clipped_when_it_leaves_the_range(value: float, move: str, clipped: bool) -> None:
    f = Feature.linspace("x", 0.0, 1.0, 11, coactive=(0.1, 0.2))
    assert f.move_clipped(value, move) is clipped


def test_a_move_that_leaves_the_range_is_said_and_stored_as_given() -> None:
    config = parse_config(WIDE)
    assert "coactive = [0.5, 1.0]" in WIDE
    s = Session.create(MemoryStorage(), config, "S01")
    q = s.next_query()
    a = q.actions[0]
    f = s.space.features[0]
    at_min = s.space.point(a)[0] == f.values[0]
    move: Move = "-big" if at_min else "+big"  # past the edge either way
    answered = s.answer(q.id, [], [(a, "step_length", move)])
    assert len(answered.clipped) == 1
    note = answered.clipped[0]
    assert note.startswith(f"trial {q.trials[0]}: step_length ")
    assert "goes past the edge of its range" in note
    (stored,) = s.suggestions()
    assert (stored.action, stored.feature, stored.move) == (a, "step_length", move)
    assert stored.target == s.space.coactive_move(a, "step_length", move)
    # back to the same gait (at the edge already): not modelled; else moved to the edge
    assert ("stored but does not enter the model" in note) == (stored.target is None)
    assert ("taken as a move to the edge" in note) == (stored.target is not None)
    if stored.target is not None:
        assert s.space.point(stored.target)[0] == (f.values[0] if at_min else f.values[-1])
    assert note == clipped_note(s.space, a, "step_length", move, q.trials[0])


def test_a_move_within_the_range_says_nothing() -> None:
    s = Session.create(MemoryStorage(), parse_config(WIDE), "S01")
    q = s.next_query()
    a = q.actions[0]
    move = "+small" if s.space.point(a)[0] <= 0.13 else "-small"  # half the range: within
    assert s.answer(q.id, [], [(a, "step_length", move)]).clipped == ()


def test_the_terminal_says_a_clipped_suggestion_after_saved() -> None:
    s = Session.create(MemoryStorage(), parse_config(WIDE), "S01")
    q = s.next_query()
    at_min = s.space.point(q.actions[0])[0] == s.space.features[0].values[0]
    keys = ["4" if at_min else "1", "y"]  # shorter / longer: past the edge
    out = StringIO()
    Terminal(s, Console(file=out, width=400), read=lambda _: keys.pop(0) if keys else "q").run()
    text = out.getvalue()
    assert "saved: trial 1\n  note: trial 1: step_length " in text
    assert "goes past the edge of its range" in text
    assert [x.move for x in s.suggestions()] == ["-big" if at_min else "+big"]
