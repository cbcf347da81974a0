"""The terminal runner driven by a scripted ``read`` (no pseudo-terminal): names and confirmations.

The pseudo-terminal tests (keys, Ctrl-C, a closed terminal) are in
``tests/sessions/test_terminal.py``.
"""

from __future__ import annotations

import re
import sqlite3
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from rich.console import Console
from typer.testing import CliRunner

from gaitpref import Rating, Session, load_config
from gaitpref.cli import app
from gaitpref.storage import MemoryStorage
from gaitpref.terminal import Terminal, gait_name
from tests.sessions.sessionkit import CONFIG


def _terminal(
    session: Session, *lines: str | BaseException | Callable[[], str]
) -> tuple[Terminal, Console]:
    """A terminal reading ``lines`` (an exception is raised by its read; a function is called,
    as another writer acting while the operator types, and its line read), then the end of
    input."""
    keys = iter(lines)

    def read(prompt: str) -> str:
        try:
            line = next(keys)
        except StopIteration:
            raise EOFError from None
        if isinstance(line, BaseException):
            raise line
        return line() if callable(line) else line

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


def test_x_states_the_confidence_after_the_flag_never_in_the_gait_about_to_be_flagged() -> None:
    """Trial 1 rated good and flagged unsafe with ``x``: the runner printed the confidence line
    before it wrote the flag, recommending trial 1's gait (the best so far) just before flagging
    it; now the flag comes first, and the recommendation is a gait that may still be proposed."""
    from gaitpref.config import parse_config

    session = Session.create(MemoryStorage(), parse_config(RATED), "S01", seed=2)
    terminal, console = _terminal(session, "4", "0", "x", "knee buckled")
    terminal.run()
    text = console.export_text()
    flagged = gait_name(session, session.trials()[0].action)
    after = text.split("saved: trial 1\n", 1)[1]
    assert after.startswith("flagged unsafe: trial 1 (knee buckled)")
    sure = re.search(r"\n  \d+% that (\S+) is within", after)
    assert sure is not None, after
    assert sure.group(1) != flagged
    best = session.recommended()
    assert best is not None and sure.group(1) == gait_name(session, best)
    assert f"that {flagged} is" not in text


def test_a_line_that_is_not_text_is_read_again() -> None:
    """A terminal whose encoding is strict (LANG=en_US.UTF-8) raises on undecodable bytes: the
    runner ended with 'error: utf-8 codec can't decode' before."""
    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    bad = UnicodeDecodeError("utf-8", b"\xff", 0, 1, "invalid start byte")
    terminal, console = _terminal(session, bad, "0", "y")
    terminal.run()
    assert "that line held bytes that are not text; type it again" in console.export_text()
    assert len(session.trials()) == 1 and session.status == "paused"


def test_a_reason_the_flag_refuses_is_asked_again_before_the_answer_is_written() -> None:
    """Undecodable bytes in the reason: the answer was written, then the flag refused and the
    runner ended (the flag lost, the session left active); a long one was cut at 2000 silently."""
    from gaitpref.config import parse_config

    session = Session.create(MemoryStorage(), parse_config(RATED), "S01", seed=2)
    terminal, console = _terminal(session, "", "0", "x", "knee \udcff", "k" * 2001)
    terminal.run()  # the input ends at the reason: nothing is written, the session pauses
    text = console.export_text()
    assert "the unsafe flag's reason is not valid text" in text
    assert "a text of 1 to 2000 characters; type it again" in text
    assert session.trials() == [] and session.status == "paused"

    terminal, console = _terminal(session, "", "0", "x", "knee \udcff", "knee buckled")
    terminal.run()
    assert session.unsafe_flags() == {1: (session.trials()[0].action, "knee buckled")}


def _answered(n: int) -> Session:
    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    for _ in range(n):
        q = session.next_query()
        session.answer(q.id, [], [(q.actions[0], "step_length", "+big")])
    return session


def test_a_ranking_is_checked_before_its_confirmation_and_u_does_not_become_one() -> None:
    session = _answered(3)
    terminal, console = _terminal(session, "", "u", "n", "ABD", "bac", "y")
    terminal.validate()
    text = console.export_text()
    assert "got nothing" in text and "got ABD" in text
    # u offers to withdraw the round (opened by hand: no answer to undo); n keeps it
    assert "Withdraw validation round 1 unanswered?  y yes, n no" in text
    assert "not withdrawn: the subject's ranking, best first, as before" in text
    assert text.count("Write the ranking") == 1  # 'Write the ranking u?' and the others before
    assert ["".join(v.ranking) for v in session.validations()] == ["BAC"]


def test_the_stop_rules_round_is_recorded_then_the_session_pauses() -> None:
    """The runner ended after the unblinding with the session left active, saying nothing."""
    from gaitpref.config import parse_config

    config = parse_config(RATED + "\n[stop]\nmax_trials = 1\n")
    session = Session.create(MemoryStorage(), config, "S01", seed=2)
    terminal, console = _terminal(session, "4", "0", "y", "ABC", "y")
    terminal.run()
    text = console.export_text()
    assert "Unblinded" in text and "The session is paused: resuming it goes on" in text
    assert "'gaitpref session finish 1' ends it" in text
    assert session.status == "paused" and len(session.validations()) == 1


def test_a_closed_stdin_pauses_the_session(monkeypatch: pytest.MonkeyPatch) -> None:
    """Started with stdin closed (a service, ``<&-``): input() raised 'lost sys.stdin', a
    traceback that left the session active."""
    import sys

    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    monkeypatch.setattr(sys, "stdin", None)
    console = Console(record=True, width=200, highlight=False)
    Terminal(session, console).run()
    assert session.status == "paused" and "Paused." in console.export_text()


class _ClosingStream:
    """A console's output whose reader goes away (``run ID | head``) once ``after`` is printed."""

    def __init__(self, after: str) -> None:
        self.after, self.text, self.closed = after, "", False

    def write(self, text: str) -> int:
        if self.closed:
            raise BrokenPipeError(32, "Broken pipe")
        self.text += text
        self.closed = self.after in self.text
        return len(text)

    def flush(self) -> None:
        if self.closed:
            raise BrokenPipeError(32, "Broken pipe")


