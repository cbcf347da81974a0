"""What a sweep keeps when one of its runs fails: the runs that finished, and the failure.

A sweep is many independent runs: a study's (settings x objectives x seeds), ``gaitpref bench
continuous``'s (seeds) or ``gaitpref bench population``'s (each subject cold, then warm).  A run
fails when its function raises (in a worker, its exception is caught there and sent back as a
:class:`RunFailure` naming the run) or when the worker running it dies (a crash, the
out-of-memory killer: on joblib every run in progress then is a candidate, each marked while it
runs; Ray names the one).  :func:`~gaitpref.simulate.sweep.run_tasks` then starts no more runs;
the sweep keeps those that finished (on joblib, also the runs in progress when a run raised, once
they finish) in memory and, when asked, in a ``partial`` file written run by run
(:func:`partial_file`: a CSV run table for a study, :class:`JsonLines` for a bench), and raises
:class:`RunError` (a study: :class:`StudyRunError`), which names the failed run (a study's
setting, objective and seed; a bench's objective or subject, and seed), its error and where the
finished runs are.  A study resumes from its partial table (:mod:`gaitpref.simulate.resume`),
``bench continuous`` and ``bench population`` from their JSON lines
(:mod:`gaitpref.simulate.resume_lines`).
"""

from __future__ import annotations

import json
import pickle
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Generic, Protocol, TypeVar

import numpy as np

from gaitpref.errors import GaitprefError
from gaitpref.simulate.study import RunResult, RunTask
from gaitpref.simulate.tables import RecordFile, RunTable

R = TypeVar("R")


@dataclass(frozen=True, eq=False)
class RunFailure:
    """A run that failed: its index in the sweep's tasks (several when a worker died while
    running any of them; none known: empty), the error, and whether its worker died."""

    indices: tuple[int, ...]
    error: BaseException
    died: bool = False


def sendable(exc: BaseException) -> BaseException:
    """``exc``, or a ``RuntimeError`` with its type and text when it cannot be pickled back
    from a worker process."""
    try:
        pickle.dumps(exc)
    except Exception:
        return RuntimeError(f"{type(exc).__name__}: {exc}")
    return exc


class RunError(GaitprefError, RuntimeError, Generic[R]):
    """A run of a sweep failed; the sweep stopped, keeping the runs that finished.

    ``runs`` names the failed run as the message does (several when a worker died while running
    any of them; none when which is not known), ``run`` the one (None otherwise); ``finished``
    holds the finished runs' results in the sweep's order; ``partial`` is the file they were
    written to as they finished (None when none was asked for, or none finished).  The run's own
    error is the ``__cause__``.
    """

    def __init__(
        self,
        message: str,
        *,
        runs: tuple[str, ...],
        finished: tuple[R, ...],
        partial: Path | None,
    ) -> None:
        super().__init__(message)
        self.runs = runs
        self.run: str | None = runs[0] if len(runs) == 1 else None
        self.finished = finished
        self.partial = partial


def stopped_message(
    failure: RunFailure,
    named: Sequence[str],
    finished: int,
    total: int,
    partial: Path | None,
    sweep: str,
    holder: str,
) -> str:
    """The message of a ``sweep`` (``"study"``, ``"bench"``) stopped by ``failure``: the failed
    run (``named``: the names of ``failure.indices``), its error, how many of ``total`` runs
    finished and where they are (``partial``, else the error's attributes ``holder``)."""
    error = failure.error
    kind = type(error).__name__
    if len(named) == 1 and failure.died:
        what = f"{named[0]} failed: the worker running it died ({kind}: {error})"
    elif len(named) == 1:
        where = named[0]
        what = f"{where} failed ({kind}): {str(error).removeprefix(where + ': ')}"
    elif named:
        what = f"a worker died ({kind}: {error}) while running one of: {'; '.join(named)}"
    else:
        what = f"a worker failed ({kind}: {error}); which run is not known"
    kept = f"{finished} of {total} runs finished"
    if not finished:
        kept += " (none to keep)"
    elif partial is not None:
        kept += f"; their results are in {partial}"
    else:
        kept += f"; their results are on this error ({holder})"
    return f"{what}; the {sweep} stopped: {kept}"


def run_error(
    failure: RunFailure,
    names: Sequence[str],
    finished: Sequence[R],
    total: int,
    partial: Path | None,
    sweep: str = "bench",
) -> RunError[R]:
    """The error of a ``sweep`` stopped by ``failure``: ``names`` names the tasks that
    ``failure.indices`` index, ``finished`` are the results kept (of ``total`` runs)."""
    named = tuple(names[i] for i in failure.indices)
    message = stopped_message(
        failure, named, len(finished), total, partial, sweep, "RunError.finished"
    )
    err: RunError[R] = RunError(
        message, runs=named, finished=tuple(finished), partial=partial if finished else None
    )
    err.__cause__ = failure.error
    return err


