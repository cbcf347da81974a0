"""Issue 13 study: the line path on continuous spaces (docs/results/continuous/).

Hartmann-6 and random-GP objectives (``gaitpref.simulate.continuous``) in 6, 8 and 12
dimensions, 150 trials, ``n = 1, b = 1``, with and without coactive feedback, noiseless and noisy
subjects; against random selection, and in 6-D against the full 57,750-gait grid (11 x 10 x 7 x
5 x 5 x 3 values over the same box) with the line path run on that same grid (lines snapped to
it) and on the continuous box.  The line path's strategy, fit and lines per query are
``--line-strategy``, ``--line-fit`` and ``--line-count`` (1, LineCoSpar's one line, unless
given; a line config's default since defaults 0.10 is 4) and ``--line-boundary`` (``clip``, as
every recorded run drew its lines, unless given; a line config's default since defaults 0.11 is
``fold``, ``loop/lines.py``); the full grid runs twice, with
self-sparring (``grid``) and with the project's default for grids, gated EUBO
(``grid-gated``).  One process, seeds 0..S-1.

    python benchmarks/study_continuous.py --seeds 6 [--subset] [--paths grid-gated --merge]
    python benchmarks/study_continuous.py --report
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from gaitpref import CoSpar, Feature, Space, SquaredExponential
from gaitpref.loop.learning import Learning
from gaitpref.loop.line import LineCoSpar
from gaitpref.loop.lines import Boundary, LineSettings
from gaitpref.simulate.continuous import (
    HARTMANN6_MAX,
    builtin,
    estimate_optimum,
    random_gp_lengthscale,
)
from gaitpref.simulate.points import PointCoactive, PointUser, random_curve, run_points
from gaitpref.strategies import make_strategy

TRIALS = 150
GRID_SIZES = (11, 10, 7, 5, 5, 3)  # 57,750 gaits
NOISY = 0.2  # the noisy subject's probit noise (utility units; both objectives span ~3-4)
PREF_NOISE = 0.05  # the model's probit noise
PATHS = ("line", "grid", "grid-gated", "line-on-grid")
GRID_STRATEGY = {"grid": "self-sparring", "grid-gated": "gated-eubo"}
#: what made a results.json that names no commands (the study's first runs)
DEFAULT_COMMAND = "python benchmarks/study_continuous.py --seeds 6"


def box(d: int) -> Space:
    return Space([Feature.interval(f"x{k}", 0.0, 1.0) for k in range(d)])


def grid6() -> Space:
    return Space([Feature.linspace(f"x{k}", 0.0, 1.0, n) for k, n in enumerate(GRID_SIZES)])


def kernel(objective: str, d: int) -> SquaredExponential:
    scale = 0.25 if objective == "hartmann6" else random_gp_lengthscale(d)
    return SquaredExponential(scale, 1.0, 1e-6)


def one_run(path: str, objective: str, d: int, coactive: bool, noise: float, seed: int,
            optimum: float | None, line_strategy: str = "self-sparring",
            line_fit: str = "fixed", line_count: int = 1,
            line_points: int = 50, line_cloud: int = 0,
            line_boundary: str = "clip") -> dict[str, Any]:  # fmt: skip
    domain = box(d) if path == "line" else grid6()
    fn = builtin(objective, domain, seed)
    if optimum is None:  # the objective's best over the domain
        optimum = float(fn(domain.points).max()) if path != "line" else \
            estimate_optimum(fn, domain, seed)[1]  # fmt: skip
    loop_seed, user_seed = np.random.SeedSequence(seed).spawn(2)
    settings: dict[str, Any] = dict(n=1, buffer=1, seed=np.random.default_rng(loop_seed))
    k = kernel(objective, d)
    if path in GRID_STRATEGY:
        strategy = make_strategy(GRID_STRATEGY[path])
        loop: CoSpar = CoSpar(domain, k, PREF_NOISE, strategy=strategy, **settings)
    else:
        strategy = make_strategy(line_strategy)
        learning = Learning(fit="evidence" if line_fit == "evidence" else "fixed")
        boundary: Boundary = "fold" if line_boundary == "fold" else "clip"
        line = LineSettings(line_points, "random", line_count, line_cloud, boundary)
        loop = LineCoSpar(domain, k, PREF_NOISE, line=line, strategy=strategy,
                          learning=learning, **settings)  # fmt: skip
    user = PointUser(fn, np.random.default_rng(user_seed), noise)
    helper = PointCoactive(fn, domain, seed=seed) if coactive else None
    start = time.perf_counter()
    res = run_points(loop, fn, user, TRIALS, helper, checkpoints=(60, 150))
    rand = random_curve(fn, domain, 4000, np.random.default_rng(10_000 + seed))
    return {
        "path": path, "objective": objective, "d": d, "coactive": coactive, "noise": noise,
        "seed": seed, "seconds": time.perf_counter() - start, "optimum": optimum,
        "strategy": strategy.name, "fit": loop.learning.fit,
        **({"lines": line_count} if path not in GRID_STRATEGY and line_count != 1 else {}),
        **({"points": line_points} if path not in GRID_STRATEGY and line_points != 50 else {}),
        **({"cloud": line_cloud} if path not in GRID_STRATEGY and line_cloud else {}),
        **({"boundary": line_boundary} if path not in GRID_STRATEGY and line_boundary != "clip"
           else {}),
        "random_mean": float(rand.mean()), "worst": float(fn(domain.points).min())
        if path != "line" else float(rand.min()),
        "curve": res.curve.tolist(), "best_at": {str(k): v for k, v in res.best_at.items()},
    }  # fmt: skip


def cells(subset: bool) -> list[tuple[str, str, int, bool, float]]:
    out = []
    for objective in ("hartmann6", "random-gp"):
        for coactive in (False, True):
            for noise in (0.0, NOISY):
                for d in (6, 8, 12):
                    out.append(("line", objective, d, coactive, noise))
                out.append(("grid", objective, 6, coactive, noise))
                out.append(("grid-gated", objective, 6, coactive, noise))
                out.append(("line-on-grid", objective, 6, coactive, noise))
    if subset:
        out = [c for c in out if not c[3] and c[4] == 0.0]
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--subset", action="store_true")
    parser.add_argument("--out", type=Path, default=Path("docs/results/continuous"))
    parser.add_argument("--report", action="store_true", help="summarise results.json only")
    parser.add_argument("--paths", nargs="+", choices=PATHS, default=list(PATHS))
    parser.add_argument("--dims", nargs="+", type=int, default=[6, 8, 12])
    parser.add_argument("--merge", action="store_true", help="replace only these paths' runs")
    parser.add_argument("--line-strategy", default="self-sparring")
    parser.add_argument("--line-fit", choices=("fixed", "evidence"), default="fixed")
    parser.add_argument("--line-count", type=int, default=1, help="lines per query")
    parser.add_argument("--line-points", type=int, default=50, help="points per line")
    parser.add_argument(
        "--line-cloud", type=int, default=0, help="points around the best point besides the lines"
    )
    parser.add_argument(
        "--line-boundary", choices=("clip", "fold"), default="clip",
        help="a line leaving the box at once both ways: clip it to its origin (every recorded "
        "run, as before defaults 0.11) or fold its direction into the box (the default since)",
    )  # fmt: skip
    args = parser.parse_args()
    if args.report:
        report(args.out / "results.json", args.out)
        return
    runs = []
    for path, objective, d, coactive, noise in cells(args.subset):
        if path not in args.paths or d not in args.dims:
            continue
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            known = HARTMANN6_MAX if objective == "hartmann6" and path == "line" else None
            r = one_run(
                path, objective, d, coactive, noise, seed, known,
                args.line_strategy, args.line_fit, args.line_count, args.line_points,
                args.line_cloud, args.line_boundary,
            )  # fmt: skip
            runs.append(r)
            print(
                f"{path:12s} {objective:9s} d={d:2d} co={int(coactive)} noise={noise} "
                f"seed={seed} best150={r['best_at']['150']:.3f} opt={r['optimum']:.3f} "
                f"rand={r['random_mean']:.3f} {r['seconds']:.1f}s",
                flush=True,
            )
    args.out.mkdir(parents=True, exist_ok=True)
    name = "results-subset.json" if args.subset else "results.json"
    commands = ["python benchmarks/study_continuous.py " + " ".join(sys.argv[1:])]
    if args.merge and (args.out / name).exists():
        old = json.loads((args.out / name).read_text())
        runs = [r for r in old["runs"] if r["path"] not in args.paths] + runs
        commands = [*old.get("commands", [DEFAULT_COMMAND]), *commands]
    (args.out / name).write_text(json.dumps({"trials": TRIALS, "commands": commands, "runs": runs}))


# -- the report: docs/results/continuous/summary.md and curves.png ----------------------------
def _fraction(values: np.ndarray, run: dict[str, Any]) -> np.ndarray:
    """How far from random selection (0) to the optimum (1)."""
    out: np.ndarray = (values - run["random_mean"]) / (run["optimum"] - run["random_mean"])
    return out


def _normalised(values: np.ndarray, run: dict[str, Any]) -> np.ndarray:
    """The paper's normalised objective, ``(f - worst) / (best - worst)``."""
    out: np.ndarray = (values - run["worst"]) / (run["optimum"] - run["worst"])
    return out


