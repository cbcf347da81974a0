"""Issue 13 check: how far 60 trials get on the random-GP cells when every trial returns the
objective's exact value, not a comparison.

The cells that miss "halfway by trial 60" are the random GP in 8-D and 12-D without coactive
feedback (``docs/results/continuous/``).  A comparison carries at most one bit; an exact value
carries far more.  So Bayesian optimisation on exact values, with the objective's own kernel
(``study_continuous.kernel``: the draw's lengthscale, signal variance 1), is a generous
reference for what 60 trials of any method can reach: if it does not reach halfway, the target
asks more of 60 comparisons than 60 exact values give.

The optimiser: a GP on the values so far (jitter 1e-6), expected improvement over the best
value, maximised over 4,000 uniform points and 4,000 points around the five best so far
(Gaussian steps of 0.02, 0.05, 0.1 and 0.2 of the range, clipped to the box), the first point
uniform.  Its best value after ``T`` trials, as a fraction of the way from random selection to
the optimum (``study_continuous.py``'s fraction, the same random mean and optimum estimate),
on the study's objective draws (seed ``k`` draws ``random-gp:k``).

    python benchmarks/check_continuous_values.py --seeds 12
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.linalg import cho_solve, cholesky
from scipy.special import ndtr
from study_continuous import box, kernel

from gaitpref.simulate.continuous import builtin, estimate_optimum
from gaitpref.simulate.points import random_curve

CELLS = (8, 12)
TRIALS = 60
CHECKPOINTS = (20, 40, 60)


def _cov(x: np.ndarray, y: np.ndarray, ell: float) -> np.ndarray:
    d2 = ((x[:, None, :] - y[None, :, :]) ** 2).sum(axis=2)
    out: np.ndarray = np.exp(-0.5 * d2 / ell**2)
    return out


def _candidates(rng: np.random.Generator, X: np.ndarray, y: np.ndarray) -> np.ndarray:
    d = X.shape[1]
    best = X[np.argsort(y)[-5:]]
    local = [
        np.clip(best[rng.integers(0, len(best), 1000)] + rng.normal(0, s, (1000, d)), 0, 1)
        for s in (0.02, 0.05, 0.1, 0.2)
    ]
    return np.vstack([rng.uniform(size=(4000, d)), *local])


def run(d: int, seed: int) -> np.ndarray:
    """The best exact value after each trial, as a fraction from random to the optimum."""
    domain = box(d)
    fn = builtin("random-gp", domain, seed)
    optimum = estimate_optimum(fn, domain, seed)[1]
    rand = float(random_curve(fn, domain, 4000, np.random.default_rng(10_000 + seed)).mean())
    ell = float(np.asarray(kernel("random-gp", d).lengthscales(d))[0])
    rng = np.random.default_rng(seed)
    X = rng.uniform(size=(1, d))
    y = np.asarray(fn(X), dtype=np.float64)
    while len(y) < TRIALS:
        L = cholesky(_cov(X, X, ell) + 1e-6 * np.eye(len(y)), lower=True)
        alpha = cho_solve((L, True), y)
        C = _candidates(rng, X, y)
        Kc = _cov(C, X, ell)
        mean = Kc @ alpha
        v = np.linalg.solve(L, Kc.T)
        sd = np.sqrt(np.maximum(1.0 - (v * v).sum(axis=0), 1e-12))
        z = (mean - y.max()) / sd
        ei = (mean - y.max()) * ndtr(z) + sd * np.exp(-0.5 * z * z) / np.sqrt(2 * np.pi)
        x = C[int(np.argmax(ei))][None, :]
        X = np.vstack([X, x])
        y = np.concatenate([y, np.asarray(fn(x), dtype=np.float64)])
    out: np.ndarray = (np.maximum.accumulate(y) - rand) / (optimum - rand)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=12)
    args = parser.parse_args()
    heads = " | ".join(f"best@{t}" for t in CHECKPOINTS)
    print(f"| random GP | seeds | {heads} | runs at or past 0.5 by trial 60 |")
    print("|---|---|" + "---|" * len(CHECKPOINTS) + "---|")
    for d in CELLS:
        curves = np.array([run(d, s) for s in range(args.seeds)])
        cells = []
        for t in CHECKPOINTS:
            col = curves[:, t - 1]
            cells.append(f"{col.mean():.3f} ± {col.std(ddof=1) / np.sqrt(len(col)):.3f}")
        past = int(np.sum(curves[:, TRIALS - 1] >= 0.5))
        print(f"| {d}-D | {args.seeds} | {' | '.join(cells)} | {past} of {args.seeds} |",
              flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
