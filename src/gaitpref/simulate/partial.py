"""What a study keeps when one of its runs fails: the runs that finished, and the failure.

A run fails when :func:`~gaitpref.simulate.study.run_one` raises (in a worker, its exception
is caught there and sent back as a :class:`RunFailure` naming the run) or when the worker
running it dies (a crash, the out-of-memory killer: on joblib every run in progress then is a
candidate, each marked while it runs; Ray names the one).
:func:`~gaitpref.simulate.sweep.run_study` then starts no more runs, keeps those that finished
(on joblib, also the runs in progress when a run raised, once they finish) in memory and, when
asked, in a ``partial`` CSV run table written run by run, and raises :class:`StudyRunError`,
which names the failed run (setting, objective, seed) and where the finished runs are.
"""

from __future__ import annotations

import pickle
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gaitpref.errors import GaitprefError
from gaitpref.simulate.study import RunResult, RunTask
from gaitpref.simulate.tables import RunTable


@dataclass(frozen=True, eq=False)
class RunFailure:
    """A run that failed: its index in the study's tasks (several when a worker died while
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


def coordinates(task: RunTask) -> str:
    """A run as the errors name it: ``setting 'n1_b1', objective 3, seed 0``."""
    return f"setting {task.setting.name!r}, objective {task.objective_id}, seed {task.seed}"


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


class StudyRunError(GaitprefError, RuntimeError):
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
        super().__init__(message)
        self.candidates = candidates
        one = len(candidates) == 1
        self.setting: str | None = candidates[0][0] if one else None
        self.objective_id: int | None = candidates[0][1] if one else None
        self.seed: int | None = candidates[0][2] if one else None
        self.finished = finished
        self.partial = partial
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
    error = failure.error
    named = [tasks[i] for i in failure.indices]
    kind = type(error).__name__
    if len(named) == 1 and failure.died:
        what = f"{coordinates(named[0])} failed: the worker running it died ({kind}: {error})"
    elif len(named) == 1:
        where = coordinates(named[0])
        what = f"{where} failed ({kind}): {str(error).removeprefix(where + ': ')}"
    elif named:
        among = "; ".join(coordinates(t) for t in named)
        what = f"a worker died ({kind}: {error}) while running one of: {among}"
    else:
        what = f"a worker failed ({kind}: {error}); which run is not known"
    kept = f"{len(finished)} of {len(tasks)} runs finished"
    if not finished:
        kept += " (none to keep)"
    elif partial is not None:
        kept += f"; their results are in {partial}"
    else:
        kept += "; their results are on this error (StudyRunError.finished, .table())"
    err = StudyRunError(
        f"{what}; the study stopped: {kept}",
        candidates=tuple((t.setting.name, t.objective_id, t.seed) for t in named),
        finished=finished,
        rated=rated,
        partial=partial if finished else None,
    )
    err.__cause__ = error
    return err


__all__ = ["RunFailure", "StudyRunError", "coordinates", "run_table", "sendable", "study_error"]
