"""The operator's terminal loop: show the trial, ask the answer with single keys, confirm, write.

One iteration (n = 1, b = 1, the paper's protocol), after the opening line that names the keys
(``Keys: u undo the last answer, q pause and quit.``)::

    Trial 5: run g08 (step_length=0.1371 m)
      compare with trial 4: g07 (step_length=0.1229 m)
    Trial 5 against trial 4: 1 this one, 2 the previous one, 0 no preference
    Suggestion for step_length: 1 longer, 2 slightly longer, 3 slightly shorter, 4 shorter, 0 none
    Rating of trial 5: 1 very bad, 2 bad, 3 okay, 4 good, Enter to skip     (with [feedback.rating])
    Write: trial 5 preferred to trial 4; step_length slightly longer.  y yes, n re-enter,
      x write and flag trial 5 unsafe                         (n > 1: which trial, or a all)
    saved: trial 5

Each answer is one key and Enter.  ``u`` undoes the last answer after a confirmation (its trial
is asked again), ``q`` pauses the session and quits (``gaitpref session run ID [--db URL]``
resumes it); so do Ctrl-C, a closed terminal (SIGHUP), the end of input and a closed output
(``gaitpref session run ID | head``: what is left to print is dropped).  A line that is
not text, an unsafe reason the flag would refuse and a ranking that is not one are asked again.
The blind validation round the ``[stop]`` rule opens is asked (after the rule's reason, said
when it opens the round and again when the runner resumes at it), unblinded, then the session
pauses; ``u`` inside a round offers to withdraw it, with the answer after which the rule opened
it undone (a mis-keyed answer: its trial is asked again), or alone for a round opened by hand
(a round another writer opens is asked the same way; the answer typed meanwhile is not
written); when the rule says stop but no round can be drawn (fewer than three gaits may be
shown), the runner says why after each answer.  A ranking of a round drawn again since its
gaits were shown is refused and the round shown again, as the console refuses it.  A gait
the generator fails to make (gaits on demand; after an undo too) is said and the session
paused; while an ask makes gaits on demand a terminal shows a spinner saying so.  A signal
(or a closed output) that comes while an answer is being written lets the write finish first.
Nothing is written before the operator confirms (answers, undo and a validation ranking
alike), and the answer is committed before the next trial is shown.
After ``saved:`` the runner says which suggestions went past the edge of their range and were
clipped there (``note: ...``, :attr:`Answered.clipped`) and, when the ``[stop]`` rule could not
be checked after the stored answer, why (``warning: ...``, :attr:`Answered.stop_warning`).
A session another writer pauses or finishes while the runner waits at a prompt stops the
runner, said so, nothing more written; an undo whose 'last answer' is no longer the last one
is refused; a write refused as busy (another writer holds the session) or failed by the
database (a SQLite file locked by another program past the busy timeout, a disk I/O error, a
lost connection: nothing written) is asked again (the answer, an unsafe flag) or pauses the
session (the next trial, an undo).  Lines are at most
:data:`MAX_LINE` characters, and what is echoed back is printed without markup and cut
(:func:`clip`).
Gaits are named by their gait library id, or ``G<action>`` (as in the console) without a
library.  The loop only calls the public :class:`~gaitpref.sessions.session.Session` API.
"""

from __future__ import annotations

import contextlib
import os
import shlex
import signal
import sys
import warnings
from collections.abc import Callable, Iterator, Sequence
from types import FrameType

from rich.console import Console
from rich.text import Text

from gaitpref.errors import FeedbackError, GaitError, NoSafeGaitError, SessionStateError
from gaitpref.feedback import Rating
from gaitpref.loop.cospar import QueryError
from gaitpref.loop.stopping import preference_learned
from gaitpref.sessions.confidence import StopCheckWarning
from gaitpref.sessions.gaits import NOT_MADE
from gaitpref.sessions.records import (
    InfeasibleGait,
    SessionQuery,
    check_printable,
    check_unsafe_reason,
)
from gaitpref.sessions.session import Session
from gaitpref.sessions.validation import LABELS, ValidationPlan, check_ranking
from gaitpref.space import Feature
from gaitpref.storage import SessionBusyError, StorageConnectError, StorageFailureError
from gaitpref.wording import plural

Reader = Callable[[str], str]

#: A write that raised one of these wrote nothing: another writer held the session past the
#: bounded wait (:class:`SessionBusyError`), or the database failed under it (a SQLite file
#: locked by another program past the busy timeout, a disk I/O error, a file removed or
#: replaced, a lost connection).  The runner handles them alike: the answer, an unsafe flag or
#: a ranking is asked again, the next trial or an undo pauses the session, and a pause that
#: cannot be written leaves it active, each said with the error.
_UNWRITTEN = (SessionBusyError, StorageFailureError, StorageConnectError)
_MOVES = ("+big", "+small", "-small", "-big")

#: the longest line of input taken (characters): a longer one is refused and asked again
MAX_LINE = 65_536
#: the most characters of a text echoed back (what was typed, a gait id, a reason) that are shown
MAX_SHOWN = 200
#: and of an error's message (gaitpref's own say what happened and what to do: kept whole; one
#: that quotes a generator's error at length is cut)
MAX_MESSAGE = 4000


def clip(text: object, limit: int = MAX_SHOWN) -> str:
    """``text`` as echoed back: cut to ``limit`` characters, saying how long it was (printed
    with markup off, as every line here: a ``[bold]`` in it is shown as typed)."""
    out = str(text)
    if len(out) <= limit:
        return out
    return f"{out[:limit]}... ({len(out)} characters)"


