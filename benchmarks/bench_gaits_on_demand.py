"""Gaits on demand (issue 13, item 4): a gait made when first proposed, target under 1 s.

1. *one gait on demand*: 40 points of the 15 x 10 step length x step duration grid (the
   library benchmark's, ``bench_gaits.py``) in a seeded random order, as a session would first
   propose them; each made by ``OnDemandGaits`` (warm-started from the nearest feasible gait
   made so far) and, for comparison, from the default start alone; then looked up in the cache;
2. *an infeasible proposal*: step lengths with no gait at 0.2 m/s, one near the feasible ones
   (0.02 m) and two far from them (0.40 and 0.50 m), each warm-started from the 0.12 m gait as in
   a session, under the iteration budget of the current defaults (``[gaits] max_iterations``)
   and without one (the rule of sessions recorded before it): wall and CPU seconds, mean and
   standard error over ``--repeats`` runs, and the SLSQP iterations taken;
3. *a session*: ``next_query()`` + ``answer()`` on that grid with ``[gaits] generator =
   "compass-hzd"`` and SQLite, a simulated subject, 30 trials: the iterations that made a gait
   against those that did not; then ``Session.open`` with the gait cache and without it.

    python benchmarks/bench_gaits_on_demand.py [--points 40] [--trials 30] [--repeats 3]

Writes benchmarks/results/gaits_on_demand.md and gaits_on_demand.json.
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from gaitpref import Session
from gaitpref.config import DEFAULTS, parse_config
from gaitpref.gaits import GaitCache, GaitRequest, OnDemandGaits, make_generator, optimize_gait
from gaitpref.gaits import optimize as optimize_module
from gaitpref.sessions.demo import SimulatedSubject, bump_utility

try:
    from _machine import machine_description, machine_markdown
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown

RESULTS = Path(__file__).parent / "results"
LENGTHS = np.linspace(0.08, 0.18, 15)
DURATIONS = np.linspace(0.85, 1.15, 10)
INFEASIBLE = (0.02, 0.40, 0.50)  # step lengths (m) with no gait at 0.2 m/s
BUDGET: int = DEFAULTS["gaits"]["max_iterations"]
CONFIG = """
name = "on-demand-2d"
[space.step_length]
min = 0.08
max = 0.18
num = 15
unit = "m"
[space.step_duration]
min = 0.85
max = 1.15
num = 10
unit = "s"
[gaits]
generator = "compass-hzd"
[model]
lengthscale = { step_length = 0.025, step_duration = 0.08 }
signal_variance = 0.005
noise = 0.02
[cospar]
seed = 1
"""


def _stats(times: list[float]) -> dict[str, float]:
    arr = np.asarray(times)
    return {
        "median_s": float(np.median(arr)),
        "p90_s": float(np.quantile(arr, 0.9)),
        "max_s": float(arr.max()),
        "n": int(arr.size),
    }


def one_gait(points: int, folder: Path) -> dict[str, object]:
    grid = np.array([(length, d) for length in LENGTHS for d in DURATIONS])
    order = np.random.default_rng(0).permutation(len(grid))[:points]
    generator = make_generator(
        "compass-hzd", ["step_length", "step_duration"], {"max_iterations": BUDGET}
    )
    gaits = OnDemandGaits(generator, GaitCache(folder), [0.1, 0.3])
    warm, cold, hits, feasible = [], [], [], 0
    for k in order:
        t0 = time.perf_counter()
        made, _ = gaits.get(grid[k])
        warm.append(time.perf_counter() - t0)
        feasible += made.feasible
        t0 = time.perf_counter()
        optimize_gait(GaitRequest(grid[k][0], step_duration=grid[k][1]))
        cold.append(time.perf_counter() - t0)
    again = OnDemandGaits(generator, GaitCache(folder), [0.1, 0.3])
    for k in order:
        t0 = time.perf_counter()
        found, _ = again.get(grid[k])
        hits.append(time.perf_counter() - t0)
        assert found.from_cache
    return {
        "on_demand": _stats(warm),
        "default_start": _stats(cold),
        "cache_hit": _stats(hits),
        "feasible": feasible,
        "points": points,
    }


def _mean_se(values: list[float]) -> dict[str, float]:
    arr = np.asarray(values)
    se = float(arr.std(ddof=1) / np.sqrt(arr.size)) if arr.size > 1 else float("nan")
    return {"mean": float(arr.mean()), "se": se}


def infeasible(repeats: int) -> dict[str, object]:
    """What an infeasible proposal costs, with the budget and without it."""
    iterations: list[int] = []
    real = optimize_module.minimize

    def counting(*args: object, **kwargs: object) -> object:
        res = real(*args, **kwargs)  # type: ignore[arg-type]
        iterations.append(int(res.nit))
        return res

    optimize_module.minimize = counting  # type: ignore[assignment]
    out: dict[str, object] = {}
    try:
        for budget in (BUDGET, None):
            settings = (
                {"speed": 0.2} if budget is None else {"speed": 0.2, "max_iterations": budget}
            )
            generator = make_generator("compass-hzd", ["step_length"], settings)
            for length in INFEASIBLE:
                wall, cpu = [], []
                for _ in range(repeats):
                    fixed = OnDemandGaits(generator, GaitCache(), [0.1])
                    fixed.get(np.array([0.12]))  # the warm start a session would have
                    iterations.clear()
                    t0, c0 = time.perf_counter(), time.process_time()
                    made, _ = fixed.get(np.array([length]))
                    wall.append(time.perf_counter() - t0)
                    cpu.append(time.process_time() - c0)
                out[f"{length:.2f} m, {'budget ' + str(budget) if budget else 'no budget'}"] = {
                    "wall_s": _mean_se(wall),
                    "cpu_s": _mean_se(cpu),
                    "iterations": list(iterations),
                    "feasible": made.feasible,
                    "reason": made.gait.message[:150],
                }
    finally:
        optimize_module.minimize = real  # type: ignore[assignment]
    return out


def session(trials: int, folder: Path) -> dict[str, object]:
    cfg = parse_config(CONFIG)
    subject = SimulatedSubject(cfg.space, bump_utility(cfg.space), seed=0)
    url = f"sqlite:///{folder / 'lab.db'}"
    s = Session.create(url, cfg, "BENCH", seed=1)
    making, reusing = [], []
    while len(s.trials()) < trials:
        before = len(s.events())
        t0 = time.perf_counter()
        q = s.next_query()
        comparisons, suggestions = subject.respond(q)
        s.answer(q.id, comparisons, suggestions)
        dt = time.perf_counter() - t0
        made = any(e.kind == "gait_made" for e in s.events()[before:])
        (making if made else reusing).append(dt)
    t0 = time.perf_counter()
    Session.open(url, s.id).close()
    with_cache = time.perf_counter() - t0
    shutil.rmtree(folder / "lab.db.gaits")
    t0 = time.perf_counter()
    Session.open(url, s.id).close()
    without = time.perf_counter() - t0
    s.close()
    return {
        "trials": trials,
        "gaits_made": len(making),
        "iteration_making_a_gait": _stats(making),
        "iteration_reusing": _stats(reusing) if reusing else None,
        "resume_with_cache_s": with_cache,
        "resume_without_cache_s": without,
    }


def _row(name: str, st: dict[str, float]) -> str:
    return f"| {name} | {st['n']} | {st['median_s']:.3f} | {st['p90_s']:.3f} | {st['max_s']:.3f} |"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=40)
    parser.add_argument("--trials", type=int, default=30)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    info = machine_description()
    with tempfile.TemporaryDirectory() as tmp:
        gait = one_gait(args.points, Path(tmp) / "gaits")
        bad = infeasible(args.repeats)
        sess = session(args.trials, Path(tmp))
    on = gait["on_demand"]
    assert isinstance(on, dict)
    lines = [
        "# Gaits on demand",
        "",
        machine_markdown(info),
        "",
        f"## One gait made on demand ({gait['points']} points of the 15 x 10 grid, seeded order)",
        "",
        f"- target: a gait made on demand in under 1 s; worst here **{on['max_s']:.3f} s** "
        f"(median {on['median_s']:.3f} s): **{'met' if on['max_s'] < 1.0 else 'not met'}**",
        f"- feasible: {gait['feasible']} / {gait['points']}",
        "",
        "| how | gaits | median [s] | p90 [s] | max [s] |",
        "|---|---|---|---|---|",
        _row("on demand (warm start from the nearest made)", on),  # type: ignore[arg-type]
        _row("default start only", gait["default_start"]),  # type: ignore[arg-type]
        _row("cache hit (another session)", gait["cache_hit"]),  # type: ignore[arg-type]
        "",
        f"## An infeasible proposal at 0.2 m/s ({args.repeats} runs each, mean +- se)",
        "",
        f"Warm-started from the 0.12 m gait; `[gaits] max_iterations = {BUDGET}` (the default) "
        "against no budget (sessions recorded before it: each start may take 300 iterations).",
        "",
        "| step length, rule | wall [s] | CPU [s] | SLSQP iterations per start | verdict |",
        "|---|---|---|---|---|",
        *[
            f"| {name} | {v['wall_s']['mean']:.2f} +- {v['wall_s']['se']:.2f} "
            f"| {v['cpu_s']['mean']:.2f} +- {v['cpu_s']['se']:.2f} | {v['iterations']} "
            f"| {'feasible' if v['feasible'] else 'infeasible'} |"
            for name, v in bad.items()  # type: ignore[union-attr]
        ],
        "",
        "Reasons:",
        "",
        *[f"- {name}: {v['reason']}..." for name, v in bad.items()],  # type: ignore[index]
        "",
        f'## A session on the grid with `generator = "compass-hzd"` ({sess["trials"]} trials, '
        "SQLite)",
        "",
        "| iteration (next_query + answer) | count | median [s] | p90 [s] | max [s] |",
        "|---|---|---|---|---|",
        _row("that made a gait", sess["iteration_making_a_gait"]),  # type: ignore[arg-type]
    ]
    if sess["iteration_reusing"] is not None:
        lines.append(_row("that reused a made gait", sess["iteration_reusing"]))  # type: ignore[arg-type]
    lines += [
        "",
        f"- resume (`Session.open`, replaying {sess['trials']} trials): "
        f"{sess['resume_with_cache_s']:.2f} s with the gait cache, "
        f"{sess['resume_without_cache_s']:.2f} s without it (the gaits from the log; "
        "`bench_gaits_log.py` compares a log without them)",
        "",
    ]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "gaits_on_demand.md").write_text("\n".join(lines))
    (RESULTS / "gaits_on_demand.json").write_text(
        json.dumps(
            {"machine": info, "one_gait": gait, "infeasible": bad, "session": sess}, indent=1
        )
        + "\n"
    )
    print("\n".join(lines))


if __name__ == "__main__":
    main()
