"""Run a :class:`~gaitpref.simulate.study.Study` in parallel: joblib processes or Ray.

Both backends call the same pure :func:`~gaitpref.simulate.study.run_one` on the same
:class:`~gaitpref.simulate.study.RunTask` values, and the results are put back in study order
(setting, objective, seed) whatever order they finish in, so a study's tables are identical on
either backend and for any number of workers.

- ``"joblib"`` (default): ``jobs`` local worker processes (loky), each with single-threaded BLAS
  (small linear algebra is several times slower when threads oversubscribe the cores);
  ``jobs = 1`` runs in this process.
- ``"ray"``: tasks on a Ray cluster: the one at ``address`` (``"auto"`` or ``"ray://..."``),
  an already initialised runtime, or else a local runtime with ``num_cpus = jobs`` that is
  started here and shut down afterwards.  Ray is an optional extra: ``pip install gaitpref[ray]``.

A Rich progress bar (runs done, runs per second, time left) is drawn when ``progress`` is true.

When a run fails (its error, or its worker dies) the study stops and raises
:class:`~gaitpref.simulate.partial.StudyRunError` naming the run, with the runs that finished;
given ``partial``, a CSV path, each finished run is also appended there as it finishes (the file
is removed when the whole study finishes, and kept when it does not, whatever stopped it).
"""

from __future__ import annotations

import contextlib
import logging
import os
import socket
import tempfile
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    ProgressColumn,
    Task,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.text import Text

from gaitpref.simulate.partial import RunFailure, run_table, sendable, study_error
from gaitpref.simulate.study import RunResult, RunTask, Study, run_one
from gaitpref.simulate.tables import Curves, RunTable, TableAppender, summarize

Backend = Literal["joblib", "ray"]
BACKENDS: tuple[Backend, ...] = ("joblib", "ray")


@dataclass(frozen=True, eq=False)
class StudyResult:
    """A finished study: its run table, curves and how it was run."""

    study: Study
    table: RunTable
    curves: Curves
    backend: str
    jobs: int
    seconds: float


class _RateColumn(ProgressColumn):
    def render(self, task: Task) -> Text:
        speed = task.finished_speed or task.speed
        return Text("  -  runs/s" if speed is None else f"{speed:5.1f} runs/s", style="cyan")


def _progress(console: Console | None) -> Progress:
    return Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("runs"),
        _RateColumn(),
        TimeElapsedColumn(),
        TextColumn("left"),
        TimeRemainingColumn(),
        console=console,
        transient=False,
    )


def resolve_jobs(jobs: int | None) -> int:
    """``None`` or ``<= 0``: every core (``-1`` is all, ``-2`` all but one, as joblib counts)."""
    cores = os.cpu_count() or 1
    if jobs is None:
        return cores
    if jobs == 0:
        raise ValueError("jobs must be a positive count or negative (all cores but |jobs| - 1)")
    return jobs if jobs > 0 else max(1, cores + 1 + jobs)


def run_study(
    study: Study,
    backend: Backend = "joblib",
    jobs: int | None = None,
    address: str | None = None,
    progress: bool = False,
    console: Console | None = None,
    partial: str | Path | None = None,
) -> StudyResult:
    """Run every run of ``study`` and collect the tidy table and curves.

    A run that fails stops the study with :class:`~gaitpref.simulate.partial.StudyRunError`
    (the run named, the finished runs kept on it); ``partial``: a ``.csv`` file each finished
    run is appended to as it finishes, removed once every run has finished.
    """
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {', '.join(BACKENDS)}; got {backend!r}")
    if address is not None and backend != "ray":
        raise ValueError("address is for the Ray backend (--backend ray)")
    tasks = study.tasks()
    # no more workers than runs: each loky worker is a process that loads NumPy and SciPy, and
    # a mistyped --jobs 1000 started a thousand of them for a handful of runs
    n_jobs = min(resolve_jobs(jobs), len(tasks))
    rated = any(s.rating_quantiles for s in study.settings)
    results: list[RunResult | None] = [None] * len(tasks)
    sink = None if partial is None else TableAppender(partial, rated)  # before any run
    start = time.perf_counter()
    try:
        with _progress(console) if progress else _NoProgress() as bar:
            tid = bar.add_task(study.name, total=len(tasks))
            runner = _run_ray if backend == "ray" else _run_joblib
            for index, outcome in runner(tasks, n_jobs, address):
                if isinstance(outcome, RunFailure):
                    finished = any(r is not None for r in results)
                    kept = sink.path if sink is not None and finished else None
                    raise study_error(outcome, tasks, results, rated, kept)
                results[index] = outcome
                if sink is not None:
                    sink.append(run_table([outcome], rated))
                bar.advance(tid)
    finally:
        if sink is not None:
            sink.close()
            if not any(r is not None for r in results):
                sink.path.unlink(missing_ok=True)  # nothing finished: nothing to keep
    seconds = time.perf_counter() - start
    done = [r for r in results if r is not None]
    if len(done) != len(tasks):
        raise RuntimeError(f"{len(tasks) - len(done)} of {len(tasks)} runs returned no result")
    table = run_table(done, rated)
    if sink is not None:
        sink.path.unlink(missing_ok=True)  # the whole study finished: its tables are the result
    return StudyResult(study, table, summarize(table), backend, n_jobs, seconds)


def _attempt(index: int, task: RunTask) -> RunResult | RunFailure:
    """``run_one(task)``, or the failure that names it."""
    try:
        return run_one(task)
    except Exception as exc:
        return RunFailure((index,), sendable(exc))