def _bounded_input(prompt: str) -> str:
    """``input()`` for a stdin that is not a terminal (a pipe, a file): a line is read
    :data:`MAX_LINE` characters at a time, and the rest of a longer one is read and dropped in
    pieces, so that no line is held whole; :class:`_LongLineError` then.  (A terminal's own
    line discipline bounds a typed line: there ``input()`` is used, line editing and all.)"""
    stdin = sys.stdin
    if stdin is None:
        raise EOFError
    sys.stdout.write(prompt)
    sys.stdout.flush()
    line = stdin.readline(MAX_LINE + 1)
    if not line:
        raise EOFError
    if len(line) > MAX_LINE and not line.endswith("\n"):
        while True:  # the rest of the line, dropped
            rest = stdin.readline(MAX_LINE)
            if not rest or rest.endswith("\n"):
                break
        raise _LongLineError
    return line.removesuffix("\n")


def _is_terminal(stream: object) -> bool:
    try:
        return bool(stream.isatty())  # type: ignore[attr-defined]
    except (AttributeError, OSError, ValueError):  # no such method, or closed
        return False


class _LongLineError(Exception):
    """A line longer than :data:`MAX_LINE` characters was read."""


class _QuitError(Exception):
    """The operator pressed q (or closed the input)."""


class _UndoError(Exception):
    """The operator pressed u."""


class _WithdrawnError(Exception):
    """The operator withdrew the open validation round (``u`` inside it, confirmed)."""


class _ElsewhereError(Exception):
    """Another writer (the console, a second terminal) paused or finished the session."""


#: the signals that pause the session: Ctrl-C and a closed terminal
PAUSE_SIGNALS = (signal.SIGINT, signal.SIGHUP)


def gait_name(session: Session, action: int) -> str:
    """The gait's library id, or ``G<action>`` without a library (as the console names it)."""
    return session.gait_name(action)


def _move_words(feature: Feature) -> tuple[str, str, str, str]:
    up, down = feature.words
    return (up, f"slightly {up}", f"slightly {down}", down)


def _trials(q: SessionQuery | Sequence[int]) -> str:
    """``trial 5`` or ``trials 4, 5``: the query's trials (or these trial numbers) as the
    prompts name them."""
    numbers = q.trials if isinstance(q, SessionQuery) else q
    return ("trial " if len(numbers) == 1 else "trials ") + ", ".join(map(str, numbers))


def _trials_of(q: SessionQuery) -> dict[int, list[int]]:
    """The query's executed gaits, each with its trials: a gait proposed twice in one query
    (n > 1) ran in two trials, and takes one rating and one suggestion per feature (the
    session refuses a second: ``action 89 is rated twice``)."""
    out: dict[int, list[int]] = {}
    for t, a in zip(q.trials, q.actions, strict=True):
        out.setdefault(a, []).append(t)
    return out


