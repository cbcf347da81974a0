"""The terminal runner driven by a scripted ``read`` (no pseudo-terminal): names and confirmations.

The pseudo-terminal tests (keys, Ctrl-C, a closed terminal) are in
``tests/sessions/test_terminal.py``.
"""

from __future__ import annotations

from rich.console import Console

from gaitpref import Session, load_config
from gaitpref.storage import MemoryStorage
from gaitpref.terminal import Terminal, gait_name
from tests.sessions.sessionkit import CONFIG


def _terminal(session: Session, *lines: str) -> tuple[Terminal, Console]:
    keys = iter(lines)

    def read(prompt: str) -> str:
        try:
            return next(keys)
        except StopIteration:
            raise EOFError from None

    console = Console(record=True, width=200, highlight=False)
    return Terminal(session, console, read), console


def test_gaits_are_named_by_library_id_or_by_action() -> None:
    n = len(load_config(CONFIG).space)
    ids = [f"lib{k:02d}" for k in range(n)]
    with_library = Session.create(MemoryStorage(), CONFIG, "S01", seed=1, library=ids)
    terminal, console = _terminal(with_library, "0", "y")
    terminal.run()  # trial 1, no suggestion, written; then the input ends: paused
    action = with_library.trials()[0].action
    assert gait_name(with_library, action) == ids[action]
    assert f"Trial 1: run {ids[action]} (step_length=" in console.export_text()
    assert with_library.status == "paused"

    plain = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    terminal, console = _terminal(plain, "0", "y")
    terminal.run()
    action = plain.trials()[0].action
    assert f"Trial 1: run G{action} (step_length=" in console.export_text()


def test_a_typed_ranking_is_confirmed_before_it_is_written() -> None:
    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    for _ in range(3):
        q = session.next_query()
        session.answer(q.id, [], [(q.actions[0], "step_length", "+big")])
    terminal, console = _terminal(session, "BAC", "n", "ABC", "y")
    terminal.validate()
    text = console.export_text()
    assert "Write the ranking BAC?  y yes, n re-enter" in text
    assert "Write the ranking ABC?" in text and "Unblinded" in text
    assert ["".join(v.ranking) for v in session.validations()] == ["ABC"]


RATED = """
name = "rated-terminal"
[space.step_length]
min = 0.08
max = 0.18
num = 15
unit = "m"
words = ["longer", "shorter"]
[model]
lengthscale = 0.03
signal_variance = 0.005
noise = 0.02
fit = "fixed"
[cospar]
strategy = "self-sparring"
[feedback.rating]
labels = ["very bad", "bad", "okay", "good"]
[safety]
unsafe_radius = 0.1
"""


def test_ratings_are_asked_skippable_and_written() -> None:
    from gaitpref.config import parse_config

    session = Session.create(MemoryStorage(), parse_config(RATED), "S01", seed=2)
    # trial 1: rated 4 (good), no suggestion, written; trial 2: compared, rating skipped
    terminal, console = _terminal(session, "4", "0", "y", "1", "", "0", "y")
    terminal.run()
    text = console.export_text()
    assert "Rating of trial 1: 1 very bad, 2 bad, 3 okay, 4 good, Enter to skip" in text
    assert "trial 1 rated good" in text
    rated = [e.payload for e in session.events() if e.kind == "rating_given"]
    assert [(r["trial"], r["category"]) for r in rated] == [(1, "good")]
    assert len(session.trials()) == 2


def test_x_writes_the_answer_and_flags_the_trial_unsafe() -> None:
    from gaitpref.config import parse_config

    session = Session.create(MemoryStorage(), parse_config(RATED), "S01", seed=2)
    terminal, console = _terminal(session, "", "0", "x", "knee buckled")
    terminal.run()
    assert "flagged unsafe: trial 1 (knee buckled)" in console.export_text()
    action = session.trials()[0].action
    assert session.unsafe_flags() == {1: (action, "knee buckled")}