def _mse(xs: list[float]) -> str:
    a = np.asarray(xs)
    se = a.std(ddof=1) / np.sqrt(a.size) if a.size > 1 else 0.0
    return f"{a.mean():.3f} ± {se:.3f}"


def _grid_target(
    groups: dict[tuple[Any, ...], list[dict[str, Any]]], arm: str, objective: str, co: bool,
    noise: float,
) -> list[str]:  # fmt: skip
    """The 6-D target against one full-grid arm: line path (on the grid) minus the grid at trial
    150, paired by seed (same objective draw, same seed), normalised."""
    grid = {r["seed"]: r for r in groups.get((objective, 6, arm, co, noise), [])}
    line = {r["seed"]: r for r in groups.get((objective, 6, "line-on-grid", co, noise), [])}
    both = sorted(set(grid) & set(line))
    if len(both) < 2:
        return []
    diffs = np.array([
        float(_normalised(np.array(line[s]["best_at"]["150"]), line[s]))
        - float(_normalised(np.array(grid[s]["best_at"]["150"]), grid[s]))
        for s in both
    ])  # fmt: skip
    se = diffs.std(ddof=1) / np.sqrt(diffs.size)
    verdict = "met" if diffs.mean() >= -0.03 else "not met"
    return [
        f"- 6-D {objective}, coactive {'yes' if co else 'no'}, noise {noise}: line path (on "
        f"the same 57,750-gait grid) minus full grid ({arm}, "
        f"{grid[both[0]].get('strategy', 'self-sparring')}) at trial 150 = "
        f"{diffs.mean():+.3f} ± {se:.3f} (normalised, paired by seed; target: no worse than "
        f"-0.03): {verdict}"
    ]