def _indexed(item: tuple[int, RunTask, str]) -> tuple[int, RunResult | RunFailure]:
    """A worker's run: marked as running (a file named by its index in ``item[2]``) until it
    returns, so that a worker that dies leaves the name of the run it was running."""
    index, task, running = item
    marker = Path(running) / str(index)
    with contextlib.suppress(OSError):  # the study stopped and took the folder away
        marker.touch()
    try:
        return index, _attempt(index, task)
    finally:
        marker.unlink(missing_ok=True)


def _run_joblib(
    tasks: list[RunTask], jobs: int, address: str | None
) -> Iterator[tuple[int, RunResult | RunFailure]]:
    """Each run's index and result as it finishes; a failure last: after a run's error no more
    runs start and those in progress finish first (their results are kept)."""
    if jobs == 1:
        for i, task in enumerate(tasks):
            outcome = _attempt(i, task)
            yield i, outcome
            if isinstance(outcome, RunFailure):
                return
        return
    from joblib import Parallel, delayed

    parallel = Parallel(
        n_jobs=jobs, backend="loky", inner_max_num_threads=1, return_as="generator_unordered"
    )
    failed: list[RunFailure] = []
    with tempfile.TemporaryDirectory(prefix="gaitpref-running-") as running:

        def feed() -> Iterator[Any]:  # read by joblib as it dispatches: none after a failure
            for i, t in enumerate(tasks):
                if failed:
                    return
                yield delayed(_indexed)((i, t, running))

        try:
            for i, outcome in parallel(feed()):
                if not isinstance(outcome, RunFailure):
                    yield i, outcome
                elif not failed:
                    failed.append(outcome)
        except Exception as exc:  # not a run's error (each is sent back): a worker died
            names = sorted(int(p.name) for p in Path(running).iterdir() if p.name.isdigit())
            failed.append(RunFailure(tuple(names), exc, died=True))
    if failed:
        yield -1, failed[0]


def _import_ray() -> Any:
    try:
        import ray
    except ImportError:
        raise RuntimeError(
            "the Ray backend needs Ray: pip install 'gaitpref[ray]' (or use --backend joblib)"
        ) from None
    return ray


def start_ray(address: str | None = None, jobs: int | None = None) -> bool:
    """Initialise Ray quietly unless it already is; True when this call started it."""
    ray = _import_ray()
    if ray.is_initialized():
        return False
    options: dict[str, Any] = {
        "include_dashboard": False,
        "logging_level": logging.ERROR,
        "log_to_driver": False,
        "configure_logging": True,
    }
    if address is None:
        options["num_cpus"] = resolve_jobs(jobs)
    else:
        _probe(address)
    os.environ.setdefault("RAY_DEDUP_LOGS", "0")
    try:
        ray.init(address=address, **options)
    except (ConnectionError, TimeoutError, ValueError) as exc:
        where = f"the Ray cluster at {address!r}" if address else "a local Ray runtime"
        raise RuntimeError(f"could not start or reach {where}: {exc}") from None
    return True


def _probe(address: str, timeout: float = 5.0) -> None:
    """Refuse a ``HOST:PORT`` address where nothing listens (Ray retried it for minutes, its
    warnings the only output); ``auto`` and ``ray://`` addresses Ray itself answers at once."""
    host, sep, port = address.rpartition(":")
    if "://" in address or not sep or not port.isdigit():
        return
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout):
            pass
    except OSError as exc:
        raise RuntimeError(
            f"could not reach the Ray cluster at {address!r}: nothing answers there "
            f"({exc.strerror or exc}); start one (ray start --head) or give its address"
        ) from None


def _run_ray(
    tasks: list[RunTask], jobs: int, address: str | None
) -> Iterator[tuple[int, RunResult | RunFailure]]:
    ray = _import_ray()
    started = start_ray(address, jobs)
    pending: list[Any] = []
    try:
        remote: Callable[..., Any] = ray.remote(num_cpus=1, max_retries=0)(run_one).remote
        refs = [remote(t) for t in tasks]
        position = {ref: i for i, ref in enumerate(refs)}
        pending = list(refs)
        while pending:
            done, pending = ray.wait(pending, num_returns=1, timeout=None)
            for ref in done:
                i = position[ref]
                try:
                    result = ray.get(ref)
                except ray.exceptions.RayTaskError as exc:  # the run's own error, as on joblib
                    cause = getattr(exc, "cause", None)  # (not the remote traceback)
                    error = cause if isinstance(cause, Exception) else exc
                    failure = RunFailure((i,), error)
                except ray.exceptions.RayError as exc:  # its worker died, or the task was lost
                    failure = RunFailure((i,), exc, died=True)
                else:
                    yield i, result
                    continue
                yield from _finished_already(ray, pending, position)
                yield i, failure
                return
    finally:
        for ref in pending:  # the runs not finished when one failed: not left running
            with contextlib.suppress(Exception):
                ray.cancel(ref)
        if started:
            ray.shutdown()


def _finished_already(
    ray: Any, pending: list[Any], position: dict[Any, int]
) -> Iterator[tuple[int, RunResult]]:
    """The results of ``pending`` runs that have finished by now (a failure stops the rest)."""
    if not pending:
        return
    done, _ = ray.wait(pending, num_returns=len(pending), timeout=0)
    for ref in done:
        with contextlib.suppress(ray.exceptions.RayError):
            yield position[ref], ray.get(ref)


class _NoProgress:
    def __enter__(self) -> _NoProgress:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def add_task(self, description: str, total: int) -> TaskID:
        return TaskID(0)

    def advance(self, task: TaskID) -> None:
        return None