def coordinates(task: RunTask) -> str:
    """A run as the errors name it: ``setting 'n1_b1', objective 3, seed 0``."""
    return _coordinates(task.setting.name, task.objective_id, task.seed)


def _coordinates(setting: str, objective_id: int, seed: int) -> str:
    return f"setting {setting!r}, objective {objective_id}, seed {seed}"


def run_table(results: Sequence[RunResult], rated: bool) -> RunTable:
    """The run table of ``results`` (in their order); ``rated``: with the rating column."""
    T = results[0].actions.size
    return RunTable(
        np.repeat([r.setting for r in results], T),
        np.repeat([r.objective_id for r in results], T),
        np.repeat([r.seed for r in results], T),
        np.tile(np.arange(1, T + 1), len(results)),
        np.concatenate([r.actions for r in results]),
        np.concatenate([r.normalized for r in results]),
        np.concatenate([np.zeros(T, np.intp) if r.ratings is None else r.ratings for r in results])
        if rated
        else None,
    )


class StudyRunError(RunError[RunResult]):
    """A run of a study failed; the study stopped, keeping the runs that finished.

    ``setting``, ``objective_id`` and ``seed`` name the failed run (None when a worker died
    while running any of ``candidates``); ``finished`` holds the finished runs' results in
    study order and :meth:`table` their run table; ``partial`` is the CSV run table they were
    written to as they finished (None when none was asked for).  The run's own error is the
    ``__cause__``.
    """

    def __init__(
        self,
        message: str,
        *,
        candidates: tuple[tuple[str, int, int], ...],
        finished: tuple[RunResult, ...],
        rated: bool,
        partial: Path | None,
    ) -> None:
        runs = tuple(_coordinates(*c) for c in candidates)
        super().__init__(message, runs=runs, finished=finished, partial=partial)
        self.candidates = candidates
        one = len(candidates) == 1
        self.setting: str | None = candidates[0][0] if one else None
        self.objective_id: int | None = candidates[0][1] if one else None
        self.seed: int | None = candidates[0][2] if one else None
        self._rated = rated

    def table(self) -> RunTable | None:
        """The finished runs' run table (None when none finished)."""
        return run_table(self.finished, self._rated) if self.finished else None


def study_error(
    failure: RunFailure,
    tasks: Sequence[RunTask],
    results: Sequence[RunResult | None],
    rated: bool,
    partial: Path | None,
) -> StudyRunError:
    """The error of a study stopped by ``failure``, with the ``results`` that finished."""
    finished = tuple(r for r in results if r is not None)
    named = [tasks[i] for i in failure.indices]
    holder = "StudyRunError.finished, .table()"
    message = stopped_message(
        failure, [coordinates(t) for t in named], len(finished), len(tasks), partial, "study",
        holder,
    )  # fmt: skip
    err = StudyRunError(
        message,
        candidates=tuple((t.setting.name, t.objective_id, t.seed) for t in named),
        finished=finished,
        rated=rated,
        partial=partial if finished else None,
    )
    err.__cause__ = failure.error
    return err


class Appender(Protocol):
    """A file the finished runs are appended to as they finish: where, and how many so far."""

    @property
    def path(self) -> Path: ...

    @property
    def appended(self) -> int: ...

    def close(self) -> None: ...


A = TypeVar("A", bound=Appender)


@contextmanager
def partial_file(sink: A | None) -> Iterator[A | None]:
    """``sink``, closed when the block ends: removed when it ends normally (every run finished;
    the results are the caller's to write) or when nothing was appended, and kept when an error
    ends it (a run's, an interrupt) after some run was."""
    try:
        yield sink
    except BaseException:
        if sink is not None:
            sink.close()
            if not sink.appended:
                sink.path.unlink(missing_ok=True)  # nothing finished: nothing to keep
        raise
    if sink is not None:
        sink.close()
        sink.path.unlink(missing_ok=True)


class JsonLines(RecordFile):
    """A JSON-lines file (one JSON object a line: one finished run of a bench) written a run at
    a time (a :class:`~gaitpref.simulate.tables.RecordFile`).  ``first``: an object written as
    the first line (the bench that writes the file: :mod:`gaitpref.simulate.resume_lines`), not
    counted as a run; ``existing``: the file exists, holding that many runs, and is appended to
    (nothing written first)."""

    def __init__(
        self,
        path: str | Path,
        first: Mapping[str, object] | None = None,
        existing: int | None = None,
    ) -> None:
        super().__init__(path, existing=existing)
        if first is not None and existing is None:
            self._open().write(json.dumps(first) + "\n")
            self._open().flush()

    def append(self, record: Mapping[str, object]) -> None:
        self._open().write(json.dumps(record) + "\n")
        self._recorded()


__all__ = [
    "Appender",
    "JsonLines",
    "RunError",
    "RunFailure",
    "StudyRunError",
    "coordinates",
    "partial_file",
    "run_error",
    "run_table",
    "sendable",
    "stopped_message",
    "study_error",
]
