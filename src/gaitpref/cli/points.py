"""``gaitpref simulate`` and ``gaitpref bench continuous`` against objectives over points.

Issue 13, item 5: ``--objective PATH.py:NAME`` (a function of an ``m x d`` array of points in
the features' units returning ``m`` utilities), ``hartmann6`` or ``random-gp[:SEED]``
(``gaitpref.simulate.continuous``).  The run reports, per query, the executed points' feature
values (``"points"``, one list of points per query) and the objective there (``"objective"``),
and the final posterior's best point and its objective (``simulate/points.py``).
``bench continuous`` runs its seeds through :func:`~gaitpref.simulate.sweep.run_tasks`, as a
study runs its runs: a run that fails stops the rest and keeps the finished ones.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from gaitpref.cli.output import console, guard, json_only

if TYPE_CHECKING:
    from gaitpref.config import ExperimentConfig
    from gaitpref.simulate.continuous import PointObjective
    from gaitpref.simulate.points import PointsResult


def is_grid_objective(spec: str) -> bool:
    """Whether ``--objective`` names a ``.npy`` array over the grid (the 0.1 form)."""
    return spec.endswith(".npy")


def load_point_objective(spec: str, cfg: ExperimentConfig) -> PointObjective:
    from gaitpref.simulate.continuous import objective_from

    return guard(lambda: objective_from(spec, cfg.space, cfg.seed))


def simulate_points(
    cfg: ExperimentConfig,
    objective: PointObjective,
    *,
    trials: int,
    seed: int,
    coactive: bool = False,
    noise: float = 0.0,
    progress: Callable[[int], None] | None = None,
) -> PointsResult:
    """One simulated run on ``cfg``'s loop (grid or line path), seeded by ``seed``;
    ``progress`` is called with the trials done after every query."""
    import numpy as np

    from gaitpref.simulate.points import PointCoactive, PointUser, run_points

    loop_seed, user_seed = np.random.SeedSequence(seed).spawn(2)
    loop = cfg.make_loop(seed=np.random.default_rng(loop_seed))
    user = PointUser(objective, np.random.default_rng(user_seed), noise)
    helper = PointCoactive(objective, cfg.space, seed=seed) if coactive else None
    return run_points(loop, objective, user, trials, helper, progress=progress)


def run_record(seed: int, result: PointsResult) -> dict[str, object]:
    """One run of ``bench continuous`` as its JSON's ``runs`` and the partial file hold it."""
    return {"seed": seed, **result.to_json()}


def check_bench_points(
    cfg: ExperimentConfig, spec: str, runs: int, *, trials: int, noise: float = 0.0
) -> tuple[list[str], PointObjective]:
    """What :func:`bench_points` refuses before any run, checked on its own (so that the
    command line refuses before it shows a progress bar): the runs (at most
    :data:`~gaitpref.simulate.study.MAX_RUNS`, as a study's), the trials (at most
    :data:`~gaitpref.limits.MAX_TRIALS`, and runs x trials at most
    :data:`~gaitpref.limits.MAX_STUDY_TRIALS`), the noise and the first run's objective, each a
    ValueError.  Returns every run's objective spec and the first run's objective."""
    from gaitpref.limits import MAX_RUNS, MAX_STUDY_TRIALS, MAX_TRIALS
    from gaitpref.simulate.continuous import objective_from

    if not 1 <= runs <= MAX_RUNS:  # the runs' list is made first: 10**12 was a MemoryError
        raise ValueError(f"--runs must be 1 to {MAX_RUNS}, got {runs}")
    if not 1 <= trials <= MAX_TRIALS:  # every trial runs: 10**12 ran until memory ran out
        raise ValueError(f"--trials must be 1 to {MAX_TRIALS}, got {trials}")
    if runs * trials > MAX_STUDY_TRIALS:  # every run's results are kept, as a study's
        raise ValueError(
            f"--runs {runs} x --trials {trials} is {runs * trials} trials, more than "
            f"{MAX_STUDY_TRIALS}; give fewer runs or trials"
        )
    check_noise(noise, "--noise")  # refused here, not as every run's failure
    specs = [f"random-gp:{k}" if spec == "random-gp" else spec for k in range(runs)]
    return specs, objective_from(specs[0], cfg.space, cfg.seed)


