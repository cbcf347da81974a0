"""BLAS threading for the small dense problems of one CoSpar iteration.

An iteration on a paper-sized grid is dominated by ``m x m`` factorisations and ``A x m`` products
with ``m`` a few hundred, where multi-threaded BLAS has little to gain.  Measured on a 2-core
machine at load 2.2 (``benchmarks/bench_threads.py``, ``benchmarks/results/threads.md``),
150-trial runs on the 30 x 30 grid took 0.20-0.36 s with one thread and 0.19-0.27 s with
BLAS's default of two: no difference at that load.  (An earlier measurement under heavier load,
not recorded, gave 0.12 s against 0.31-0.84 s.)

On large grids one thread wins: the Laplace fit is ``m x m`` work whatever the grid's size, and
an ask on the scalable path is mostly memory-bound (normal draws, axis-wise prior transforms,
the argmax) around ``2 A m`` flops of matrix products.  At 1,048,576 actions and 300 comparisons
an ask + tell took a median 0.059 s with one thread against 0.155 s with two (p95 0.065 s
against 1.2 s) at load 2.2, and 0.06-0.13 s against 0.19-0.78 s at load 5 (the same script's
first run, commit 717ee57).  So the loop uses :func:`one_blas_thread` at every size, and so
does the confidence (``loop/stopping.py``): 2000 draws over the 90 gaits of the paper's 2-D
grid took 0.4-0.8 s with BLAS's default threads at load 4 on 2 cores and 9 ms with one, after
every answer and for every row of an export (``benchmarks/results/long.md``).  The session
figure (``plots/session.py``) and the export's posterior and summary (``sessions/export.py``)
too: the same bytes (grid and line-path sessions), and an export of 100 trials of
``exo-2d-rated`` in 1.9 s against 6.2 s with the default threads at load 1.3 (its figure 0.31 s
against 0.39 s; no difference for ``synthetic-2d`` or the line path,
``benchmarks/results/blas_outputs.md``).

Independent fits of one step (a warm start's share hypotheses, ``share_mix.py``) may instead run
side by side in threads (:func:`in_threads`), each on one BLAS thread: NumPy and LAPACK release
the interpreter lock, so on a clinic's data two cores weigh five hypotheses in about half the
time, and every fit computes exactly what it computes alone.
"""

from __future__ import annotations

import contextvars
import os
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from functools import cache
from typing import Any, TypeVar

from threadpoolctl import ThreadpoolController


@cache
def _controller() -> ThreadpoolController:
    return ThreadpoolController()


#: the blocks inside :func:`one_blas_thread` now, in every thread, and the limit they share
_BLAS_LOCK = threading.Lock()
_blas_held = 0
_blas_limit: Any = None


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """One BLAS thread inside the block, whatever the grid's size; restored after.

    The limit is the process's: it is set when the first block (of any thread) begins and
    restored when the last one ends, so that a thread leaving its block does not give BLAS its
    threads back under another still inside (the console computes sessions side by side)."""
    global _blas_held, _blas_limit
    with _BLAS_LOCK:
        if _blas_held == 0:
            _blas_limit = _controller().limit(limits=1, user_api="blas")
        _blas_held += 1
    try:
        yield
    finally:
        with _BLAS_LOCK:
            _blas_held -= 1
            if _blas_held == 0:
                limit, _blas_limit = _blas_limit, None
                limit.restore_original_limits()


_T = TypeVar("_T")


def available_cpus() -> int:
    """The CPUs this process may run on (its affinity where the platform says, else all)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on every platform
        return max(1, os.cpu_count() or 1)


def in_threads(tasks: Sequence[Callable[[], _T]], *, parallel: bool = True) -> list[_T]:
    """Each task's result, in order: in threads (at most one per available CPU) when
    ``parallel`` and there are two or more of both, else one after the other.

    Each task runs in a copy of the caller's context (NumPy's error state rides in it).  The
    first task to raise makes the call raise it, after every task has finished.  The caller
    sets the BLAS threads (:func:`one_blas_thread`): the limit is the process's, so it holds in
    the workers too.
    """
    workers = min(len(tasks), available_cpus()) if parallel else 1
    if workers < 2:
        return [task() for task in tasks]
    contexts = [contextvars.copy_context() for _ in tasks]
    with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="gaitpref-fit") as pool:
        futures = [pool.submit(ctx.run, task) for ctx, task in zip(contexts, tasks, strict=True)]
        return [f.result() for f in futures]
