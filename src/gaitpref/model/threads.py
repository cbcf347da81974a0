"""BLAS threading for the small dense problems of one CoSpar iteration.

An iteration on a paper-sized grid is dominated by ``m x m`` factorisations and ``A x m`` products
with ``m`` a few hundred: multi-threaded BLAS spends longer waking its threads than computing, and
on a loaded 2-core machine it can be several times slower than one thread (measured: 0.12 s vs
0.31-0.84 s per 150-trial run on the 30 x 30 grid).

On large grids the same holds: the Laplace fit is ``m x m`` work whatever the grid's size, and an
ask on the scalable path is mostly memory-bound (normal draws, axis-wise prior transforms, the
argmax) around ``2 A m`` flops of matrix products.  At 1,048,576 actions and 300 comparisons on a
loaded 2-core machine an ask + tell took 0.15 s (p95 0.18 s) with one thread and 0.34 s (p95
1.3 s) with two (``benchmarks/results/large.md``), so the loop uses :func:`one_blas_thread` at
every size.
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from functools import cache

from threadpoolctl import ThreadpoolController


@cache
def _controller() -> ThreadpoolController:
    return ThreadpoolController()


def one_blas_thread() -> AbstractContextManager[object]:
    """One BLAS thread inside the block, whatever the grid's size; restored after."""
    limit: AbstractContextManager[object] = _controller().limit(limits=1, user_api="blas")
    return limit
