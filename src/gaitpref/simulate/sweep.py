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
"""

from __future__ import annotations

import logging
import os
import socket
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
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

from gaitpref.simulate.study import RunResult, RunTask, Study, run_one
from gaitpref.simulate.tables import Curves, RunTable, summarize

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
) -> StudyResult:
    """Run every run of ``study`` and collect the tidy table and curves."""
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {', '.join(BACKENDS)}; got {backend!r}")
    if address is not None and backend != "ray":
        raise ValueError("address is for the Ray backend (--backend ray)")
    tasks = study.tasks()
    # no more workers than runs: each loky worker is a process that loads NumPy and SciPy, and
    # a mistyped --jobs 1000 started a thousand of them for a handful of runs
    n_jobs = min(resolve_jobs(jobs), len(tasks))
    results: list[RunResult | None] = [None] * len(tasks)
    start = time.perf_counter()
    with _progress(console) if progress else _NoProgress() as bar:
        tid = bar.add_task(study.name, total=len(tasks))
        runner = _run_ray if backend == "ray" else _run_joblib
        for index, result in runner(tasks, n_jobs, address):
            results[index] = result
            bar.advance(tid)
    seconds = time.perf_counter() - start
    table = _table([r for r in results if r is not None], len(tasks))
    return StudyResult(study, table, summarize(table), backend, n_jobs, seconds)


def _table(results: list[RunResult], expected: int) -> RunTable:
    if len(results) != expected:
        raise RuntimeError(f"{expected - len(results)} of {expected} runs returned no result")
    T = results[0].actions.size
    rated = any(r.ratings is not None for r in results)
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


def _indexed(item: tuple[int, RunTask]) -> tuple[int, RunResult]:
    return item[0], run_one(item[1])


def _run_joblib(
    tasks: list[RunTask], jobs: int, address: str | None
) -> Iterator[tuple[int, RunResult]]:
    if jobs == 1:
        for i, task in enumerate(tasks):
            yield i, run_one(task)
        return
    from joblib import Parallel, delayed

    parallel = Parallel(
        n_jobs=jobs, backend="loky", inner_max_num_threads=1, return_as="generator_unordered"
    )
    yield from parallel(delayed(_indexed)((i, t)) for i, t in enumerate(tasks))


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
) -> Iterator[tuple[int, RunResult]]:
    ray = _import_ray()
    started = start_ray(address, jobs)
    try:
        remote: Callable[..., Any] = ray.remote(num_cpus=1, max_retries=0)(run_one).remote
        refs = [remote(t) for t in tasks]
        position = {ref: i for i, ref in enumerate(refs)}
        pending = list(refs)
        while pending:
            done, pending = ray.wait(pending, num_returns=1, timeout=None)
            for ref in done:
                try:
                    result = ray.get(ref)
                except ray.exceptions.RayTaskError as exc:  # the run's own error, as joblib
                    cause = getattr(exc, "cause", None)  # raises it (not the remote traceback)
                    if isinstance(cause, Exception):
                        raise cause from None
                    raise
                yield position[ref], result
    finally:
        if started:
            ray.shutdown()


class _NoProgress:
    def __enter__(self) -> _NoProgress:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def add_task(self, description: str, total: int) -> TaskID:
        return TaskID(0)

    def advance(self, task: TaskID) -> None:
        return None