class Terminal:
    """Runs a session interactively through ``read`` (default: ``input``) and a Rich console."""

    def __init__(
        self,
        session: Session,
        console: Console | None = None,
        read: Reader = input,
        resume: str | None = None,
        record_with: Callable[[Sequence[str]], str] | None = None,
        flag_with: Callable[[int, str], str] | None = None,
    ):
        self.session = session
        self.console = console or Console(highlight=False, soft_wrap=True, markup=False)
        self._read = read
        self.resume = resume or f"gaitpref session run {session.id}"
        #: the command that records a round's ranking later, given the gait names it showed
        #: (``gaitpref session validate ID --gaits ...``): printed with each round shown
        self.record_with = record_with
        #: the command that flags a trial unsafe later, given its number and the reason: printed
        #: when the runner could not write a flag the operator asked for
        self.flag_with = flag_with or (
            lambda trial, reason: (
                f"gaitpref session unsafe {session.id} {trial} --reason {shlex.quote(reason)}"
            )
        )
        self._running = False  # in run(): each line read checks that the session is still active
        self.shown_gaits: list[str] | None = None  # the names of the round shown last
        self._reading = False  # a pause signal now interrupts the read at once
        self._signalled = False  # a pause signal came while writing: pause at the next read
        self._output_closed = False  # stdout's reader went away: nothing more is printed

    # -- input ---------------------------------------------------------------------------------
    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        if self._reading:
            raise _QuitError
        self._signalled = True

    def _on_output_closed(self) -> None:
        """The reader of the output went away (``run ID | head``): as a pause signal, the write
        under way finishes and the session pauses at the next read.  What is left to print is
        dropped, and stdout is pointed at the null device so that no later flush fails (as
        Rich's own ``on_broken_pipe`` does, which exits at once instead: mid-answer, leaving the
        session active)."""
        self._signalled = self._output_closed = True
        self.console.quiet = True
        if self.console.file is not sys.stdout and self._read is not input:
            return  # neither printed to stdout: a stream of the caller's, left to it
        with contextlib.suppress(OSError, ValueError):  # no file descriptor
            stdout = sys.stdout.fileno()
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, stdout)
            os.close(devnull)

    @contextlib.contextmanager
    def pause_on_signals(self) -> Iterator[None]:
        """Ctrl-C and SIGHUP (main thread only; elsewhere they are left be) and a closed output
        pause the session."""
        hooked = "on_broken_pipe" in vars(self.console)
        previous_hook = self.console.on_broken_pipe
        self.console.on_broken_pipe = self._on_output_closed  # type: ignore[method-assign]
        try:
            with self._signal_handlers():
                yield
        finally:
            if hooked:
                self.console.on_broken_pipe = previous_hook  # type: ignore[method-assign]
            else:
                del self.console.on_broken_pipe

    @contextlib.contextmanager
    def _signal_handlers(self) -> Iterator[None]:
        try:
            previous = {sig: signal.signal(sig, self._on_signal) for sig in PAUSE_SIGNALS}
        except ValueError:  # not the main thread: signal handlers cannot be set
            yield
            return
        try:
            yield
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)

    def read(self) -> str:
        """One line of input; a pause signal or the end of input quits (the session pauses).

        A line that is not valid text (bytes the terminal's encoding cannot decode, where its
        errors are strict) or longer than :data:`MAX_LINE` characters is said so and read
        again.  In :meth:`run`, a session another writer paused or finished while the line was
        being typed stops the runner (:class:`_ElsewhereError`)."""
        while True:
            line = self._read_line()
            if line is None:
                continue
            if self._running:
                self._check_active()
            return line

    def _check_active(self) -> None:
        """Raise :class:`_ElsewhereError` when another writer paused or finished the session
        (a busy session is left to the write that follows, which says so)."""
        with contextlib.suppress(*_UNWRITTEN):
            self.session.sync()
        if self.session.status != "active":
            raise _ElsewhereError

    def _read_line(self) -> str | None:
        """A line, or None when it was refused (and said so)."""
        # reading first, then the check: a signal between the two used to be recorded and not
        # acted on, and the runner waited at the prompt for Enter
        self._reading = True
        try:
            if self._signalled or (self._read is input and sys.stdin is None):
                raise _QuitError  # a signal came, or no input at all (started with stdin closed)
            reader = self._read
            if reader is input and not _is_terminal(sys.stdin):
                reader = _bounded_input
            line = reader("> ")
        except (EOFError, KeyboardInterrupt):
            raise _QuitError from None
        except BrokenPipeError:  # input() could not write its prompt: the output is closed
            self._on_output_closed()
            raise _QuitError from None
        except _LongLineError:
            line = None
        except UnicodeDecodeError:
            self.console.print(
                "  that line held bytes that are not text; type it again", markup=False
            )
            return None
        finally:
            self._reading = False
        if line is None or len(line) > MAX_LINE:
            self.console.print(
                f"  that line is longer than {MAX_LINE} characters; type it again", markup=False
            )
            return None
        return line

    def ask(self, prompt: str, allowed: dict[str, str], default: str | None = None) -> str:
        """Ask until one of ``allowed`` keys (or u/q) is given; returns the key."""
        while True:
            self.console.print(prompt, markup=False)
            raw = self.read().strip().lower()
            key = raw or (default or "")
            if key == "q":
                raise _QuitError
            if key == "u":
                raise _UndoError
            if key in allowed:
                return key
            self.console.print(
                f"  '{clip(raw)}' is not one of: {', '.join(allowed)}, u, q", markup=False
            )

    # -- the loop ------------------------------------------------------------------------------
    def run(self) -> None:
        s = self.session
        if s.status == "finished":
            raise SessionStateError(f"session {s.id} is finished")
        if s.status == "paused":
            s.resume()
        with self.pause_on_signals():
            self._running = True
            try:
                self._loop()
            finally:
                self._running = False

    def _loop(self) -> None:
        s = self.session
        self.console.print(
            f"Session {s.id}, subject {s.subject}, {clip(s.config.name)}: "
            f"{plural(len(s.trials()), 'trial')} so far.  Keys: u undo the last answer, q pause "
            "and quit.",
            markup=False,
        )
        self._say_stop_blocked()
        if s.validation_plan is not None:  # resumed at an open round: why it is there
            stopped = s.stop_reason()
            if stopped is not None:
                self.console.print(
                    f"  the [stop] rule says stop ({clip(stopped, MAX_MESSAGE)})", markup=False
                )
        try:
            while True:
                if s.validation_plan is not None:
                    try:
                        self.validate()
                    except _WithdrawnError:  # the trials go on (the undone one asked again)
                        continue
                    except SessionStateError as exc:  # the round is gone: go on
                        self.console.print(f"  {clip(exc, MAX_MESSAGE)}", markup=False)
                        self._stopped_elsewhere()
                        continue
                    except _UNWRITTEN as exc:  # the round could not be opened: pause
                        self.console.print(
                            f"The validation round could not be opened: {clip(exc, MAX_MESSAGE)}",
                            markup=False,
                        )
                        raise _QuitError from None
                    self.console.print(
                        "The validation round is recorded.  The session is paused: resuming "
                        "it goes on with more trials; 'gaitpref session finish "
                        f"{s.id}' ends it.",
                        markup=False,
                    )
                    raise _QuitError
                skipped = len(s.infeasible_gaits())
                try:
                    with self._making():
                        query = s.next_query()
                    self._say_infeasible(s.infeasible_gaits()[skipped:])
                except NoSafeGaitError as exc:  # an ask that stopped logged its skipped gaits
                    self._say_infeasible(s.infeasible_gaits()[skipped:])
                    self.console.print(
                        f"No gait to propose: {clip(exc, MAX_MESSAGE)}", markup=False
                    )
                    raise _QuitError from None
                except _UNWRITTEN as exc:  # nothing written: pause, say so
                    self.console.print(
                        f"The next trial could not be proposed: {clip(exc, MAX_MESSAGE)}",
                        markup=False,
                    )
                    raise _QuitError from None
                except SessionStateError:  # paused or finished elsewhere meanwhile
                    self._stopped_elsewhere()
                    raise
                except GaitError as exc:  # the generator failed: nothing written, pause
                    self._say_infeasible(s.infeasible_gaits()[skipped:])
                    self._say_no_gait(exc)
                    raise _QuitError from None
                try:
                    self._one(query)
                except _UndoError:
                    self._undo()
        except _QuitError:
            self._pause()
        except _ElsewhereError:
            self._say_elsewhere()

    def _making(self) -> contextlib.AbstractContextManager[object]:
        """While an ask may make gaits on demand (a generator config, no query pending: each
        gait is an optimisation, and an ask may try up to ``[gaits] max_infeasible`` that cannot
        be made), a spinner saying so on a terminal; before, the runner showed nothing, seconds
        at a time.  Rich draws it on a terminal only and erases it: nothing else is printed."""
        spec = self.session.config.generator
        if spec is None or self.session.pending is not None or not self.console.is_terminal:
            return contextlib.nullcontext()
        return self.console.status(
            Text(f"making gaits on demand ({clip(spec.name)}); infeasible ones are skipped ...")
        )

    def _stopped_elsewhere(self) -> None:
        """Raise :class:`_ElsewhereError` if the session is no longer active (as this object
        last caught up with it: after a refused operation, it has)."""
        if self.session.status != "active":
            raise _ElsewhereError

    def _say_elsewhere(self) -> None:
        """Another writer paused or finished the session: say so, and write nothing more."""
        status = self.session.status
        line = (
            f"The session was {status} by another writer (the console, another terminal) "
            "meanwhile; the runner stops and writes nothing more"
        )
        if status == "paused":
            line += f".  Resume with: {self.resume}"
        with contextlib.suppress(OSError):
            self.console.print(line, markup=False)

    def _say_stop_blocked(self) -> None:
        """The ``[stop]`` rule says stop but no blind validation round can be drawn: say why
        (the rule cannot act; the operator decides)."""
        blocked = self.session.stop_blocked()
        if blocked is not None:
            self.console.print(f"  {clip(blocked, MAX_MESSAGE)}", markup=False)

    def _say_infeasible(self, skipped: list[InfeasibleGait]) -> None:
        """Gaits made on demand that could not be made: skipped, never shown to the subject."""
        for bad in skipped:
            self.console.print(
                f"  gait {clip(bad.gait_id)} cannot be made; skipped, with the gaits near it "
                f"({clip(bad.reason, MAX_MESSAGE)})",
                markup=False,
            )

    def _say_no_gait(self, exc: GaitError) -> None:
        """The gait generator failed to make a proposed gait (an error, not an infeasible gait):
        say so; the caller pauses the session, and resuming asks again."""
        self.console.print(
            f"The next gait could not be made: {clip(exc or type(exc).__name__, MAX_MESSAGE)}",
            markup=False,
        )

    def _pause(self) -> None:
        """Pause the session, then say how to resume (the terminal may be gone: ignore that;
        with the output closed, it is said on stderr).  A session another writer paused or
        finished meanwhile is said so; one held by another writer past the wait is left active,
        and said so."""
        try:
            self.session.pause()
        except SessionStateError:
            if self.session.status == "active":
                raise
            self._say_elsewhere()
            return
        except _UNWRITTEN as exc:
            line = (
                f"The session could not be paused ({clip(exc, MAX_MESSAGE)}); it is left active: "
                f"continue it with {self.resume}"
            )
        else:
            line = f"Paused.  Resume with: {self.resume}"
        with contextlib.suppress(OSError):
            if self._output_closed:
                print(f"output closed; {line}", file=sys.stderr)
            else:
                self.console.print(line, markup=False)

    def _flagged(self, trial: int) -> bool:
        """Whether ``trial`` is flagged unsafe, as the log says now (False when it cannot be
        read)."""
        try:
            return trial in self.session.unsafe_flags()
        except _UNWRITTEN:
            return False

    def _undone(self, query: int) -> bool | None:
        """Whether the answer to ``query`` is no longer in force, as the log says now (an undo
        whose withdrawn query's replacement failed to be written is written itself); None when
        the log cannot be read."""
        try:
            return all(t.query != query for t in self.session.trials())
        except _UNWRITTEN:
            return None

    def _withdrawn(self, round_: int) -> bool | None:
        """Whether validation round ``round_`` is withdrawn, as the log says now (a withdrawal
        with an undo whose query in place of the undone one failed to be written is written
        itself); None when the log cannot be read."""
        try:
            self.session.sync()
            rounds = [r for r in self.session.validation_rounds() if r.round == round_]
        except _UNWRITTEN:
            return None
        return bool(rounds) and rounds[-1].withdrawn is not None

    def _undo(self) -> None:
        answered = self.session.trials()
        if not answered:
            self.console.print("  cannot undo: no answer is in force", markup=False)
            return
        # every trial of the last answer's query (n > 1): the undo takes them all back
        last = f" ({_trials([t.number for t in answered if t.query == answered[-1].query])})"
        while True:
            try:
                key = self.ask(f"Undo the last answer{last}?  y yes, n no", {"y": "", "n": ""})
                break
            except _UndoError:  # u again: the question stands
                self.console.print("  undo is being asked: y yes, n no", markup=False)
        if key == "n":
            self.console.print("  not undone", markup=False)
            return
        try:  # refused if another writer answered (or undid) since the question was asked
            pending = self.session.undo(query=answered[-1].query)
        except SessionStateError as exc:
            self.console.print(f"  cannot undo: {clip(exc, MAX_MESSAGE)}", markup=False)
            self._stopped_elsewhere()
            return
        except _UNWRITTEN as exc:  # pause, saying whether the undo was written
            undone = self._undone(answered[-1].query)
            if undone:  # the query in its place (its own was withdrawn) could not be written
                self.console.print("Undone.", markup=False)
                self.console.print(
                    f"The next trial could not be proposed: {clip(exc, MAX_MESSAGE)}",
                    markup=False,
                )
            else:
                said = "not undone" if undone is False else "perhaps not undone"
                self.console.print(f"  {said}: {clip(exc, MAX_MESSAGE)}", markup=False)
            raise _QuitError from None
        except NoSafeGaitError as exc:
            self.console.print(f"No gait to propose: {clip(exc, MAX_MESSAGE)}", markup=False)
            raise _QuitError from None
        except GaitError as exc:  # the undo is written; the query in its place could not be made
            self.console.print("Undone.", markup=False)
            self._say_no_gait(exc)
            raise _QuitError from None
        if pending is None or (answered and pending.id != answered[-1].query):
            self.console.print(
                "Undone; its query proposed a gait flagged unsafe since, or in the region of "
                "avoidance now, and was withdrawn: a new query is proposed in its place.",
                markup=False,
            )
            return
        self.console.print(
            f"Undone: the answer to {_trials(pending)} is asked again.", markup=False
        )

    def _one(self, q: SessionQuery) -> None:
        s = self.session
        for t, a in zip(q.trials, q.actions, strict=True):
            self.console.print(f"Trial {t}: run {self._gait(a)}", markup=False)
        for t, a in zip(q.buffer_trials, q.buffer, strict=True):
            self.console.print(f"  compare with trial {t}: {self._gait(a)}", markup=False)
        lost = False  # a write cut short by a lost connection: whether it was stored is unknown
        while True:
            comparisons, said = self._comparisons(q)
            ratings, rated = self._ratings(q)
            suggestions, words = self._suggestions(q)
            summary = "; ".join(said + rated + words) or "no comparison, no suggestion"
            several = len(set(q.trials)) > 1
            flag = f"x write and flag {'one or all of ' if several else ''}{_trials(q)} unsafe"
            unsafe: tuple[int, ...] = ()
            while True:  # asked again while another writer holds the session (nothing written)
                try:
                    key = self.ask(
                        f"Write: {summary}.  y yes, n re-enter, {flag}",
                        {"y": "", "n": "", "x": ""},
                        "y",
                    )
                    if key == "n":
                        break
                    unsafe = self._which_unsafe(q) if key == "x" else ()
                    reason = self._reason() if key == "x" else ""
                except _QuitError:  # the answer was shown in full: say it was not kept
                    self._not_written(q, summary)
                    raise
                try:
                    with warnings.catch_warnings():  # said by _written, not as a Python warning
                        warnings.simplefilter("ignore", StopCheckWarning)
                        answered = s.answer(q.id, [*comparisons, *ratings], suggestions)
                except _UNWRITTEN as exc:
                    if isinstance(exc, StorageConnectError):  # a commit it cut short may stand
                        lost = True
                        self.console.print(
                            f"  perhaps not written: {clip(exc, MAX_MESSAGE)}; confirm it again "
                            "(an answer the database did store is found, not written twice)",
                            markup=False,
                        )
                    else:
                        self.console.print(
                            f"  not written: {clip(exc, MAX_MESSAGE)}; confirm it again",
                            markup=False,
                        )
                    continue
                except (QueryError, FeedbackError, SessionStateError) as exc:
                    if lost and any(t.query == q.id for t in s.trials()):
                        self.console.print(
                            "  the answer confirmed before the connection was lost was stored",
                            markup=False,
                        )
                        self._written(q, reason, unsafe=unsafe)
                        return
                    # a round another writer opened meanwhile: the loop asks its ranking next
                    self.console.print(f"  not written: {clip(exc, MAX_MESSAGE)}", markup=False)
                    self._stopped_elsewhere()
                    return
                self._written(
                    q, reason, answered.stop_warning, answered.clipped, answered.stopped, unsafe
                )
                return

    def _not_written(self, q: SessionQuery, summary: str) -> None:
        """Quitting at the confirmation (or the unsafe reason) writes nothing: say so, since
        the answer was just shown as if about to be saved."""
        self.console.print(
            f"  not written: {summary} ({_trials(q)} asked again when the session resumes)",
            markup=False,
        )

    def _written(
        self,
        q: SessionQuery,
        reason: str,
        stop_warning: str | None = None,
        clipped: Sequence[str] = (),
        stopped: str | None = None,
        unsafe: Sequence[int] = (),
    ) -> None:
        """Say the answer to ``q`` is saved, write the unsafe flag asked with it (``reason``,
        on the trials ``unsafe``, default every trial of ``q``), then say how sure the model is
        now: after the flag, so that the recommendation is never the gait about to be flagged
        (it said so before, then flagged it).  ``stop_warning``: why the ``[stop]`` rule could
        not be checked after the answer (:attr:`Answered.stop_warning`), and ``clipped``: the
        suggestions that went past the edge of their range (:attr:`Answered.clipped`), said
        after the save; ``stopped``: the rule's reason when it opened blind validation after the
        answer (:attr:`Answered.stopped`), said last, before the round is shown."""
        self.console.print(f"saved: trial {', '.join(map(str, q.trials))}", markup=False)
        for note in clipped:
            self.console.print(f"  note: {clip(note, MAX_MESSAGE)}", markup=False)
        if stop_warning is not None:
            self.console.print(f"  warning: {clip(stop_warning, MAX_MESSAGE)}", markup=False)
        if reason:
            self._flag_all(q, reason, unsafe)
        self._say_confidence()
        if stopped is not None:
            self.console.print(
                f"  the [stop] rule says stop ({clip(stopped, MAX_MESSAGE)}): blind validation "
                "opens",
                markup=False,
            )

    def _flag_all(self, q: SessionQuery, reason: str, unsafe: Sequence[int]) -> None:
        """Flag the trials ``unsafe`` of ``q`` (default every trial) for ``reason``: say which
        were, what the flag does, and a validation round drawn again for it."""
        s = self.session
        redrawn = False
        flagged: list[int] = []
        for t in dict.fromkeys(unsafe or q.trials):
            done = self._flag(t, reason)
            if done is not None:
                flagged.append(t)
                redrawn |= done
        if flagged:
            self.console.print(
                f"flagged unsafe: trial {', '.join(map(str, flagged))} ({clip(reason)}); "
                + s.config.safety.flag_effect(s.config.space.continuous),
                markup=False,
            )
        if redrawn:
            self.console.print(
                "  the blind validation round showed a gait near the flag: it is drawn "
                "again among the gaits still allowed",
                markup=False,
            )

    def _say_confidence(self) -> None:
        """How sure the model is of its recommendation, once it learnt (as the console and
        session show: before that the recommendation is the first gait for no reason), with or
        without a ``[stop]`` rule; and why the rule cannot open validation, if so."""
        s = self.session
        with contextlib.suppress(*_UNWRITTEN):  # only a report: the answer is written
            if preference_learned(s.posterior().mean):
                try:
                    sure = s.confidence()
                except NoSafeGaitError as exc:  # no gait to recommend: say why, as show does
                    why = s.no_recommendation() or str(exc)
                    line = f"no gait may be recommended now ({why}), so no confidence is stated"
                else:
                    line = sure.sentence(gait_name(s, sure.recommended))
                    if s.gait_made(sure.recommended) is False:  # a point no query proposed
                        line += f" ({NOT_MADE})"
                self.console.print(f"  {clip(line, MAX_MESSAGE)}", markup=False)
            self._say_stop_blocked()

    def _flag(self, trial: int, reason: str) -> bool | None:
        """Flag ``trial`` unsafe: what :meth:`Session.flag_unsafe` returns, or None when it could
        not be written (said so, with the command that writes it later).  Refused as busy (another
        writer holds the session), the operator is asked whether to try again."""
        s = self.session
        later = f"flag it later with: {self.flag_with(trial, reason)}"
        while True:
            try:
                return s.flag_unsafe(trial, reason)
            except _UNWRITTEN as exc:
                if self._flagged(trial):  # written; the round it withdrew was not drawn again
                    self.console.print(f"  {clip(exc, MAX_MESSAGE)}", markup=False)
                    return False
                self.console.print(
                    f"  trial {trial} is not flagged unsafe yet: {clip(exc, MAX_MESSAGE)}; {later}",
                    markup=False,
                )
            except SessionStateError as exc:  # finished elsewhere, or withdrawn meanwhile
                self.console.print(
                    f"  trial {trial} was not flagged unsafe: {clip(exc, MAX_MESSAGE)}; {later}",
                    markup=False,
                )
                return None
            try:
                key = self.ask(f"Flag trial {trial} unsafe again?  y yes, n no", {"y": "", "n": ""})
            except _UndoError:  # the flag is being asked: no undo before it is settled
                self.console.print("  the flag is being asked: y yes, n no", markup=False)
                continue
            if key == "n":
                self.console.print(f"  trial {trial} not flagged; {later}", markup=False)
                return None

    def _which_unsafe(self, q: SessionQuery) -> tuple[int, ...]:
        """The trials of ``q`` to flag unsafe: asked when it ran several (n > 1), so that one
        unsafe gait does not take the query's other gaits away too."""
        trials = tuple(dict.fromkeys(q.trials))
        if len(trials) == 1:
            return trials
        keys = {str(t): "" for t in trials}
        key = self.ask(
            f"Which trial is unsafe? {', '.join(keys)}, a all of them", {**keys, "a": ""}
        )
        return trials if key == "a" else (int(key),)

    def _reason(self) -> str:
        """Why the trial is unsafe (asked until given; ``q`` pauses and ``u`` undoes, as at
        every prompt, so neither is ever taken for the reason).  A reason the flag would refuse
        (too long, undecodable bytes) is refused here, before the answer is written."""
        while True:
            self.console.print("Why is it unsafe? (a few words; q pause, u undo)", markup=False)
            text = self.read().strip()
            if text.lower() == "q":
                raise _QuitError
            if text.lower() == "u":
                raise _UndoError
            if not text:
                continue
            try:
                return check_printable(check_unsafe_reason(text), "the reason")
            except ValueError as exc:
                self.console.print(f"  {exc}; type it again", markup=False)

    def _ratings(self, q: SessionQuery) -> tuple[list[object], list[str]]:
        """A rating per executed trial when the config asks for them (Enter skips)."""
        scale = self.session.config.ordinal
        if scale is None:
            return [], []
        out: list[object] = []
        said: list[str] = []
        keys = {str(k + 1): label for k, label in enumerate(scale.categories)}
        options = ", ".join(f"{k} {label}" for k, label in keys.items())
        for a, numbers in _trials_of(q).items():  # a gait run twice in the query: rated once
            which = _trials(numbers) + (" (the same gait)" if len(numbers) > 1 else "")
            key = self.ask(
                f"Rating of {which}: {options}, Enter to skip", {**keys, "": ""}, default=""
            )
            if key:
                out.append(Rating(a, keys[key]))
                said.append(f"{_trials(numbers)} rated {keys[key]}")
        return out, said

    def _gait(self, action: int) -> str:
        return f"{gait_name(self.session, action)} ({self.session.space.describe(action)})"

    def _comparisons(self, q: SessionQuery) -> tuple[list[tuple[int, int, str]], list[str]]:
        """Each pair the query asks (:attr:`SessionQuery.pairs`, the console's and the
        simulated users' too); a pair it does not ask is said, with why."""
        out: list[tuple[int, int, str]] = []
        said: list[str] = []
        members, numbers = q.members, q.member_trials
        for pair in q.pairs:
            r, c = pair.first, pair.second
            ti, tj, ai, aj = numbers[r], numbers[c], members[r], members[c]
            if pair.same_gait:
                self.console.print(
                    f"  trials {ti} and {tj} are the same gait: nothing to compare",
                    markup=False,
                )
                continue
            if pair.repeats is not None:  # a gait run twice (b > 1, n > 1): asked once
                pi, pj = (numbers[k] for k in pair.repeats)
                self.console.print(
                    f"  trial {ti} against trial {tj}: the same gaits as trial {pi} against "
                    f"trial {pj}, compared once",
                    markup=False,
                )
                continue
            # "the previous one" only when one trial is buffered: with b > 1 the buffer
            # holds earlier ones too, and trial 1 of 1, 2 is not "the previous one"
            previous = c >= len(q.actions) and len(q.buffer) == 1
            other = "the previous one" if previous else f"trial {tj}"
            this = "this one" if len(q.actions) == 1 else f"trial {ti}"
            answer = self.ask(
                f"Trial {ti} against trial {tj}: 1 {this}, 2 {other}, 0 no preference",
                {"1": "first", "2": "second", "0": "none"},
            )
            outcome = {"1": "first", "2": "second", "0": "none"}[answer]
            out.append((ai, aj, outcome))
            said.append(
                f"no preference between trials {ti} and {tj}"
                if outcome == "none"
                else f"trial {ti if outcome == 'first' else tj} preferred to trial "
                f"{tj if outcome == 'first' else ti}"
            )
        return out, said

    def _suggestions(self, q: SessionQuery) -> tuple[list[tuple[int, str, str]], list[str]]:
        out: list[tuple[int, str, str]] = []
        said: list[str] = []
        space = self.session.space
        for a, numbers in _trials_of(q).items():  # a gait run twice: one suggestion per feature
            same = ", the same gait" if len(numbers) > 1 else ""
            for f in space.features:
                words = _move_words(f)
                options = ", ".join(f"{k + 1} {w}" for k, w in enumerate(words))
                where = f" ({_trials(numbers)}{same})" if len(q.actions) > 1 else ""
                key = self.ask(
                    f"Suggestion for {f.name}{where}: {options}, 0 none",
                    {"0": "", "1": "", "2": "", "3": "", "4": ""},
                    default="0",
                )
                if key != "0":
                    out.append((a, f.name, _MOVES[int(key) - 1]))
                    said.append(f"{f.name}{where} {words[int(key) - 1]}")
        return out, said

    # -- blind validation ----------------------------------------------------------------------
    def _show_round(self, plan: ValidationPlan, hint: bool = True) -> list[str]:
        """Print the round's gaits in label order (and, with ``hint``, the command that records
        their ranking later: :meth:`_say_record_with`); their names (checked when it is
        ranked)."""
        self.console.print(
            f"Blind validation, round {plan.round}: run these gaits in this order and tell the "
            "subject nothing about them.",
            markup=False,
        )
        gaits = self.session.validation_gaits(plan.round)
        for g in gaits:
            self.console.print(f"  Gait {g.label}: {g.gait} ({g.text})", markup=False)
        self.shown_gaits = [g.gait for g in gaits]
        if hint:
            self._say_record_with(self.shown_gaits)
        return self.shown_gaits

    def _say_record_with(self, names: list[str]) -> None:
        """With :attr:`record_with`, print the command that records the ranking of the round
        that shows the gaits ``names``."""
        if self.record_with is not None:
            self.console.print(
                f"  To record the ranking later: {self.record_with(names)}\n"
                "  (RANKING: the subject's, best first; refused if the round shows other gaits "
                "by then)",
                markup=False,
            )

    def _withdraw(self, round_: int) -> None:
        """``u`` inside a round: offer to withdraw it, and to undo the answer after which the
        ``[stop]`` rule opened it when it did (and that answer is still the last); confirmed
        with ``y``.  Withdrawn: :class:`_WithdrawnError` (the loop goes on with the trials);
        refused or not confirmed: said, and the ranking is asked again."""
        s = self.session
        info = next((r for r in s.validation_rounds() if r.round == round_ and r.open), None)
        if info is None:
            raise SessionStateError(f"validation round {round_} is no longer open")
        undo = info.opened_by == "rule"
        trials = [t.number for t in s.trials() if t.query == info.opened_after]
        try:
            s.check_withdraw_validation(round_, undo=undo)
        except SessionStateError as exc:  # undone since, flagged unsafe...: the round alone
            if undo:
                self.console.print(
                    f"  the answer that opened it cannot be undone with it: "
                    f"{clip(exc, MAX_MESSAGE)}",
                    markup=False,
                )
            undo = False
        if undo:
            question = (
                f"The [stop] rule opened round {round_} after the answer to "
                f"{_trials(trials)}.  Withdraw the round and undo that answer (it is asked "
                "again)?  y yes, n no"
            )
            reason = f"u at the terminal: the answer to {_trials(trials)} that opened it is undone"
        else:
            question = f"Withdraw validation round {round_} unanswered?  y yes, n no"
            reason = "u at the terminal"
        while True:
            try:
                key = self.ask(question, {"y": "", "n": ""})
                break
            except _UndoError:  # u again: the question stands
                self.console.print("  withdrawing is being asked: y yes, n no", markup=False)
        if key == "n":
            self.console.print(
                "  not withdrawn: the subject's ranking, best first, as before", markup=False
            )
            return
        try:
            pending = s.withdraw_validation(round_, reason, undo=undo)
        except SessionStateError as exc:  # another writer answered or withdrew it meanwhile
            self.console.print(f"  cannot withdraw: {clip(exc, MAX_MESSAGE)}", markup=False)
            if s.validation_plan is None or s.validation_plan.round != round_:
                raise
            return
        except _UNWRITTEN as exc:  # the ranking is asked again, unless the round is withdrawn
            withdrawn = self._withdrawn(round_)
            if withdrawn:  # the query in place of the undone one's could not be written
                done = f"; undone: the answer to {_trials(trials)}" if undo else ""
                self.console.print(f"Round {round_} withdrawn{done}.", markup=False)
                self.console.print(
                    f"The next trial could not be proposed: {clip(exc, MAX_MESSAGE)}",
                    markup=False,
                )
                raise _QuitError from None
            said = "not withdrawn" if withdrawn is False else "perhaps not withdrawn"
            self.console.print(f"  {said}: {clip(exc, MAX_MESSAGE)}", markup=False)
            return
        except NoSafeGaitError as exc:  # written; no gait left for the query in its place
            self.console.print(f"Round {round_} withdrawn.", markup=False)
            self.console.print(f"No gait to propose: {clip(exc, MAX_MESSAGE)}", markup=False)
            raise _QuitError from None
        except GaitError as exc:  # written; the query in its place could not be made
            self.console.print(f"Round {round_} withdrawn.", markup=False)
            self._say_no_gait(exc)
            raise _QuitError from None
        line = f"Round {round_} withdrawn"
        if undo:
            again = pending is not None and pending.id == info.opened_after
            line += (
                f"; undone: the answer to {_trials(trials)} is asked again."
                if again
                else f"; undone the answer to {_trials(trials)}: its query proposed a gait "
                "flagged unsafe since, or in the region of avoidance now, and was withdrawn: "
                "a new query is proposed in its place."
            )
        else:
            line += "."
        self.console.print(line, markup=False)
        raise _WithdrawnError

    def validate(self, ranking: str | None = None, gaits: Sequence[str] | None = None) -> None:
        """Run (or resume) a blind validation round and report the unblinded result.

        A ranking is refused if the round was drawn again since its gaits were shown (another
        writer flagged a gait it showed): the round's gaits are shown again as they are now and
        the ranking asked again (with ``ranking`` given: :class:`SessionStateError`).  When no
        round is open any more, :class:`SessionStateError` says the ranking was not recorded.

        ``gaits``, with ``ranking``: the names of the gaits the subject walked, in label order,
        as an earlier display of the round showed them (``session validate ID --gaits``, typed
        in another command).  The ranking is then recorded only if the open round shows those
        gaits now (:class:`SessionStateError` naming both lists otherwise; the round is shown as
        it is now), and no round is opened: without them, the round shown here is the one
        ranked, and a round drawn again in between went unnoticed."""
        s = self.session
        if gaits is not None and ranking is None:
            raise SessionStateError("the gaits shown check a ranking: give the ranking too")
        if ranking is not None:  # refused before a round is logged
            try:
                check_ranking(ranking, LABELS)
            except ValueError as exc:
                raise SessionStateError(str(exc)) from None
        if gaits is None:
            plan = s.start_validation()
        else:
            open_ = s.validation_plan
            if open_ is None:
                raise SessionStateError(
                    f"the ranking {ranking} of {', '.join(gaits)} was not recorded: no blind "
                    "validation round is open (the round that showed them was answered since, "
                    "or an unsafe flag withdrew it and fewer than three gaits are left to show); "
                    "nothing was written"
                )
            plan = open_
        shown = self._show_round(plan, hint=ranking is None)
        # compared joined: a name with a comma in it comes split by the command line
        if gaits is not None and ",".join(gaits) != ",".join(shown):
            self._say_record_with(shown)
            raise SessionStateError(
                f"the ranking {ranking} was not recorded: it ranks the gaits {', '.join(gaits)}, "
                f"but validation round {plan.round} shows {', '.join(shown)} now (drawn again "
                "since those were shown: an unsafe flag on one of them; or mistyped); nothing "
                "was written: run the round's gaits as shown now and record their ranking"
            )
        while True:
            if ranking is None:
                self.console.print(
                    f"The subject's ranking, best first (e.g. {''.join(plan.labels)}; "
                    "u withdraw the round, q quit):",
                    markup=False,
                )
                given = self.read().strip()
                if given.lower() == "q":
                    raise _QuitError
                if given.lower() == "u":  # offers to withdraw the round (and undo its answer)
                    self._withdraw(plan.round)
                    continue
                try:  # refused before the confirmation is asked
                    check_ranking(given, plan.labels)
                except ValueError as exc:
                    self.console.print(f"  {exc}", markup=False)
                    continue
                try:
                    key = self.ask(
                        f"Write the ranking {given}?  y yes, n re-enter", {"y": "", "n": ""}
                    )
                except _UndoError:  # offers to withdraw the round, then asks the ranking again
                    self._withdraw(plan.round)
                    continue
                if key == "n":
                    continue
            else:
                given = ranking
            try:  # refused if the round was drawn again since its gaits were shown
                result = s.answer_validation(plan.round, given, shown=shown)
                break
            except _UNWRITTEN as exc:  # nothing written: the ranking is asked again
                if ranking is not None:
                    raise
                self.console.print(
                    f"  the ranking was not recorded: {clip(exc, MAX_MESSAGE)}; type it again",
                    markup=False,
                )
                continue
            except SessionStateError as exc:
                if ranking is not None:
                    raise
                self.console.print(f"  {exc}", markup=False)
                now = s.validation_plan  # as another writer left it (a flag, an answer)
                if now is None:
                    raise SessionStateError(
                        f"the ranking {given} was not recorded: no blind validation round is "
                        "open any more (another writer answered it, or a flag withdrew it and "
                        "fewer than three gaits are left to show)"
                    ) from None
                if now != plan or [g.gait for g in s.validation_gaits()] != shown:
                    plan = now  # drawn again: the subject walks the round's gaits as they are
                    shown = self._show_round(plan)
        roles = ", ".join(f"{label} = {result.roles[label]}" for label in plan.labels)
        verdict = "agrees" if result.agrees else "does not agree"
        self.console.print(
            f"Unblinded: {roles}.  The subject's ranking {''.join(result.ranking)} {verdict} "
            f"with the posterior ({''.join(result.model_ranking)}); Kendall's tau "
            f"{result.kendall_tau:+.2f}.",
            markup=False,
        )


