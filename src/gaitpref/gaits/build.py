"""Build a gait library over a grid, warm-starting along chains, chains in parallel (joblib).

A chain is one row of the grid along step length (one per step duration, or the whole length
axis cut into ``n_jobs`` pieces at a fixed speed); each gait starts from its predecessor's
coefficient shape (:func:`optimize_gait` falls back to its default start when that fails).  A
``step_width`` axis is a label: each width reuses the gait of its (length, duration).

Notation: ``n_L``, ``n_T``, ``n_W`` values per axis; ``n_L n_T`` gaits are optimized.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from joblib import Parallel, delayed

from gaitpref.gaits.gait import Gait, GaitRequest, HZDSettings
from gaitpref.gaits.library import GaitLibrary, check_axes
from gaitpref.gaits.optimize import optimize_gait
from gaitpref.gaits.params import CompassGaitParams
from gaitpref.gaits.zero_dynamics import guard_angle

Progress = Callable[[int], None]
_Chain = list[tuple[int, GaitRequest]]


def _run_chain(
    chain: _Chain,
    params: CompassGaitParams,
    settings: HZDSettings,
    progress: Progress | None = None,
) -> list[tuple[int, Gait]]:
    out: list[tuple[int, Gait]] = []
    previous: Gait | None = None
    for key, request in chain:
        gait = optimize_gait(request, params, settings, warm_start=previous)
        out.append((key, gait))
        previous = gait if gait.feasible else previous
        if progress is not None:
            progress(1)
    return out


def _chains(
    lengths: Sequence[float], durations: Sequence[float] | None, speed: float | None, n_jobs: int
) -> list[_Chain]:
    if durations is not None:
        n_t = len(durations)
        return [
            [
                (i * n_t + j, GaitRequest(lengths[i], step_duration=durations[j]))
                for i in range(len(lengths))
            ]
            for j in range(n_t)
        ]
    requests = [(i, GaitRequest(length, speed=speed)) for i, length in enumerate(lengths)]
    pieces = np.array_split(np.arange(len(requests)), max(1, min(n_jobs, len(requests))))
    return [[requests[k] for k in piece] for piece in pieces if piece.size]


def check_grid(
    step_lengths: Sequence[float],
    step_durations: Sequence[float] | None,
    speed: float | None,
    step_widths: Sequence[float] | None = None,
    params: CompassGaitParams | None = None,
) -> tuple[tuple[str, tuple[float, ...]], ...]:
    """What :func:`build_library` checks before it optimizes anything: the axes (positive,
    increasing, distinct ids; :class:`GaitLibraryError`) and step lengths the legs reach,
    ``0 < L < 2 l`` (a ``ValueError``).  Returns the library's axes."""
    axes: list[tuple[str, tuple[float, ...]]] = [("step_length", tuple(step_lengths))]
    if step_durations is not None:
        axes.append(("step_duration", tuple(step_durations)))
    if step_widths is not None:
        axes.append(("step_width", tuple(step_widths)))
    check_axes(tuple(axes), speed)
    p = params or CompassGaitParams()
    for length in step_lengths:
        guard_angle(p, length)  # a step the legs reach: 0 < L < 2 l
    return tuple(axes)


def build_library(
    step_lengths: Sequence[float],
    *,
    step_durations: Sequence[float] | None = None,
    speed: float | None = None,
    step_widths: Sequence[float] | None = None,
    params: CompassGaitParams | None = None,
    settings: HZDSettings | None = None,
    n_jobs: int = 1,
    progress: Progress | None = None,
) -> GaitLibrary:
    """Optimize one gait per grid point; infeasible points stay in the library, flagged.

    ``progress(k)`` is called with the number of gaits just finished (for a progress bar).
    ``n_jobs`` worker processes at most, and no more than the chains (one per step duration;
    at a fixed speed, at most one per step length): each chain is one worker's piece of work.
    """
    p = params or CompassGaitParams()
    s = settings or HZDSettings()
    if (step_durations is None) == (speed is None):
        raise ValueError("give exactly one of step_durations and speed")
    if n_jobs < 1:
        raise ValueError(f"n_jobs must be >= 1, got {n_jobs}")
    lengths = [float(v) for v in step_lengths]
    durations = None if step_durations is None else [float(v) for v in step_durations]
    widths = None if step_widths is None else [float(w) for w in step_widths]
    axes = check_grid(lengths, durations, speed, widths, p)  # fail before any optimization
    chains = _chains(lengths, durations, speed, n_jobs)
    workers = min(n_jobs, len(chains))  # joblib starts every worker asked for, idle or not
    base: dict[int, Gait] = {}
    if workers <= 1:
        for chain in chains:
            base.update(_run_chain(chain, p, s, progress))
    else:
        runner = Parallel(n_jobs=workers, return_as="generator_unordered")
        for done in runner(delayed(_run_chain)(chain, p, s) for chain in chains):
            base.update(done)
            if progress is not None:
                progress(len(done))
    n_base = len(base)
    repeat = len(widths) if widths is not None else 1
    gaits = tuple(base[k // repeat] for k in range(n_base * repeat))
    return GaitLibrary(p, s, axes, gaits, speed)