def test_a_closed_output_pauses_the_session_and_keeps_the_confirmed_answer_and_flag() -> None:
    """``gaitpref session run ID | head``: the first print after the reader went away raised
    (Rich: SystemExit(1) at once), between the answer and its unsafe flag, and the session was
    left active.  The confirmed answer and its flag are written, then the session pauses."""
    from gaitpref.config import parse_config

    session = Session.create(MemoryStorage(), parse_config(RATED), "S01", seed=2)
    stream = _ClosingStream(after="saved: trial 1")
    keys = iter(["", "0", "x", "knee buckled", "1", "0", "y"])
    console = Console(file=stream, width=200, highlight=False)  # type: ignore[arg-type]
    Terminal(session, console, lambda prompt: next(keys)).run()
    action = session.trials()[0].action
    assert session.unsafe_flags() == {1: (action, "knee buckled")}
    assert len(session.trials()) == 1 and session.status == "paused"
    assert "flagged unsafe" not in stream.text  # nothing printed after the output closed


def test_a_prompt_that_cannot_be_written_pauses_the_session() -> None:
    """input() raised BrokenPipeError writing its prompt: 'error: Broken pipe', session active."""
    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    terminal, console = _terminal(session, BrokenPipeError(32, "Broken pipe"))
    terminal.run()
    assert session.status == "paused" and not session.trials()
    assert "Paused." not in console.export_text()  # said on stderr instead


def _open_round_showing_a_walked_gait() -> tuple[Session, Session, int]:
    """A session whose open round shows a gait within a trial's unsafe radius, a second writer
    on it (the console, another terminal) and that trial's number."""
    from gaitpref.config import parse_config
    from gaitpref.loop.safety import near
    from tests.sessions.test_unsafe import CONFIG as UNSAFE
    from tests.sessions.test_unsafe import _answer

    storage = MemoryStorage()
    session = Session.create(storage, parse_config(UNSAFE), "S01")
    for k in range(6):
        _answer(session, k)
    plan = session.start_validation()
    space = session.config.space
    shown = [g.action for g in plan.gaits]
    trial = next(t for t in session.trials() if near(space, {t.action}, 0.15)[shown].any())
    return session, Session.open(storage, session.id), trial.number


def test_a_ranking_of_a_round_drawn_again_meanwhile_is_refused_and_the_new_gaits_shown() -> None:
    """Another writer flagged a gait the open round showed while the operator typed the
    ranking: the round was drawn again with the same number, and the terminal booked the
    ranking of the gaits walked before against the new ones (the console refused it, 409)."""
    session, other, trial = _open_round_showing_a_walked_gait()
    before = [g.gait for g in session.validation_gaits()]

    def flag_then_rank() -> str:
        assert other.flag_unsafe(trial, "knee gave way") is True  # drawn again, still open
        return "ABC"

    terminal, console = _terminal(session, flag_then_rank, "y", "BCA", "y")
    terminal.validate()
    text = console.export_text()
    after = [g.gait for g in session.validation_gaits(1)]
    assert after != before
    assert "validation round 1 was drawn again since its gaits were shown" in text
    assert f"it now shows {', '.join(after)}, not {', '.join(before)}" in text
    assert text.count("Blind validation, round 1") == 2  # the round shown again, as it is now
    assert all(f"{g} (" in text.split("drawn again")[-1] for g in after)
    [result] = session.validations()
    assert "".join(result.ranking) == "BCA"  # only the ranking of the gaits shown now
    assert [e.kind for e in session.events()].count("validation_answered") == 1


def test_a_ranking_of_a_round_no_longer_open_is_not_recorded_and_says_so() -> None:
    """Another writer answered the round meanwhile: the terminal asked the ranking again and
    again, refused each time, with no way out but q."""
    import pytest

    from gaitpref import SessionStateError

    session, other, _ = _open_round_showing_a_walked_gait()

    def answered_elsewhere() -> str:
        other.answer_validation(1, "CBA")
        return "ABC"

    terminal, _ = _terminal(session, answered_elsewhere, "y")
    with pytest.raises(SessionStateError, match="ABC was not recorded: no blind validation round"):
        terminal.validate()
    assert ["".join(v.ranking) for v in session.validations()] == ["CBA"]


def test_an_answer_after_another_writer_opened_a_round_is_refused_and_the_round_asked() -> None:
    """The console opened a round while the terminal's query was being answered: the answer
    was written inside the round, moving the model the round was drawn from."""
    session = _answered(3)
    other = Session.open(session.storage, session.id)
    pending = session.next_query()

    def open_round_then(key: str) -> Callable[[], str]:
        def run() -> str:
            other.start_validation()
            return key

        return run

    terminal, console = _terminal(session, open_round_then("1"), "0", "y", "ABC", "y")
    terminal.run()
    text = console.export_text()
    assert "not written: blind validation round 1 is open" in text
    assert "Unblinded" in text and session.status == "paused"
    assert len(session.trials()) == 3 and session.pending == pending  # asked again on resume


def test_the_terminal_says_why_the_stop_rule_cannot_open_validation() -> None:
    """max_trials reached with nothing learnt: no round can be drawn, and the runner went on
    with the next trial as if the config had no rule."""
    from gaitpref.config import parse_config

    config = parse_config(load_config(CONFIG).text + "\n[stop]\nmax_trials = 1\n")
    session = Session.create(MemoryStorage(), config, "S01", seed=1)
    terminal, console = _terminal(session, "0", "y")  # trial 1: no suggestion
    terminal.run()
    text = console.export_text()
    assert "the [stop] rule says stop (1 trial reached max_trials = 1), but it cannot" in text
    assert "open blind validation: the posterior mean is flat" in text
    assert "Finish the" in text and "go on with trials" in text
    assert session.validation_plan is None and session.status == "paused"


def _with_second_writer() -> tuple[Session, Session]:
    storage = MemoryStorage()
    session = Session.create(storage, CONFIG, "S01", seed=1)
    return session, Session.open(storage, session.id)