def bench_points(
    cfg: ExperimentConfig,
    spec: str,
    runs: int,
    *,
    trials: int,
    coactive: bool = False,
    noise: float = 0.0,
    progress: Callable[[int], None] | None = None,
    partial: Path | None = None,
    checked: tuple[list[str], PointObjective] | None = None,
    resume: bool = False,
) -> list[PointsResult]:
    """``gaitpref bench continuous``'s runs, seeds ``0 .. runs - 1`` (``random-gp`` alone: run
    ``k`` against ``random-gp:k``); ``progress`` is called with the trials done in all runs.

    Everything :func:`check_bench_points` checks is checked before any run (a ValueError); a run
    that fails stops the rest with :class:`~gaitpref.simulate.partial.RunError` naming it
    (objective and seed), the finished runs on it as their JSON (``{"seed": k, ...}``), and in
    ``partial`` (a new file of JSON lines, written as each run finishes, removed once every
    run has; one that exists is refused, ``FileExistsError``).
    ``checked``: what :func:`check_bench_points` returned for the same arguments (not checked
    again, the first objective not made again).  The file's first line names the bench
    (:func:`continuous_sweep`); ``resume``: ``partial`` is such a file, left by this bench when
    it stopped: its runs are kept, only the others run (:mod:`gaitpref.simulate.resume_lines`),
    and the results are those of a bench that never stopped.
    """
    from gaitpref.simulate.continuous import objective_from
    from gaitpref.simulate.partial import JsonLines, partial_file, run_error
    from gaitpref.simulate.resume_lines import first_line
    from gaitpref.simulate.sweep import run_tasks

    specs, first = (
        check_bench_points(cfg, spec, runs, trials=trials, noise=noise)
        if checked is None
        else checked
    )
    sweep = continuous_sweep(cfg, spec, runs, trials=trials, coactive=coactive, noise=noise)
    kept: dict[int, PointsResult] = {}
    sink: JsonLines | None = None
    if resume:
        if partial is None:
            raise ValueError("resume: give the partial file the bench stopped with")
        kept = _kept_points(partial, sweep, runs, trials)
        sink = JsonLines(partial, existing=len(kept))
        if progress is not None and kept:
            progress(len(kept) * trials)
    elif partial is not None:
        sink = JsonLines(partial, first=first_line(sweep))
    todo = [k for k in range(runs) if k not in kept]

    def one(seed: int) -> PointsResult:
        fn = first if seed == 0 else objective_from(specs[seed], cfg.space, cfg.seed)
        return simulate_points(
            cfg, fn, trials=trials, seed=seed, coactive=coactive, noise=noise,
            progress=None if progress is None else lambda done: progress(seed * trials + done),
        )  # fmt: skip

    with partial_file(sink):

        def done(index: int, result: PointsResult) -> None:
            if sink is not None:
                sink.append(run_record(todo[index], result))

        ran, failure = run_tasks(one, todo, 1, done=done)
        results: list[PointsResult | None] = [kept.get(k) for k in range(runs)]
        for k, result in zip(todo, ran, strict=True):
            results[k] = result
        if failure is not None:
            records = [run_record(k, r) for k, r in enumerate(results) if r is not None]
            names = [f"objective {specs[k]!r}, seed {k}" for k in todo]
            raise run_error(failure, names, records, runs, None if sink is None else sink.path)
    return [r for r in results if r is not None]


def continuous_sweep(
    cfg: ExperimentConfig, spec: str, runs: int, *, trials: int, coactive: bool, noise: float
) -> dict[str, object]:
    """What ``bench continuous``'s runs depend on (its partial file's first line names it):
    the release, the config's name and text (a digest), the objective (and a digest of its
    file), the runs, trials, coactive feedback and noise."""
    import hashlib

    from gaitpref import __version__

    source = Path(spec.rpartition(":")[0])
    text = source.read_bytes() if source.suffix == ".py" and source.is_file() else None
    return {
        "bench": "continuous",
        "gaitpref": __version__,
        "config": cfg.name,
        "config_sha256": cfg.sha256,
        "objective": spec,
        "objective_file_sha256": None if text is None else hashlib.sha256(text).hexdigest(),
        "runs": runs,
        "trials": trials,
        "coactive": coactive,
        "noise": noise,
    }