def run_terminal(
    session: Session,
    console: Console | None = None,
    read: Reader = input,
    resume: str | None = None,
    flag_with: Callable[[int, str], str] | None = None,
) -> None:
    """The interactive loop of ``gaitpref session run``; ``resume`` is the command it prints,
    ``flag_with`` the one that flags a trial unsafe later (given its number and the reason)."""
    Terminal(session, console, read, resume, flag_with=flag_with).run()


def run_validation(
    session: Session,
    ranking: str | None = None,
    console: Console | None = None,
    read: Reader = input,
    *,
    gaits: Sequence[str] | None = None,
    record_with: Callable[[Sequence[str]], str] | None = None,
) -> bool:
    """The blind validation of ``gaitpref session validate``; False if the operator quit.

    ``gaits``: the round's gait names as shown earlier (:meth:`Terminal.validate`);
    ``record_with``: the command that records the ranking later, given the names shown, printed
    with the round and, when the operator quits, with the round's state."""
    terminal = Terminal(session, console, read, record_with=record_with)
    try:
        with terminal.pause_on_signals():
            terminal.validate(ranking, gaits)
    except _WithdrawnError:
        return False
    except (_QuitError, _UndoError):
        # not after a withdrawal that was written (the query in place of the answer it undid
        # could not be proposed): no round stays open then
        if (
            record_with is not None
            and terminal.shown_gaits is not None
            and session.validation_plan is not None
        ):
            terminal.console.print(
                "No ranking recorded; the round stays open (no trials are proposed until it is "
                "answered or withdrawn: gaitpref session validate "
                f"{session.id} --withdraw --reason TEXT).  Record it with: "
                f"{record_with(terminal.shown_gaits)}",
                markup=False,
            )
        return False
    return True