@pytest.mark.parametrize("how", ["pause", "finish"])
def test_a_session_paused_or_finished_elsewhere_at_a_prompt_stops_the_runner(how: str) -> None:
    """The console (or a second terminal) paused or finished the session while the operator
    typed: the runner said 'not written', then ended with a SessionStateError traceback."""
    session, other = _with_second_writer()

    def meanwhile() -> str:
        getattr(other, how)()
        return "0"

    terminal, console = _terminal(session, meanwhile, "y", "q")
    terminal.run()  # no error
    text = console.export_text()
    done = "paused" if how == "pause" else "finished"
    assert f"The session was {done} by another writer" in text
    assert ("Resume with: gaitpref session run 1" in text) == (how == "pause")
    assert "saved" not in text and "Paused." not in text
    assert session.trials() == [] and Session.open(session.storage, 1).status == done


def test_the_undo_refuses_when_another_writer_answered_since_it_was_asked() -> None:
    """The runner asked 'Undo the last answer (trial 1)?', another writer answered trial 2
    meanwhile, and y undid trial 2's answer: someone else's."""
    session, other = _with_second_writer()
    q = session.next_query()
    session.answer(q.id, [], [(q.actions[0], "step_length", "+big")])

    def other_answers() -> str:
        q = other.next_query()
        other.answer(q.id, [], [(q.actions[0], "step_length", "+big")])
        return "y"

    terminal, console = _terminal(session, "u", other_answers)
    terminal.run()
    text = console.export_text()
    assert "Undo the last answer (trial 1)?" in text
    assert re.search(
        r"cannot undo: the answer to query \d+ \(trial 1\) is no longer the last", text
    )
    assert [(t.number, t.undone) for t in session.trials(include_undone=True)] == [
        (1, False),
        (2, False),
    ]


def test_session_undo_with_a_query_that_is_not_the_last_answer_writes_nothing() -> None:
    from gaitpref.errors import SessionStateError

    session = _answered(2)
    seq = session.last_seq
    first = session.trials()[0].query
    with pytest.raises(SessionStateError, match=r"query \d+ \(trial 1\) is no longer the last"):
        session.undo(query=first)
    assert session.last_seq == seq
    session.undo(query=session.trials()[-1].query)
    assert len(session.trials()) == 1


def test_echoed_text_is_shown_as_typed_and_cut() -> None:
    """What the operator typed is echoed back with markup off (a console made with markup on
    too) and cut to a bounded length: a pasted 60,000 character line filled the screen."""
    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    console = Console(record=True, width=200, highlight=False, markup=True, soft_wrap=True)
    keys = iter(["[bold]x[/]", "7" * 60_000, "0", "y"])

    def read(prompt: str) -> str:
        try:
            return next(keys)
        except StopIteration:
            raise EOFError from None

    Terminal(session, console, read).run()
    text = console.export_text()
    assert "'[bold]x[/]' is not one of" in text
    assert f"'{'7' * 200}... (60000 characters)' is not one of" in text
    assert len(session.trials()) == 1


def test_a_line_over_the_limit_is_refused_naming_it_and_asked_again() -> None:
    from gaitpref.terminal import MAX_LINE

    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    terminal, console = _terminal(session, "0" * (MAX_LINE + 1), "0", "y")
    terminal.run()
    assert f"that line is longer than {MAX_LINE} characters; type it again" in (
        console.export_text()
    )
    assert len(session.trials()) == 1


def test_piped_input_is_read_in_bounded_pieces(monkeypatch: pytest.MonkeyPatch) -> None:
    """stdin not a terminal (``... | gaitpref session run``): a line without end was read
    whole by input(); it is read and dropped in pieces, then the next line is taken."""
    import io
    import sys

    from gaitpref.terminal import MAX_LINE

    class Pipe:
        """A stdin that is not a terminal, remembering the longest piece it handed out."""

        longest = 0

        def __init__(self, text: str) -> None:
            self.text = io.StringIO(text)

        def isatty(self) -> bool:
            return False

        def readline(self, size: int = -1) -> str:
            line = self.text.readline(size)
            Pipe.longest = max(Pipe.longest, len(line))
            return line

    pipe = Pipe("5" * (3 * MAX_LINE + 7) + "\n0\ny\n")
    monkeypatch.setattr(sys, "stdin", pipe)
    monkeypatch.setattr(sys, "stdout", io.StringIO())
    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    console = Console(record=True, width=200, highlight=False)
    Terminal(session, console).run()
    assert f"that line is longer than {MAX_LINE} characters" in console.export_text()
    assert Pipe.longest <= MAX_LINE + 1
    assert len(session.trials()) == 1 and session.status == "paused"


def _busy(times: int, method: Callable[..., object]) -> Callable[..., object]:
    from gaitpref.storage import SessionBusyError

    left = [times]

    def wrapped(*args: object, **kwargs: object) -> object:
        if left[0]:
            left[0] -= 1
            raise SessionBusyError("session 1 is busy: another writer held it too long")
        return method(*args, **kwargs)

    return wrapped