def _kept_points(
    partial: Path, sweep: dict[str, object], runs: int, trials: int
) -> dict[int, PointsResult]:
    """The finished runs in ``partial`` by seed (the file written again without a line cut
    short); a line that is not a run of this bench is refused naming it."""
    from gaitpref.simulate.points import PointsResult
    from gaitpref.simulate.resume import ResumeError
    from gaitpref.simulate.resume_lines import read_lines, write_lines

    if not partial.is_file():
        raise FileNotFoundError(
            f"{partial}: no such file, no finished runs to resume from; run the bench without "
            "resuming"
        )
    lines, rewrite = read_lines(partial, sweep)
    kept: dict[int, PointsResult] = {}
    for line, record in lines:
        where = f"{partial}:{line}"
        seed = record.get("seed")
        if not isinstance(seed, int) or not 0 <= seed < runs or record.get("trials") != trials:
            raise ResumeError(
                f"{where}: not a run of this bench (seeds 0..{runs - 1}, {trials} trials)"
            )
        if seed in kept:
            raise ResumeError(f"{where}: the run of seed {seed} is in the file twice")
        try:
            result = PointsResult(
                record["points"], record["objective"], record["best_point"],
                record["best_objective"],
            )  # fmt: skip
            same = json.dumps(run_record(seed, result)) == json.dumps(record)
        except (KeyError, TypeError, ValueError):
            same = False
        if not same:
            raise ResumeError(f"{where}: not a run record of bench continuous (seed {seed})")
        kept[seed] = result
    if rewrite:
        write_lines(partial, sweep, [run_record(k, r) for k, r in kept.items()])
    return kept


def report(cfg: ExperimentConfig, result: PointsResult, seed: int, elapsed: float,
           as_json: bool) -> None:  # fmt: skip
    """Print one run: a JSON object, or a table of the learning curve and the best point."""
    if as_json:
        payload: dict[str, Any] = {"config": cfg.name, "seed": seed, "seconds": elapsed}
        print(json.dumps({**payload, **result.to_json()}))
        return
    from rich.table import Table

    curve = result.curve
    table = Table(title=f"{cfg.name}: {curve.size} trials, seed {seed} ({cfg.subspace} path)")
    table.add_column("trials")
    table.add_column("mean objective", justify="right")
    for lo, hi in [(1, 10), (11, 25), (26, 50), (51, 100), (101, curve.size)]:
        if lo <= curve.size:
            table.add_row(f"{lo}-{min(hi, curve.size)}", f"{curve[lo - 1 : hi].mean():.4g}")
    console.print(table)
    values = ", ".join(
        f"{f.name}={v:.4g}" for f, v in zip(cfg.space.features, result.best_point, strict=True)
    )
    console.print(f"posterior best point: {values}; objective {result.best_objective:.4g}")
    console.print(f"simulated {curve.size} trials in {elapsed:.2f} s (wall clock)")


def check_noise(noise: float, option: str) -> None:
    """A simulated subject's probit noise given as ``option``: a finite number >= 0, else a
    ValueError naming the option (it said 'noise must be ...', for --user-noise too)."""
    if not (math.isfinite(noise) and noise >= 0):
        raise ValueError(f"{option} must be a finite number >= 0, got {noise!r}")


def run_command(cfg: ExperimentConfig, spec: str, trials: int, seed: int, coactive: bool,
                noise: float, as_json: bool) -> None:  # fmt: skip
    """``gaitpref simulate`` with a point objective."""
    from gaitpref.cli.main import progress_bar

    guard(lambda: check_noise(noise, "--noise"))
    with json_only(as_json):  # the objective's own prints kept off the JSON
        objective = load_point_objective(spec, cfg)
    start = time.perf_counter()
    with (
        json_only(as_json),
        progress_bar(transient=True, shown=not as_json) as bar,  # trials: it said nothing
    ):
        task = bar.add_task("trials", total=trials)
        result = guard(
            lambda: simulate_points(
                cfg,
                objective,
                trials=trials,
                seed=seed,
                coactive=coactive,
                noise=noise,
                progress=lambda done: bar.update(task, completed=done),
            )
        )
    report(cfg, result, seed, time.perf_counter() - start, as_json)


__all__ = [
    "bench_points",
    "check_bench_points",
    "check_noise",
    "is_grid_objective",
    "load_point_objective",
    "report",
    "run_command",
    "simulate_points",
]
