"""Issue 16 check: the exploration burst on objectives it was not chosen on.

The burst's window (self-sparring for trials 21-45, ``sparring_from = 20``, ``sparring_until =
45``) was picked on the paper's 100 objectives, the same ones the learning study reports.  This
script draws fresh objectives like the paper's (its objectives are GP samples; here a Gaussian
process on the 30 x 30 grid of ``[0, 1]^2``, squared-exponential kernel, lengthscale 0.15, the
study's "kernel right", variance 0.1; seeded), and runs the study's arms on them with the
study's harness (``study_learning.run_one``: its subjects, seeds per run and coactive feedback),
paired by objective.

    python benchmarks/check_burst_heldout.py [--objectives 100] [--seed 1] [--scenario noiseless]

Prints each arm's trials 1-20 / 31-150 / 121-150 / final argmax and trials 21-45 / 1-60 /
1-150 (mean and standard error over objectives), and each arm's paired difference from
``gated+fit`` (the default) and from ``paper`` (self-sparring); writes the rows to ``--out``
(JSON).  Results: ``docs/learning.md`` ("An exploration burst").
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed
from study_learning import ARMS, WINDOWS, _phase, _se, run_one

ARM_NAMES = ("paper", "gated+fit", "gated+fit+local", "gated+fit+burst", "gated+burst")


def draw_objectives(count: int, seed: int, lengthscale: float = 0.15) -> np.ndarray:
    """``count`` GP draws on the 30 x 30 grid, ``(count, 30, 30)``, C order (x major)."""
    axis = np.linspace(0.0, 1.0, 30)
    points = np.stack(np.meshgrid(axis, axis, indexing="ij"), axis=-1).reshape(-1, 2)
    d2 = ((points[:, None, :] - points[None, :, :]) ** 2).sum(-1)
    cov = 0.1 * np.exp(-0.5 * d2 / lengthscale**2) + 1e-8 * np.eye(len(points))
    root = np.linalg.cholesky(cov)
    z = np.random.default_rng(seed).standard_normal((count, len(points)))
    return (z @ root.T).reshape(count, 30, 30)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--objectives", type=int, default=100)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--scenario", default="noiseless", choices=("noiseless", "noisy"))
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("out/burst-heldout.json"))
    args = parser.parse_args()
    objectives = draw_objectives(args.objectives, args.seed)
    arms = {a.name: a for a in ARMS}
    phases: dict[str, dict[str, np.ndarray]] = {}
    rows: dict[str, list[dict[str, object]]] = {}
    for name in ARM_NAMES:
        runs = Parallel(n_jobs=args.jobs)(
            delayed(run_one)(arms[name], args.scenario, k, objectives[k])
            for k in range(args.objectives)
        )
        rows[name] = [{"scores": list(r["scores"]), "argmax": r["argmax"]} for r in runs]
        phases[name] = _phase(runs)
        scores = np.array([r["scores"] for r in runs])
        for window, (lo, hi) in WINDOWS.items():  # every trial counted
            phases[name][window] = scores[:, lo:hi].mean(axis=1)
        cells = [f"{k} {v.mean():.3f} ({_se(v):.3f})" for k, v in phases[name].items()]
        print(f"{name:18s} " + " | ".join(cells), flush=True)
    for base in ("gated+fit", "paper"):
        for name in ARM_NAMES:
            if name == base:
                continue
            diffs = {k: phases[name][k] - phases[base][k] for k in phases[name]}
            cells = [f"{k} {d.mean():+.3f} ± {_se(d):.3f}" for k, d in diffs.items()]
            print(f"{name} - {base}: " + " | ".join(cells), flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    meta = {"objectives": args.objectives, "seed": args.seed, "scenario": args.scenario}
    args.out.write_text(json.dumps({**meta, "runs": rows}))


if __name__ == "__main__":
    main()
