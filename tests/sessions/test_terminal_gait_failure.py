"""The terminal runner when the gait generator fails (gaits on demand): the next gait, or the
gait of the query an undo puts in place of a withdrawn one, cannot be made.  The runner says so
and pauses the session; it used to end with the CLI's bare "gait error" and leave the session
active."""

from __future__ import annotations

from io import StringIO
from pathlib import Path

import pytest
from rich.console import Console

from gaitpref.config import parse_config
from gaitpref.errors import GaitGeneratorError
from gaitpref.sessions.session import Session
from gaitpref.terminal import Terminal
from tests.sessions.gaitkit import CONFIG, FakeSteps


def _fails(monkeypatch: pytest.MonkeyPatch) -> None:
    def make(self: FakeSteps, vector: object, warm_start: object = None) -> None:
        raise GaitGeneratorError("solver crashed")

    monkeypatch.setattr(FakeSteps, "make", make)


def _run(s: Session, keys: list[str]) -> str:
    out = StringIO()
    keys = list(keys)
    Terminal(s, Console(file=out, width=300), read=lambda _: keys.pop(0) if keys else "q").run()
    return out.getvalue()


def test_a_next_gait_that_cannot_be_made_is_said_and_the_session_paused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    s = Session.create(f"sqlite:///{tmp_path / 'lab.db'}", parse_config(CONFIG), "S01")
    _fails(monkeypatch)
    text = _run(s, [])
    assert "The next gait could not be made: solver crashed" in text
    assert "Paused." in text
    again = Session.open(f"sqlite:///{tmp_path / 'lab.db'}", s.id)
    assert again.status == "paused"
    assert [e.kind for e in again.events() if e.kind not in ("paused", "resumed")] == ["created"]


def test_an_undo_whose_new_query_cannot_be_made_says_it_was_undone_and_pauses(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, parse_config(CONFIG + "[safety]\nunsafe_radius = 0.3\n"), "S01", seed=1)
    for _ in range(2):
        q = s.next_query()
        s.answer(q.id, [(a, b, "first") for a in q.actions for b in q.buffer if a != b])
    s.flag_unsafe(1, "hip")  # the pending query proposes a gait near trial 1: undo withdraws it
    s.next_query()
    _fails(monkeypatch)
    text = _run(s, ["u", "y"])
    assert "Undone." in text and "The next gait could not be made: solver crashed" in text
    assert "Paused." in text
    again = Session.open(url, s.id)
    assert "undo" in [e.kind for e in again.events()]
    assert len(again.trials()) == 1 and again.status == "paused"


def test_an_ask_that_makes_gaits_shows_a_spinner_on_a_terminal_and_nothing_elsewhere(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each gait made on demand is an optimisation (an ask may try up to max_infeasible that
    cannot be made): the runner showed nothing meanwhile, seconds at a time.  On a terminal a
    spinner now says so while the ask runs; Rich erases it, and prints nothing of it elsewhere."""
    import time

    made = FakeSteps.make

    def slow(self: FakeSteps, vector: object, warm_start: object = None) -> object:
        time.sleep(0.3)
        return made(self, vector, warm_start)  # type: ignore[arg-type]

    monkeypatch.setattr(FakeSteps, "make", slow)
    for terminal in (True, False):
        url = f"sqlite:///{tmp_path / f'lab{terminal}.db'}"
        s = Session.create(url, parse_config(CONFIG), "S01")
        out = StringIO()
        console = Console(file=out, width=300, force_terminal=terminal, highlight=False)
        Terminal(s, console, read=lambda _: "q").run()
        text = out.getvalue()
        said = "making gaits on demand (test-steps); infeasible ones are skipped ..."
        assert (said in text) is terminal
        assert "Trial 1: run" in text and "Paused." in text
