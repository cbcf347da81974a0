"""Simulated study: plain CoSpar over the full 57,750-action six-feature grid vs random selection.

The ``synthetic-6d`` config (11 x 7 x 6 x 5 x 5 x 5 on [0, 1]^6, the shape of LineCoSpar's
exoskeleton space; lengthscale 0.4), n = 1, b = 1 with the paper's gradient coactive feedback,
150 trials.  Run ``k`` uses objective ``k``: a sample of a unit-variance GP with the model's
lengthscale, drawn by the Kronecker sampler with seed ``1000 + k`` (a well-specified model, as in
the paper's synthetic study), and CoSpar seed ``k``.  Random selection executes uniformly random
actions (seed ``k``).  The score of a trial is the normalised objective of its action.

    python benchmarks/study_large_6d.py [--runs 100] [--jobs 2]

Writes docs/results/large-6d/: curves.csv, learning_curve.png and runs.csv.
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from joblib import Parallel, delayed
from threadpoolctl import threadpool_limits

from gaitpref import GradientCoactive, SimulatedUser, load_config, run_simulation
from gaitpref.model import SquaredExponential
from gaitpref.model.kronecker import KroneckerPriorSampler

OUT = Path(__file__).resolve().parent.parent / "docs" / "results" / "large-6d"
TRIALS = 150


def objective(k: int) -> np.ndarray:
    cfg = load_config("synthetic-6d")
    ell = cfg.kernel.lengthscales(cfg.space.ndim)
    prior = KroneckerPriorSampler(cfg.space, SquaredExponential(ell, 1.0, 0.0))
    return prior.sample(np.random.default_rng(1000 + k), 1)[0]


def one_run(k: int) -> dict[str, object]:
    """CoSpar and random selection on objective ``k``."""
    with threadpool_limits(limits=1, user_api="blas"):  # the jobs share 2 cores
        cfg = load_config("synthetic-6d")
        f = objective(k)
        user = SimulatedUser(cfg.space, f, np.random.default_rng(k))
        start = time.perf_counter()
        result = run_simulation(cfg.make_loop(seed=k), user, TRIALS, GradientCoactive(cfg.space, f))
        seconds = time.perf_counter() - start
        random_actions = np.random.default_rng(k).integers(0, len(cfg.space), TRIALS)
        return {
            "cospar": result.normalized_objective,
            "random": user.normalized(random_actions),
            "grid_mean": float(np.mean(user.normalized(np.arange(len(cfg.space))))),
            "argmax": result.argmax_normalized_objective,
            "seconds": seconds,
        }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    start = time.perf_counter()
    runs = Parallel(n_jobs=args.jobs)(delayed(one_run)(k) for k in range(args.runs))
    wall = time.perf_counter() - start
    cospar = np.array([r["cospar"] for r in runs])
    rand = np.array([r["random"] for r in runs])
    sqrt_n = np.sqrt(args.runs)
    OUT.mkdir(parents=True, exist_ok=True)
    with (OUT / "curves.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["trial", "cospar_mean", "cospar_se", "random_mean", "random_se"])
        for t in range(TRIALS):
            w.writerow(
                [t + 1]
                + [f"{v:.4f}" for v in (cospar[:, t].mean(), cospar[:, t].std(ddof=1) / sqrt_n)]
                + [f"{v:.4f}" for v in (rand[:, t].mean(), rand[:, t].std(ddof=1) / sqrt_n)]
            )
    with (OUT / "runs.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["run", "posterior_argmax_normalized", "grid_mean_normalized", "seconds"])
        for k, r in enumerate(runs):
            w.writerow([k, f"{r['argmax']:.4f}", f"{r['grid_mean']:.4f}", f"{r['seconds']:.2f}"])
    trials = np.arange(1, TRIALS + 1)
    fig, ax = plt.subplots(figsize=(6, 4))
    for data, label in ((cospar, "CoSpar (n = 1, b = 1, coactive)"), (rand, "random selection")):
        mean, se = data.mean(axis=0), data.std(axis=0, ddof=1) / sqrt_n
        ax.plot(trials, mean, label=label)
        ax.fill_between(trials, mean - se, mean + se, alpha=0.3)
    ax.set_xlabel("trial")
    ax.set_ylabel("normalized objective of the executed action")
    ax.set_title(f"57,750-action 6-D grid, {args.runs} runs (mean +- s.e.)")
    ax.set_ylim(0, 1)
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(OUT / "learning_curve.png", dpi=120)
    at = [24, 49, 99, 149]
    print("trial        " + " ".join(f"{t + 1:>6d}" for t in at))
    print("cospar       " + " ".join(f"{cospar[:, t].mean():6.3f}" for t in at))
    print("random       " + " ".join(f"{rand[:, t].mean():6.3f}" for t in at))
    argmax = np.array([r["argmax"] for r in runs])
    secs = np.array([r["seconds"] for r in runs])
    print(
        f"posterior argmax at trial 150: {argmax.mean():.3f} +- {argmax.std(ddof=1) / sqrt_n:.3f}"
    )
    print(f"seconds per CoSpar run: median {np.median(secs):.2f}; wall {wall:.0f} s")


if __name__ == "__main__":
    main()
