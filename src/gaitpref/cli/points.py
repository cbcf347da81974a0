"""``gaitpref simulate`` and ``gaitpref bench continuous`` against objectives over points.

Issue 13, item 5: ``--objective PATH.py:NAME`` (a function of an ``m x d`` array of points in
the features' units returning ``m`` utilities), ``hartmann6`` or ``random-gp[:SEED]``
(``gaitpref.simulate.continuous``).  The run reports, per query, the executed points' feature
values (``"points"``, one list of points per query) and the objective there (``"objective"``),
and the final posterior's best point and its objective (``simulate/points.py``).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from gaitpref.cli.output import console, guard

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


def run_command(cfg: ExperimentConfig, spec: str, trials: int, seed: int, coactive: bool,
                noise: float, as_json: bool) -> None:  # fmt: skip
    """``gaitpref simulate`` with a point objective."""
    from gaitpref.cli.main import progress_bar

    objective = load_point_objective(spec, cfg)
    start = time.perf_counter()
    with progress_bar(transient=True, shown=not as_json) as bar:  # trials: it said nothing
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


__all__ = ["is_grid_objective", "load_point_objective", "report", "run_command", "simulate_points"]