def report(results: Path, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data = json.loads(results.read_text())
    runs: list[dict[str, Any]] = data["runs"]
    groups: dict[tuple[Any, ...], list[dict[str, Any]]] = {}
    for r in runs:
        key = (r["objective"], r["d"], r["path"], r["coactive"], r["noise"])
        groups.setdefault(key, []).append(r)
    seeds = max(len(g) for g in groups.values())
    used: dict[str, set[str]] = {}
    for r in runs:  # runs from before the strategy was recorded were self-sparring, fixed
        setting = f"{r.get('strategy', 'self-sparring')}, {r.get('fit', 'fixed')} kernel"
        if r.get("lines", 1) != 1:
            setting += f", {r['lines']} lines per query"
        if r.get("points", 50) != 50:
            setting += f" of {r['points']} points"
        if r.get("cloud", 0):
            setting += f", a cloud of {r['cloud']} points around the best"
        used.setdefault(r["path"], set()).add(setting)
    how = "; ".join(f"{p}: {' / '.join(sorted(used[p]))}" for p in PATHS if p in used)
    lines = [
        "# The line path on continuous spaces (issue 13)",
        "",
        *[f"`{c}`" for c in data.get("commands", [DEFAULT_COMMAND])],
        "then `--report` (with the same `--out`).",
        f"{TRIALS} trials, n = 1, b = 1; strategy and kernel per path: {how}.",
        "50 points per line, one line per query (unless said), random line directions; kernel",
        "(the starting one where it is evidence-fitted): lengthscale 0.25 of the range for",
        "Hartmann-6, the objective's own for the random GP; signal variance 1, jitter 1e-6;",
        f"model probit noise 0.05; noisy subjects answer with probit noise {NOISY}.  Up to",
        f"{seeds} seeds per cell (fewer than a full study: a shared 2-core machine); mean ±",
        "standard error over seeds.",
        "Random GP: a fresh draw per seed (`random-gp:SEED`, lengthscale 0.1 sqrt(d) of the",
        "range); its optimum is estimated (random search + L-BFGS-B). Hartmann-6 acts on the",
        "first six features; in 8-D and 12-D the others are irrelevant.",
        "",
        "**Fraction** = (f - random) / (optimum - random): 0 is random selection (the mean of",
        "4,000 uniform points), 1 the optimum. **best@T**: the posterior mean's best point after",
        "T trials; **exec 51-60**: the executed points of trials 51-60 (the learning curve).",
        "",
        "| objective | d | path | coactive | noise | best@60 fraction | exec 51-60 fraction "
        "| best@150 fraction | best@150 normalised | s/run |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for key in sorted(groups, key=lambda k: (k[0], k[1], k[2], k[3], k[4])):
        g = groups[key]
        b60 = [float(_fraction(np.array(r["best_at"]["60"]), r)) for r in g]
        e60 = [float(_fraction(np.array(r["curve"][50:60]), r).mean()) for r in g]
        b150 = [float(_fraction(np.array(r["best_at"]["150"]), r)) for r in g]
        n150 = [float(_normalised(np.array(r["best_at"]["150"]), r)) for r in g]
        sec = np.mean([r["seconds"] for r in g])
        objective, d, path, co, noise = key
        lines.append(
            f"| {objective} | {d} | {path} | {'yes' if co else 'no'} | {noise} | {_mse(b60)} | "
            f"{_mse(e60)} | {_mse(b150)} | {_mse(n150)} | {sec:.1f} |"
        )
    lines += ["", "## Targets", ""]
    for arm in ("grid", "grid-gated"):
        for objective in ("hartmann6", "random-gp"):
            for co in (False, True):
                for noise in (0.0, NOISY):
                    lines += _grid_target(groups, arm, objective, co, noise)
    for objective in ("hartmann6", "random-gp"):
        for d in (8, 12):
            for co in (False, True):
                for noise in (0.0, NOISY):
                    g = groups.get((objective, d, "line", co, noise), [])
                    if not g:
                        continue
                    b60 = np.array([float(_fraction(np.array(r["best_at"]["60"]), r)) for r in g])
                    verdict = "met" if b60.mean() >= 0.5 else "not met"
                    lines.append(
                        f"- {d}-D {objective}, coactive {'yes' if co else 'no'}, noise {noise}: "
                        f"best@60 fraction {_mse(list(b60))} (target >= 0.5): {verdict}"
                    )
    from matplotlib.lines import Line2D

    colour = {"line": "C0", "line-on-grid": "C2", "grid": "C7", "grid-gated": "C3"}
    style = {(False, 0.0): "-", (False, NOISY): "--", (True, 0.0): ":", (True, NOISY): "-."}
    panels = [(6, False), (6, True), (8, None), (12, None)]  # None: with and without coactive
    fig, axes = plt.subplots(2, 4, figsize=(16, 7), sharex=True, sharey=True)
    for row, objective in enumerate(("hartmann6", "random-gp")):
        for col, (d, coactive) in enumerate(panels):
            ax = axes[row, col]
            shown: set[str] = set()
            for (obj, dd, path, co, noise), g in sorted(groups.items()):
                if obj != objective or dd != d or coactive not in (None, co):
                    continue
                curve = np.mean([_fraction(np.array(r["curve"]), r) for r in g], axis=0)
                smooth = np.convolve(curve, np.ones(10) / 10, mode="valid")
                ax.plot(np.arange(10, TRIALS + 1), smooth, style[(co, noise)], color=colour[path])
                shown.add(path)
            ax.axhline(0.0, color="grey", lw=0.8)
            ax.axhline(1.0, color="grey", lw=0.8)
            which = "" if coactive is None else (", coactive" if coactive else ", no coactive")
            ax.set_title(f"{objective}, {d}-D{which}")
            if row == 1:
                ax.set_xlabel("trial")
            if col == 0:
                ax.set_ylabel("fraction random -> optimum")
            handles = [Line2D([], [], color=colour[p], label=p) for p in colour if p in shown]
            for (co, nz), ls in style.items():
                if coactive in (None, co):
                    label = f"{'' if co else 'no '}coactive, {'noisy' if nz else 'noiseless'}"
                    handles.append(Line2D([], [], color="k", ls=ls, label=label))
            ax.legend(handles=handles, fontsize=6.5, loc="upper left", ncol=2)
    fig.suptitle("executed points, 10-trial moving mean (0: random selection, 1: the optimum)")
    fig.tight_layout()
    fig.savefig(out / "curves.png", dpi=110)
    lines += ["", "![learning curves](curves.png)", ""]
    notes = "notes.md" if (out / "notes.md").exists() else "../notes.md"
    lines += [f"Observations and what was not met: [notes.md]({notes})."]
    (out / "summary.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
