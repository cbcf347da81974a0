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
``resume=True`` continues a study from that file: its runs are kept, only the others run
(:mod:`gaitpref.simulate.resume`).

:func:`run_tasks` is the machinery under it, for any function over any tasks: each result as it
finishes, and the first failure; ``gaitpref bench continuous`` and ``bench population`` keep
their finished runs with it too (:mod:`gaitpref.simulate.partial`).
"""

from __future__ import annotations

import contextlib
import logging
import os
import socket
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, TypeVar

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

from gaitpref.limits import MAX_JOBS
from gaitpref.simulate.partial import (
    RunFailure,
    partial_file,
    run_table,
    sendable,
    study_error,
)
from gaitpref.simulate.resume import read_partial, signature, write_partial
from gaitpref.simulate.study import RunResult, RunTask, Study, run_one
from gaitpref.simulate.tables import Curves, RunTable, TableAppender, summarize

Backend = Literal["joblib", "ray"]
BACKENDS: tuple[Backend, ...] = ("joblib", "ray")
T = TypeVar("T")
R = TypeVar("R")


@dataclass(frozen=True, eq=False)
class StudyResult:
    """A finished study: its run table, curves and how it was run."""

    study: Study
    table: RunTable
    curves: Curves
    backend: str
    jobs: int
    seconds: float
    #: the runs a resume kept from the partial run table (not run, not counted in ``seconds``)
    kept: int = 0


class _RateColumn(ProgressColumn):
    def render(self, task: Task) -> Text:
        if task.finished_time:
            # The whole sweep's rate, start-up included, not counting the runs a resume kept:
            # rich's own estimate reads its last 1,000 updates only and left out the wait for
            # the first (3 Ray runs in 7.6 s showed 41.9 runs/s; a resumed 4,000-run study,
            # whose joblib results arrive in batches, 4835.7 runs/s for about 230).
            ran = task.completed - int(task.fields.get("kept", 0))
            speed: float | None = ran / task.finished_time
        else:
            speed = task.speed
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
    """``None`` or ``<= 0``: every core (``-1`` is all, ``-2`` all but one, as joblib counts);
    a positive count at most :data:`~gaitpref.limits.MAX_JOBS` (each a local process)."""
    cores = os.cpu_count() or 1
    if jobs is None:
        return cores
    if jobs == 0:
        raise ValueError("jobs must be a positive count or negative (all cores but |jobs| - 1)")
    if jobs > MAX_JOBS:  # joblib starts every worker asked for (capped by the runs only)
        raise ValueError(f"jobs must be at most {MAX_JOBS} (local worker processes), got {jobs}")
    return jobs if jobs > 0 else max(1, cores + 1 + jobs)


def run_study(
    study: Study,
    backend: Backend = "joblib",
    jobs: int | None = None,
    address: str | None = None,
    progress: bool = False,
    console: Console | None = None,
    partial: str | Path | None = None,
    resume: bool = False,
) -> StudyResult:
    """Run every run of ``study`` and collect the tidy table and curves.

    A run that fails stops the study with :class:`~gaitpref.simulate.partial.StudyRunError`
    (the run named, the finished runs kept on it); ``partial``: a new ``.csv`` file each
    finished run is appended to as it finishes, its first line naming the study
    (:mod:`gaitpref.simulate.resume`), removed once every run has finished (one that exists is
    refused, ``FileExistsError``: it may hold the finished runs of a study that stopped).

    ``resume``: ``partial`` is such a file, left by this study when it stopped: its finished
    runs are kept (:func:`~gaitpref.simulate.resume.read_partial`; a file of another sweep is
    refused with :class:`~gaitpref.simulate.resume.ResumeError`), only the others run, and are
    appended to it; the result is the one an uninterrupted study gives.
    """
    check_backend(backend, address)
    tasks = study.tasks()
    rated = _rated(study)
    sink: TableAppender | None = None
    kept: dict[int, RunResult] = {}
    if resume:
        if partial is None:
            raise ValueError("resume: give the partial file the study stopped with")
        kept = _resumed(study, tasks, Path(partial))
        sink = TableAppender(partial, rated, existing=len(kept))
    elif partial is not None:  # made before any run: a path that cannot be written fails at once
        sink = TableAppender(partial, rated, comment=signature(study))
    todo = [i for i in range(len(tasks)) if i not in kept]
    n_jobs = min(resolve_jobs(jobs), max(1, len(todo)))
    start = time.perf_counter()
    with partial_file(sink):
        with _progress(console) if progress else _NoProgress() as bar:
            tid = bar.add_task(study.name, total=len(tasks), completed=len(kept), kept=len(kept))

            def done(index: int, result: RunResult) -> None:
                if sink is not None:
                    sink.append(run_table([result], rated))
                bar.advance(tid)

            ran, failure = run_tasks(
                run_one, [tasks[i] for i in todo], n_jobs, backend, address, done
            )
        results: list[RunResult | None] = [kept.get(i) for i in range(len(tasks))]
        for i, result in zip(todo, ran, strict=True):
            results[i] = result
        if failure is not None:
            failure = RunFailure(
                tuple(todo[i] for i in failure.indices), failure.error, failure.died
            )
            raise study_error(failure, tasks, results, rated, None if sink is None else sink.path)
    seconds = time.perf_counter() - start
    done_runs = [r for r in results if r is not None]
    if len(done_runs) != len(tasks):
        raise RuntimeError(f"{len(tasks) - len(done_runs)} of {len(tasks)} runs returned no result")
    table = run_table(done_runs, rated)
    return StudyResult(study, table, summarize(table), backend, n_jobs, seconds, len(kept))


def _resumed(study: Study, tasks: Sequence[RunTask], partial: Path) -> dict[int, RunResult]:
    """The finished runs in ``partial`` (a ``FileNotFoundError`` naming it when there is none),
    the file written again with its signature and only those runs when lines were dropped."""
    if not partial.is_file():
        raise FileNotFoundError(
            f"{partial}: no such file, no finished runs to resume from; run the study without "
            "resuming"
        )
    kept = read_partial(partial, study, tasks)
    if kept.rewrite:
        runs = list(kept.runs.values())
        write_partial(partial, study, run_table(runs, _rated(study)) if runs else None)
    return kept.runs


def _rated(study: Study) -> bool:
    return any(s.rating_quantiles for s in study.settings)


def check_backend(backend: str, address: str | None) -> None:
    """Refuse a backend that is not one of :data:`BACKENDS`, an address without Ray, or the
    Ray backend where Ray is not installed (``RuntimeError``; found only when the runs started,
    the benches had made their output folder, or built a gait library, before)."""
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {', '.join(BACKENDS)}; got {backend!r}")
    if address is not None and backend != "ray":
        raise ValueError("address is for the Ray backend (--backend ray)")
    if backend == "ray":
        _import_ray()


def run_tasks(
    fn: Callable[[T], R],
    tasks: Sequence[T],
    jobs: int | None = 1,
    backend: Backend = "joblib",
    address: str | None = None,
    done: Callable[[int, R], None] | None = None,
) -> tuple[list[R | None], RunFailure | None]:
    """``fn`` of every task, in the tasks' order, on ``backend`` with ``jobs`` workers (as
    :func:`resolve_jobs` counts; never more than the tasks); ``done(index, result)`` is called
    here as each run finishes.  The first run that fails (raises, or its worker dies) stops the
    sweep: no more runs start (on joblib those in progress finish first; on Ray they are
    cancelled) and its :class:`~gaitpref.simulate.partial.RunFailure` is returned beside the
    results (None for each run that did not finish); without a failure it is None.  With more
    than one job (or Ray), ``fn`` and the tasks must pickle."""
    check_backend(backend, address)
    results: list[R | None] = [None] * len(tasks)
    if not tasks:
        return results, None
    # no more workers than runs: each loky worker is a process that loads NumPy and SciPy, and
    # a mistyped --jobs 1000 started a thousand of them for a handful of runs
    n_jobs = min(resolve_jobs(jobs), len(tasks))
    runner = _run_ray if backend == "ray" else _run_joblib
    for index, outcome in runner(fn, tasks, n_jobs, address):
        if isinstance(outcome, RunFailure):
            return results, outcome
        results[index] = outcome
        if done is not None:
            done(index, outcome)
    return results, None


def _attempt(fn: Callable[[T], R], index: int, task: T) -> R | RunFailure:
    """``fn(task)``, or the failure that names it."""
    try:
        return fn(task)
    except Exception as exc:
        return RunFailure((index,), sendable(exc))


def _indexed(item: tuple[Callable[[T], R], int, T, str]) -> tuple[int, R | RunFailure]:
    """A worker's run: marked as running (a file named by its index in ``item[3]``) until it
    returns, so that a worker that dies leaves the name of the run it was running."""
    fn, index, task, running = item
    marker = Path(running) / str(index)
    with contextlib.suppress(OSError):  # the sweep stopped and took the folder away
        marker.touch()
    try:
        return index, _attempt(fn, index, task)
    finally:
        marker.unlink(missing_ok=True)


def _run_joblib(
    fn: Callable[[T], R], tasks: Sequence[T], jobs: int, address: str | None
) -> Iterator[tuple[int, R | RunFailure]]:
    """Each run's index and result as it finishes; a failure last: after a run's error no more
    runs start and those in progress finish first (their results are kept)."""
    if jobs == 1:
        for i, task in enumerate(tasks):
            outcome = _attempt(fn, i, task)
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
                yield delayed(_indexed)((fn, i, t, running))

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
        probe_address(address)
    os.environ.setdefault("RAY_DEDUP_LOGS", "0")
    try:
        ray.init(address=address, **options)
    except (ConnectionError, TimeoutError, ValueError) as exc:
        where = f"the Ray cluster at {address!r}" if address else "a local Ray runtime"
        raise RuntimeError(f"could not start or reach {where}: {exc}") from None
    return True


def probe_address(address: str, timeout: float = 5.0) -> None:
    """Refuse (``RuntimeError``) a ``HOST:PORT`` address where nothing listens (Ray retried it
    for minutes, its warnings the only output); ``auto`` and ``ray://`` addresses Ray itself
    answers at once.  The benches call it before they make their output folder."""
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
    fn: Callable[[T], R], tasks: Sequence[T], jobs: int, address: str | None
) -> Iterator[tuple[int, R | RunFailure]]:
    ray = _import_ray()
    started = start_ray(address, jobs)
    pending: list[Any] = []
    try:
        remote: Callable[..., Any] = ray.remote(num_cpus=1, max_retries=0)(fn).remote
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
) -> Iterator[tuple[int, Any]]:
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

    def add_task(self, description: str, total: int, completed: int = 0, kept: int = 0) -> TaskID:
        return TaskID(0)

    def advance(self, task: TaskID) -> None:
        return None