def test_a_busy_session_at_the_confirmation_asks_it_again(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Another writer held the session past the wait when y was pressed: the runner ended with
    'session busy', the session left active."""
    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    monkeypatch.setattr(session, "answer", _busy(1, session.answer))
    terminal, console = _terminal(session, "0", "y", "y")
    terminal.run()
    text = console.export_text()
    assert "not written: session 1 is busy" in text and "confirm it again" in text
    assert len(session.trials()) == 1 and session.status == "paused"


def test_a_busy_session_at_the_next_trial_or_undo_pauses_with_a_message(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    monkeypatch.setattr(session, "next_query", _busy(1, session.next_query))
    terminal, console = _terminal(session)
    terminal.run()
    assert "The next trial could not be proposed: session 1 is busy" in console.export_text()
    assert session.status == "paused"

    session = _answered(1)
    monkeypatch.setattr(session, "undo", _busy(1, session.undo))
    terminal, console = _terminal(session, "u", "y")
    terminal.run()
    assert "not undone: session 1 is busy" in console.export_text()
    assert session.status == "paused" and len(session.trials()) == 1


def test_a_busy_session_at_the_pause_says_it_is_left_active(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    monkeypatch.setattr(session, "pause", _busy(1, session.pause))
    terminal, console = _terminal(session, "q")
    terminal.run()
    assert "could not be paused (session 1 is busy" in console.export_text()
    assert session.status == "active"


def test_an_unsafe_flag_refused_as_busy_is_asked_again_and_its_command_quoted(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The answer was written, then the flag was refused as busy: the runner ended, the flag
    lost.  It is asked again; declined, the command that writes it is printed, the reason
    shell-quoted."""
    import shlex

    from gaitpref.config import parse_config

    reason = "knee 'buckled'; $(rm -rf ~)"
    session = Session.create(MemoryStorage(), parse_config(RATED), "S01", seed=2)
    monkeypatch.setattr(session, "flag_unsafe", _busy(1, session.flag_unsafe))
    terminal, console = _terminal(session, "", "0", "x", reason, "y")
    terminal.run()
    text = console.export_text()
    assert "trial 1 is not flagged unsafe yet: session 1 is busy" in text
    assert f"gaitpref session unsafe 1 1 --reason {shlex.quote(reason)}" in text
    assert session.unsafe_flags() == {1: (session.trials()[0].action, reason)}

    session = Session.create(MemoryStorage(), parse_config(RATED), "S01", seed=2)
    monkeypatch.setattr(session, "flag_unsafe", _busy(1, session.flag_unsafe))
    terminal, console = _terminal(session, "", "0", "x", reason, "n")
    terminal.run()
    assert "trial 1 not flagged; flag it later with: gaitpref session unsafe 1 1 --reason " in (
        console.export_text()
    )
    assert session.unsafe_flags() == {} and len(session.trials()) == 1


def test_the_printed_resume_and_flag_commands_quote_what_the_user_gave() -> None:
    """``--db`` was pasted into the resume hint as given: a path with a space (or a ';') made
    a command that does something else when copied."""
    import shlex

    from gaitpref.cli.session import _flag_hint, _resume_hint

    db = "sqlite:///my lab;rm x.db"
    assert shlex.split(_resume_hint(3, db)) == ["gaitpref", "session", "run", "3", "--db", db]
    reason = "it's $(odd)"
    words = shlex.split(_flag_hint(3, db)(7, reason))
    assert words == ["gaitpref", "session", "unsafe", "3", "7", "--reason", reason, "--db", db]


def test_a_ranking_refused_as_busy_is_asked_again(monkeypatch: pytest.MonkeyPatch) -> None:
    """The ranking's write met a session held by another writer: a 'session busy' error ended
    the round's prompt."""
    session = _answered(3)
    monkeypatch.setattr(session, "answer_validation", _busy(1, session.answer_validation))
    terminal, console = _terminal(session, "ABC", "y", "BAC", "y")
    terminal.validate()
    text = console.export_text()
    assert "the ranking was not recorded: session 1 is busy" in text
    assert ["".join(v.ranking) for v in session.validations()] == ["BAC"]


@pytest.mark.parametrize("quit_keys", [("q",), (), ("x", "q")])
def test_quitting_at_the_confirmation_says_the_answer_was_not_written(
    quit_keys: tuple[str, ...],
) -> None:
    """q, the end of input or q at the unsafe reason, after the answer was shown as 'Write:
    ...': only 'Paused.' was said, as if the answer shown had been kept."""
    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    terminal, console = _terminal(session, "2", *quit_keys)  # trial 1: slightly longer
    terminal.run()
    text = console.export_text()
    assert "Write: step_length slightly longer." in text
    assert (
        "  not written: step_length slightly longer (trial 1 asked again when the session " in text
    )
    assert text.index("not written") < text.index("Paused.")
    assert session.trials() == [] and session.status == "paused"


def test_an_answer_written_is_not_said_to_be_not_written() -> None:
    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    terminal, console = _terminal(session, "2", "y", "q")  # saved, then q at trial 2's question
    terminal.run()
    assert "saved: trial 1" in console.export_text()
    assert "not written" not in console.export_text()


def test_the_opening_line_counts_one_trial_in_the_singular() -> None:
    """It said "1 trials so far"."""
    session = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    q = session.next_query()
    session.answer(q.id, [], [(q.actions[0], "step_length", "+big")])
    terminal, console = _terminal(session)  # no input: the runner pauses at once
    terminal.run()
    assert "exo-1d-step-length: 1 trial so far." in console.export_text()


def test_the_shipped_rated_config_runs_from_the_cli_with_a_rating(tmp_path: Path) -> None:
    """``configs/exo-2d-rated.toml``: a new session from the CLI, then two trials at the
    terminal, the first rated."""
    db = tmp_path / "lab.db"
    new = CliRunner().invoke(
        app, ["session", "new", "--config", "exo-2d-rated", "--subject", "S01", "--db", str(db)]
    )
    assert new.exit_code == 0, new.output
    with Session.open(f"sqlite:///{db}", 1) as session:
        # trial 1: rated 1 (very bad), no suggestion on either feature, written; trial 2:
        # compared, not rated
        terminal, console = _terminal(session, "1", "0", "0", "y", "1", "", "0", "0", "y")
        terminal.run()
        text = console.export_text()
        assert "Rating of trial 1: 1 very bad, 2 bad, 3 okay, 4 good, Enter to skip" in text
        assert "trial 1 rated very bad" in text
        rated = [e.payload for e in session.events() if e.kind == "rating_given"]
        assert [(r["trial"], r["category"]) for r in rated] == [(1, "very bad")]
        assert len(session.trials()) == 2 and session.config.name == "exo-2d-rated"


def _locked_session(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> tuple[Session, sqlite3.Connection]:
    """A SQLite session with trial 1 answered, and another program's connection to its file
    (it takes the write lock with ``BEGIN EXCLUSIVE``); the busy timeout cut to 0.2 s."""
    import gaitpref.storage.sql as sql
    from gaitpref.storage import SQLStorage

    monkeypatch.setattr(sql, "BUSY_TIMEOUT_S", 0.2)
    session = Session.create(SQLStorage(f"sqlite:///{tmp_path / 'lab.db'}"), CONFIG, "S01", seed=1)
    q = session.next_query()
    session.answer(q.id, [], [])
    return session, sqlite3.connect(tmp_path / "lab.db", isolation_level=None)


def test_an_answer_the_locked_database_refuses_is_confirmed_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Another program holding the SQLite file's write lock past the busy timeout: the answer
    the operator confirmed is said not written and asked again (it was a 'storage error'
    ending the runner, the answer lost with no word of it); confirmed once the lock is gone,
    it is written, and the session replays to the state of one that never met the lock."""
    session, other = _locked_session(tmp_path, monkeypatch)

    def lock() -> str:
        other.execute("BEGIN EXCLUSIVE")
        return "y"

    def unlock() -> str:
        other.execute("ROLLBACK")
        return "y"

    terminal, console = _terminal(session, "1", "0", lock, unlock)
    terminal.run()
    text = console.export_text()
    assert "not written: sqlite:///" in text
    assert "database is locked; nothing was written; confirm it again" in text
    assert "saved: trial 2" in text and "Paused.  Resume with:" in text
    other.close()
    reopened = Session.open(session.storage, session.id)
    plain = Session.create(MemoryStorage(), CONFIG, "S01", seed=1)
    q = plain.next_query()
    plain.answer(q.id, [], [])
    _terminal(plain, "1", "0", "y")[0].run()
    assert [(t.number, t.action) for t in reopened.trials()] == [
        (t.number, t.action) for t in plain.trials()
    ]
    assert reopened.comparisons() == plain.comparisons()
    assert reopened.status == plain.status == "paused"
    assert reopened.pending == plain.pending
    assert (reopened.posterior().mean == plain.posterior().mean).all()


def test_quitting_while_the_database_is_locked_leaves_the_session_active_saying_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Quitting while the lock is still held: the answer is said not written, the pause that
    cannot be written either is said so (the session left active) with the command to go on,
    and that command asks the same trial again."""
    session, other = _locked_session(tmp_path, monkeypatch)

    def lock() -> str:
        other.execute("BEGIN EXCLUSIVE")
        return "y"

    terminal, console = _terminal(session, "1", "0", lock, "q")
    terminal.run()
    text = console.export_text()
    assert "not written: trial 2 preferred to trial 1 (trial 2 asked again" in text
    assert "could not be paused (sqlite:///" in text and "it is left active: continue" in text
    other.execute("ROLLBACK")
    other.close()
    reopened = Session.open(session.storage, session.id)
    assert reopened.status == "active" and [t.number for t in reopened.trials()] == [1]
    assert reopened.next_query().trials == (2,)


def test_an_answer_whose_connection_was_lost_at_commit_is_found_stored_not_written_twice() -> None:
    """A lost connection (PostgreSQL restarted) may cut a commit short after it applied: the
    runner says the answer is perhaps not written and asks it again; confirmed again, it finds
    the answer stored and says so (it said 'not written: query 4 was already answered' of the
    operator's own stored answer), writing it once."""
    from gaitpref.storage import StorageConnectError

    storage = MemoryStorage()
    session = Session.create(storage, CONFIG, "S01", seed=1)
    q = session.next_query()
    session.answer(q.id, [], [])
    append = storage.append
    lost: list[int] = []

    def cut_short(*args: Any, **kwargs: Any) -> Any:
        written = append(*args, **kwargs)  # committed, then the connection is gone
        if not lost and any(e.kind == "comparison_answered" for e in args[2]):
            lost.append(1)
            raise StorageConnectError("cannot connect to postgresql://lab: server closed")
        return written

    storage.append = cut_short  # type: ignore[method-assign]
    terminal, console = _terminal(session, "1", "0", "y", "y")
    terminal.run()
    text = console.export_text()
    assert "perhaps not written: cannot connect to postgresql://lab: server closed; " in text
    assert "the answer confirmed before the connection was lost was stored" in text
    assert "saved: trial 2" in text and "already answered" not in text
    assert [t.number for t in Session.open(storage, session.id).trials()] == [1, 2]


def test_an_undo_written_whose_replacement_query_the_database_refuses_says_undone() -> None:
    """An undo whose query proposes a gait flagged unsafe since is withdrawn and a new query
    written in its place: when the database fails that second write, the undo stands, and the
    runner says 'Undone.' and why no trial follows, not 'not undone' (nothing was undone, it
    said, of an answer the log no longer holds)."""
    from gaitpref.storage import StorageFailureError

    storage = MemoryStorage()
    session = Session.create(storage, CONFIG, "S01", seed=8)  # trial 3 walks trial 1's gait
    for _ in range(3):
        q = session.next_query()
        session.answer(q.id, [], [])
    assert session.trials()[2].action == session.trials()[0].action
    session.flag_unsafe(1, "knee gave way")  # trial 3's query now proposes a flagged gait
    append = storage.append
    undone: list[int] = []

    def fails_after_the_undo(*args: Any, **kwargs: Any) -> Any:
        if undone and len(undone) < 2 and any(e.kind == "query_issued" for e in args[2]):
            undone.append(1)  # once: the pause after it is written
            raise StorageFailureError("sqlite:///lab.db: disk I/O error; nothing was written")
        written = append(*args, **kwargs)
        if any(e.kind == "undo" for e in args[2]):
            undone.append(1)
        return written

    storage.append = fails_after_the_undo  # type: ignore[method-assign]
    terminal, console = _terminal(session, "u", "y")
    terminal.run()
    text = console.export_text()
    assert len(undone) == 2, text  # the undo was written, its replacement query refused
    assert (
        "Undone.\nThe next trial could not be proposed: the undo is written; the query drawn in "
        "place of the one it withdrew was not: sqlite:///lab.db: disk I/O" in text
    )
    assert "not undone" not in text and "Paused.  Resume with:" in text
    assert [t.number for t in Session.open(storage, session.id).trials()] == [1, 2]


def test_a_flag_written_whose_round_the_database_refuses_to_draw_again_says_flagged(
    tmp_path: Path,
) -> None:
    """The answer that opens a blind validation round ([stop] max_trials) written with an
    unsafe flag on a gait the round shows: the flag withdraws the round and draws it again.
    When the database fails that second write the flag stands, and the runner says so; it
    said 'trial 2 is not flagged unsafe yet', then, asked again, 'was not flagged unsafe:
    trial 2 is already flagged unsafe; flag it later with ...'."""
    from gaitpref.storage import StorageFailureError

    config = tmp_path / "stop.toml"
    config.write_text(load_config(CONFIG).text + "\n[stop]\nmax_trials = 2\n", encoding="utf-8")
    storage = MemoryStorage()
    session = Session.create(storage, config, "S01", seed=0)  # the round shows trial 2's gait
    append = storage.append
    flagged: list[int] = []

    def fails_after_the_flag(*args: Any, **kwargs: Any) -> Any:
        kinds = {e.kind for e in args[2]}
        if flagged and len(flagged) < 2 and "validation_started" in kinds:
            flagged.append(1)  # once
            raise StorageFailureError("sqlite:///lab.db: disk I/O error; nothing was written")
        if "trial_flagged_unsafe" in kinds:
            flagged.append(1)
        return append(*args, **kwargs)

    storage.append = fails_after_the_flag  # type: ignore[method-assign]
    terminal, console = _terminal(session, "0", "y", "1", "0", "x", "knee gave way")
    terminal.run()
    text = console.export_text()
    assert len(flagged) == 2, text  # the flag was written, the round's redraw refused
    assert (
        "trial 2 is flagged unsafe (written); the blind validation round it withdrew was not "
        "drawn again: sqlite:///lab.db: disk I/O error" in text
    )
    assert "flagged unsafe: trial 2 (knee gave way)" in text
    assert "not flagged" not in text and "Paused.  Resume with:" in text
    reopened = Session.open(storage, session.id)
    assert reopened.unsafe_flags() == {2: (session.trials()[1].action, "knee gave way")}
    assert reopened.validation_plan is None


def test_with_two_buffered_trials_each_is_named_by_its_number_not_the_previous_one() -> None:
    """n = 1, b = 2: trial 3 is compared with trials 1 and 2; trial 1 was called "the previous
    one" as trial 2 was, and the operator could not tell which key meant which walk."""
    from gaitpref.config import parse_config

    config = parse_config(RATED.replace('strategy = "self-sparring"', "buffer = 2\nn = 1"))
    session = Session.create(MemoryStorage(), config, "S01", seed=2)
    q = session.next_query()
    session.answer(q.id, [], [])
    q = session.next_query()
    session.answer(q.id, [(q.actions[0], q.buffer[0], "first")], [])
    q = session.next_query()
    assert q.buffer_trials == (1, 2)
    terminal, console = _terminal(session, "1", "2", "", "0", "y")
    terminal.run()
    text = console.export_text()
    assert "Trial 3 against trial 1: 1 this one, 2 trial 1, 0 no preference" in text
    assert "Trial 3 against trial 2: 1 this one, 2 trial 2, 0 no preference" in text
    assert "the previous one" not in text
    told = [(c.first_trial, c.second_trial, c.outcome) for c in session.comparisons()][-2:]
    assert told == [(3, 1, "first"), (3, 2, "second")]


def test_the_undo_of_a_query_of_two_trials_names_both() -> None:
    """n = 2: the undo takes back the whole query; it asked 'Undo the last answer (trial 4)?',
    naming only the query's last trial."""
    from gaitpref.config import parse_config

    config = parse_config(RATED.replace('strategy = "self-sparring"', "n = 2\nbuffer = 0"))
    session = Session.create(MemoryStorage(), config, "S01", seed=2)
    q = session.next_query()
    session.answer(q.id, [(q.actions[0], q.actions[1], "first")], [])
    q = session.next_query()
    session.answer(q.id, [(q.actions[0], q.actions[1], "second")], [])
    terminal, console = _terminal(session, "u", "y")
    terminal.run()
    text = console.export_text()
    assert "Undo the last answer (trials 3, 4)?  y yes, n no" in text
    assert "Undone: the answer to trials 3, 4 is asked again." in text
    assert [t.number for t in session.trials()] == [1, 2]


def _query_with_a_gait_twice(config: str) -> Session:
    """A session (n = 2) whose pending query proposes one gait for both of its trials."""
    from gaitpref.config import parse_config

    session = Session.create(MemoryStorage(), parse_config(config), "S01", seed=0)
    for _ in range(40):
        q = session.next_query()
        if len(set(q.actions)) < len(q.actions):
            return session
        pairs = [(a, b, "first" if a > b else "second") for k, a in enumerate(q.actions)
                 for b in q.members[k + 1 :]]  # fmt: skip
        session.answer(q.id, pairs, [])
    raise AssertionError("no query proposed a gait twice")


def test_a_gait_run_twice_in_one_query_is_rated_and_suggested_once() -> None:
    """n = 2, one gait for trials 3 and 4: a rating and a suggestion per trial were asked, and
    the session refused the answer ('action 89 is rated twice'), asked again the same way."""
    shipped = Path(__file__).parents[2] / "src/gaitpref/config/shipped/exo-2d-rated.toml"
    config = shipped.read_text(encoding="utf-8").replace("n = 1\nbuffer = 1", "n = 2\nbuffer = 0")
    session = _query_with_a_gait_twice(config)
    q = session.next_query()
    (t3, t4), a = q.trials, q.actions[0]
    terminal, console = _terminal(session, "4", "1", "0", "y")
    terminal.run()
    text = console.export_text()
    assert f"trials {t3} and {t4} are the same gait: nothing to compare" in text
    assert f"Rating of trials {t3}, {t4} (the same gait): 1 very bad" in text
    assert f"Suggestion for step_length (trials {t3}, {t4}, the same gait): 1 longer" in text
    assert "not written" not in text
    rated = [e.payload for e in session.events() if e.kind == "rating_given"]
    assert [(r["action"], r["category"]) for r in rated] == [(a, "good")]
    assert [s.action for s in session.suggestions()] == [a]
    assert [t.number for t in session.trials()][-2:] == [t3, t4]


def test_a_buffer_holding_one_gait_twice_is_compared_with_it_once() -> None:
    """n = 1, b = 2, trials 14 and 15 ran one gait: trial 16 was asked against both and the
    session refused the answer ('the pair (86, 89) is compared twice'), asked again the same
    way; the console asks the pair once."""
    shipped = Path(__file__).parents[2] / "src/gaitpref/config/shipped/exo-2d-rated.toml"
    config = shipped.read_text(encoding="utf-8").replace("n = 1\nbuffer = 1", "n = 1\nbuffer = 2")
    from gaitpref.config import parse_config

    session = Session.create(MemoryStorage(), parse_config(config), "S01", seed=0)
    for _ in range(40):
        q = session.next_query()
        if len(set(q.buffer)) < len(q.buffer) and q.actions[0] not in q.buffer:
            break
        pairs = [(q.actions[0], b, "first" if q.actions[0] > b else "second") for b in q.buffer]
        session.answer(q.id, pairs, [])
    else:
        raise AssertionError("no buffer held one gait twice")
    (t,), (b1, b2) = q.trials, q.buffer_trials
    before = len(session.comparisons())
    terminal, console = _terminal(session, "1", "", "0", "0", "y")
    terminal.run()
    text = console.export_text()
    assert f"Trial {t} against trial {b1}: 1 this one, 2 trial {b1}" in text
    assert f"Trial {t} against trial {b2}:" not in text
    assert f"trial {t} against trial {b2}: the same gaits as trial {t} against trial {b1}" in text
    told = [(c.first_trial, c.second_trial, c.outcome) for c in session.comparisons()[before:]]
    assert told == [(t, b1, "first")]


def test_x_on_a_query_of_two_trials_asks_which_one_is_unsafe() -> None:
    """n = 2: x flagged both trials of the query, so one unsafe gait took the other (and, with
    a radius, its neighbours) away too; it now asks which, or a for all."""
    from gaitpref.config import parse_config

    config = parse_config(RATED.replace('strategy = "self-sparring"', "n = 2\nbuffer = 0"))
    session = Session.create(MemoryStorage(), config, "S01", seed=2)
    terminal, console = _terminal(session, "1", "", "", "0", "0", "x", "7", "2", "knee buckled")
    terminal.run()
    text = console.export_text()
    assert "x write and flag one or all of trials 1, 2 unsafe" in text
    assert "Which trial is unsafe? 1, 2, a all of them" in text
    assert "flagged unsafe: trial 2 (knee buckled)" in text
    assert session.unsafe_flags() == {2: (session.trials()[1].action, "knee buckled")}

    both = Session.create(MemoryStorage(), config, "S01", seed=2)
    terminal, console = _terminal(both, "1", "", "", "0", "0", "x", "a", "fell")
    terminal.run()
    assert sorted(both.unsafe_flags()) == [1, 2]


@pytest.mark.parametrize(
    ("actions", "buffer"),
    [
        ((5,), (9,)),
        ((5,), (5,)),
        ((5, 9, 7), (3,)),
        ((7,), (3, 3)),
        ((5, 5, 7), (9, 5)),
        ((4, 9), (9,)),
    ],
)
def test_the_terminal_the_console_and_the_simulated_users_ask_the_same_pairs(
    actions: tuple[int, ...], buffer: tuple[int, ...]
) -> None:
    """One rule (``SessionQuery.pairs``): the console asked a gait against itself and ordered
    n >= 3's pairs its own way; the terminal and the simulated users had one rule each."""
    from gaitpref import SessionQuery
    from gaitpref.console import views
    from gaitpref.loop import Query
    from gaitpref.simulate.users import query_pairs

    n = len(actions)
    q = SessionQuery(
        2, 2, actions, buffer, tuple(range(10, 10 + n)), tuple(range(1, 1 + len(buffer)))
    )
    session = Session.create(MemoryStorage(), load_config("exo-2d-rated"), "S01", seed=0)
    terminal, console = _terminal(session, *["1"] * len(q.compared))
    told, _ = terminal._comparisons(q)
    assert [(i, j) for i, j, _ in told] == list(q.compared)
    space = session.space
    groups = views.comparison_groups(
        [views.gait_view(space, a, trial=t) for a, t in zip(actions, q.trials, strict=True)],
        [views.gait_view(space, a, trial=t) for a, t in zip(buffer, q.buffer_trials, strict=True)],
    )
    assert [(g.first.index, g.second.index) for g in groups] == list(q.compared)
    assert [(g.first.trial, g.second.trial) for g in groups] == [
        (q.member_trials[p.first], q.member_trials[p.second]) for p in q.pairs if p.asked
    ]
    assert query_pairs(Query(2, actions, buffer)) == list(q.compared)
    text = console.export_text()
    same = sum(p.same_gait for p in q.pairs)
    assert text.count(": nothing to compare") == same
    assert text.count("compared once") == sum(not p.asked for p in q.pairs) - same


def test_u_inside_the_stop_rules_round_withdraws_it_and_undoes_the_answer_that_opened_it() -> None:
    """A mis-keyed last answer made the [stop] rule open the round: u offers to withdraw the
    round and undo that answer; confirmed, the trial is asked again, and the rule opens a new
    round after the next answer.  Replay gives the same state."""
    from gaitpref.config import parse_config

    config = parse_config(RATED + "\n[stop]\nmax_trials = 1\n")
    db = MemoryStorage()
    session = Session.create(db, config, "S01", seed=2)
    lines = ("1", "0", "y", "u", "u", "y", "4", "0", "y", "ABC", "y")
    terminal, console = _terminal(session, *lines)
    terminal.run()
    text = console.export_text()
    assert (
        "The [stop] rule opened round 1 after the answer to trial 1.  Withdraw the round and "
        "undo that answer (it is asked again)?  y yes, n no"
    ) in text
    assert "withdrawing is being asked: y yes, n no" in text  # u again: the question stands
    assert "Round 1 withdrawn; undone: the answer to trial 1 is asked again." in text
    assert text.count("Trial 1: run") == 2  # asked again
    kinds = [e.kind for e in session.events()]
    assert kinds.count("validation_withdrawn") == 1
    assert kinds[kinds.index("validation_withdrawn") + 1] == "undo"
    rounds = session.validation_rounds()
    assert [(r.round, r.opened_by, r.withdrawn is not None, r.answered) for r in rounds] == [
        (1, "rule", True, False),
        (2, "rule", False, True),
    ]
    assert session.status == "paused" and "Unblinded" in text
    again = Session.open(db, session.id)
    assert again.validation_rounds() == rounds
    assert again.trials(include_undone=True) == session.trials(include_undone=True)
    assert str(again.posterior().mean) == str(session.posterior().mean)


def test_u_inside_an_operators_round_withdraws_it_alone() -> None:
    from gaitpref.terminal import run_validation

    session = _answered(3)
    before = session.trials()
    console = Console(record=True, width=200, highlight=False)
    keys = iter(["u", "y"])
    assert run_validation(session, None, console, lambda _: next(keys)) is False
    text = console.export_text()
    assert "Withdraw validation round 1 unanswered?" in text and "Round 1 withdrawn." in text
    assert session.validation_plan is None and session.trials() == before  # nothing undone
    (info,) = session.validation_rounds()
    assert info.withdrawn == "u at the terminal" and info.opened_by == "operator"


def test_u_inside_the_rules_round_whose_answer_was_undone_withdraws_it_alone_saying_why() -> None:
    from gaitpref.config import parse_config

    config = parse_config(RATED + "\n[stop]\nmax_trials = 1\n")
    session = Session.create(MemoryStorage(), config, "S01", seed=2)
    q = session.next_query()
    assert session.answer(q.id, [Rating(q.actions[0], "very bad")]).stopped is not None
    session.undo()  # elsewhere (session undo): the round stays open, its answer gone
    terminal, console = _terminal(session, "u", "y")
    with pytest.raises(Exception) as raised:
        terminal.validate()
    assert type(raised.value).__name__ == "_WithdrawnError"
    text = console.export_text()
    assert "the answer that opened it cannot be undone with it: the answer to query" in text
    assert "Withdraw validation round 1 unanswered?" in text and "Round 1 withdrawn." in text
    assert [e.kind for e in session.events()][-1] == "validation_withdrawn"


def test_after_an_answer_that_leaves_no_gait_to_recommend_the_terminal_says_why() -> None:
    """Every gait rated "very bad" is avoided (``[safety] avoid``): after trial 2's answer the
    region of avoidance covers the grid, so no gait may be recommended; the runner said nothing
    there before (no confidence line, no reason), then that no gait may be proposed."""
    from gaitpref.config import parse_config

    config = RATED.replace("[safety]\n", '[safety]\navoid = ["very bad"]\n')
    session = Session.create(MemoryStorage(), parse_config(config), "S01", seed=2)
    # trial 1: rated very bad, no suggestion; trial 2: no preference, very bad, no suggestion
    terminal, console = _terminal(session, "1", "0", "y", "0", "1", "0", "y")
    terminal.run()
    text = console.export_text()
    why = "every gait is in the region of avoidance or near a gait flagged unsafe"
    assert session.no_recommendation() == why and len(session.trials()) == 2
    after = text.split("saved: trial 2", 1)[1]
    assert f"no gait may be recommended now ({why}), so no confidence is stated" in after
    assert "% that G" not in after
    # the answer before it still states the confidence in its recommendation
    assert re.search(r"saved: trial 1\n  \d+% that G\d+ is within 5% of the best", text)


def _rule_round_whose_replacement_fails(tmp_path: Path) -> tuple[Session, list[int]]:
    """Round 1 opened by the [stop] rule after trial 3, whose query proposes a gait flagged
    unsafe since (trial 1's); the database fails the query written in its place once."""
    from gaitpref.storage import StorageFailureError

    config = tmp_path / "stop.toml"
    config.write_text(load_config(CONFIG).text + "\n[stop]\nmax_trials = 3\n", encoding="utf-8")
    storage = MemoryStorage()
    session = Session.create(storage, config, "S01", seed=35)  # trial 3 walks trial 1's gait
    for _ in range(3):
        q = session.next_query()
        a = q.actions[0]
        session.answer(
            q.id, [(a, q.buffer[0], "first")] if q.buffer and q.buffer[0] != a else [], []
        )
    assert session.trials()[2].action == session.trials()[0].action
    assert session.validation_plan is not None  # opened by the rule after trial 3
    session.flag_unsafe(1, "knee gave way")  # trial 3's query now proposes a flagged gait
    assert session.validation_plan is not None
    append = storage.append
    withdrawn: list[int] = []

    def fails_after_the_withdrawal(*args: Any, **kwargs: Any) -> Any:
        if withdrawn and len(withdrawn) < 2 and any(e.kind == "query_issued" for e in args[2]):
            withdrawn.append(1)  # once: the pause after it is written
            raise StorageFailureError("sqlite:///lab.db: disk I/O error; nothing was written")
        written = append(*args, **kwargs)
        if any(e.kind == "validation_withdrawn" for e in args[2]):
            withdrawn.append(1)
        return written

    storage.append = fails_after_the_withdrawal  # type: ignore[method-assign]
    return session, withdrawn


def test_u_inside_the_rules_round_whose_replacement_query_the_database_refuses_says_withdrawn(
    tmp_path: Path,
) -> None:
    """u inside the round the [stop] rule opened withdraws it and undoes the answer that
    opened it; that answer's query proposes a gait flagged unsafe since, so a new query is
    written in its place.  When the database fails that last write, the withdrawal and the
    undo stand: the runner says the round is withdrawn and why no trial follows, and pauses.
    It said 'not withdrawn' and asked the ranking of the withdrawn round again."""
    session, withdrawn = _rule_round_whose_replacement_fails(tmp_path)
    terminal, console = _terminal(session, "u", "y")
    terminal.run()
    text = console.export_text()
    assert len(withdrawn) == 2, text  # withdrawn and undone, the query in its place refused
    assert "Round 1 withdrawn; undone: the answer to trial 3." in text
    assert "not withdrawn" not in text
    assert (
        "The next trial could not be proposed: the undo is written; the query drawn in place of "
        "the one it withdrew was not: sqlite:///lab.db: disk I/O" in text
    )
    assert "Paused.  Resume with:" in text
    again = Session.open(session.storage, session.id)
    assert [r.withdrawn is not None for r in again.validation_rounds()] == [True]
    assert [t.number for t in again.trials()] == [1, 2]


def test_session_validate_after_a_withdrawal_it_wrote_never_says_the_round_stays_open(
    tmp_path: Path,
) -> None:
    """The same at ``session validate`` (run_validation): the round is withdrawn, so the
    runner does not say 'No ranking recorded; the round stays open' with a command to rank it."""
    from gaitpref.terminal import run_validation

    session, withdrawn = _rule_round_whose_replacement_fails(tmp_path)
    console = Console(record=True, width=200, highlight=False)
    keys = iter(["u", "y"])
    assert run_validation(session, None, console, lambda _: next(keys), record_with=str) is False
    text = console.export_text()
    assert len(withdrawn) == 2, text
    assert "Round 1 withdrawn; undone: the answer to trial 3." in text
    assert "stays open" not in text and session.validation_plan is None
