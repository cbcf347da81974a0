"""Screen: lines through a point on the box's boundary clipped (before defaults 0.11) or folded
into the box (``[cospar] line_boundary``, ``gaitpref.loop.lines.entering``).

A config's defaults for a new line-path session (``gated-eubo``, a star of 4 lines of 50
points, lengthscales fitted every 20 answers), ``n = 1, b = 1``, no coactive feedback, a
noiseless subject, 60 trials (a session's length), on random-GP objectives
(``random-gp:SEED``, lengthscale ``0.1 sqrt(d)`` of the range) over three spaces: 12 features of
3 values, 8 features of 5 values, 12 continuous features.  Per run the mean objective of the
executed gaits over trials 1-60 and the posterior's best point after 60, as fractions from
random selection (0: the mean of 4,000 uniform points) to the optimum (1: the best of 50,000
grid points drawn at random, or random search + L-BFGS-B on the continuous box); and how many
trials walked the same gait as the trial before.  Clip and fold run from the same seeds;
differences are paired by seed.

    python benchmarks/screen_line_boundary.py [--seeds 10] [--out docs/results/continuous]
"""

from __future__ import annotations

import argparse
import functools
import itertools
import json
import platform
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from gaitpref.config import parse_config
from gaitpref.simulate.continuous import builtin, estimate_optimum, random_gp_lengthscale
from gaitpref.simulate.points import PointUser, random_curve, run_points

TRIALS = 60
#: grid points drawn to estimate a grid objective's optimum
OPTIMUM_SAMPLE = 50_000
SPACES = {"12 x 3 values": (12, 3), "8 x 5 values": (8, 5), "12 continuous": (12, None)}


def config_text(d: int, num: int | None, boundary: str, seed: int) -> str:
    lines = [
        "[model]", f"lengthscale = {random_gp_lengthscale(d)}", "signal_variance = 1.0",
        "noise = 0.05", "jitter = 1e-6",
        "[cospar]", 'subspace = "line"', f"seed = {seed}", f'line_boundary = "{boundary}"',
    ]  # fmt: skip
    for k in range(d):
        lines += [f"[space.x{k}]", "min = 0.0", "max = 1.0"] + ([f"num = {num}"] if num else [])
    return "\n".join(lines) + "\n"


@functools.cache
def _scale(name: str, seed: int) -> tuple[float, float]:
    """The objective's optimum (on a grid: the best of :data:`OPTIMUM_SAMPLE` grid points drawn
    at random, as its 390,625 to 531,441 points take half a minute; the arms share it, so the
    paired differences do not depend on it) and random selection's mean."""
    d, num = SPACES[name]
    domain = parse_config(config_text(d, num, "fold", seed)).space
    fn = builtin("random-gp", domain, seed)
    if num is None:
        optimum = estimate_optimum(fn, domain, seed)[1]
    else:
        rng = np.random.default_rng(30_000 + seed)
        sample = rng.integers(0, num, size=(OPTIMUM_SAMPLE, d)) / (num - 1)
        optimum = float(np.max(fn(sample)))
    rand = float(random_curve(fn, domain, 4000, np.random.default_rng(10_000 + seed)).mean())
    return optimum, rand


def one_run(name: str, boundary: str, seed: int) -> dict[str, Any]:
    d, num = SPACES[name]
    cfg = parse_config(config_text(d, num, boundary, seed))
    domain = cfg.space
    fn = builtin("random-gp", domain, seed)
    optimum, rand = _scale(name, seed)
    user = PointUser(fn, np.random.default_rng(20_000 + seed), 0.0)
    start = time.perf_counter()
    res = run_points(cfg.make_loop(), fn, user, TRIALS, None, checkpoints=(TRIALS,))
    pts = [tuple(p[0]) for p in res.points]
    frac = (res.curve.mean() - rand) / (optimum - rand)
    return {
        "space": name, "boundary": boundary, "seed": seed,
        "exec": float(frac), "best": float((res.best_at[TRIALS] - rand) / (optimum - rand)),
        "repeats": sum(a == b for a, b in itertools.pairwise(pts)),
        "distinct": len(set(pts)), "seconds": time.perf_counter() - start,
    }  # fmt: skip


def report(runs: list[dict[str, Any]], command: str) -> str:
    out = [
        "# Lines through the box's boundary: clip or fold",
        "",
        f"`{command}` (module docstring: what runs).",
        "Mean over seeds; fold - clip paired by seed (standard error).  exec: the executed gaits'",
        "objective over trials 1-60; best: the posterior's best point after 60 (fractions from",
        "random selection, 0, to the optimum, 1); repeats: trials that walked the gait of the",
        "trial before.",
        "",
        "| space | seeds | exec clip | exec fold | fold - clip | best clip | best fold "
        "| fold - clip | repeats clip | repeats fold | distinct clip | distinct fold |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name in SPACES:
        by = {b: {r["seed"]: r for r in runs if r["space"] == name and r["boundary"] == b}
              for b in ("clip", "fold")}  # fmt: skip
        seeds = sorted(set(by["clip"]) & set(by["fold"]))
        if not seeds:
            continue

        def col(b: str, key: str, seeds: list[int] = seeds, by: dict[str, Any] = by) -> np.ndarray:
            return np.array([by[b][s][key] for s in seeds], dtype=float)

        def diff(key: str) -> str:
            dd = col("fold", key) - col("clip", key)
            se = dd.std(ddof=1) / np.sqrt(dd.size) if dd.size > 1 else float("nan")
            return f"{dd.mean():+.3f} ({se:.3f})"

        out.append(
            f"| {name} | {len(seeds)} | {col('clip', 'exec').mean():.3f} | "
            f"{col('fold', 'exec').mean():.3f} | {diff('exec')} | {col('clip', 'best').mean():.3f}"
            f" | {col('fold', 'best').mean():.3f} | {diff('best')} | "
            f"{col('clip', 'repeats').mean():.1f} | {col('fold', 'repeats').mean():.1f} | "
            f"{col('clip', 'distinct').mean():.1f} | {col('fold', 'distinct').mean():.1f} |"
        )
    load = Path("/proc/loadavg").read_text().split()[0] if Path("/proc/loadavg").exists() else "?"
    out += [
        "",
        "Machine:",
        "",
        f"- date: {datetime.now(UTC):%Y-%m-%d %H:%M} UTC",
        f"- cores: {__import__('os').cpu_count()}",
        f"- load_average_1min: {load}",
        f"- python: {platform.python_version()}",
        f"- numpy: {np.__version__}",
        "",
    ]
    return "\n".join(out)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--out", type=Path, default=Path("docs/results/continuous"))
    args = parser.parse_args()
    runs = []
    for name in SPACES:
        for seed in range(args.seeds):
            for boundary in ("clip", "fold"):
                r = one_run(name, boundary, seed)
                runs.append(r)
                print(
                    f"{name:14s} {boundary} seed={seed} exec={r['exec']:.3f} best={r['best']:.3f} "
                    f"repeats={r['repeats']} {r['seconds']:.1f}s",
                    flush=True,
                )
    command = f"python benchmarks/screen_line_boundary.py --seeds {args.seeds}"
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "line-boundary.json").write_text(json.dumps({"command": command, "runs": runs}))
    (args.out / "line-boundary.md").write_text(report(runs, command))


if __name__ == "__main__":
    main()
