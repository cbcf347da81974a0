"""Issue 13 check: how far 60 trials can get on the random-GP cells, and what a continuous
recommendation adds.

For the cells of ``study_continuous.py`` that miss "halfway by trial 60" (random GP, 8-D and
12-D, no coactive feedback; and Hartmann-6 noisy), on the study's seeds and settings (line path,
self-sparring, fixed kernel):

- ``table``: the study's best@60 fraction (the posterior mean's argmax over the points so far);
- ``refined``: the posterior mean maximised over the continuous box (L-BFGS-B from the table's
  five best points, the mean ``k(x, V) alpha`` and its gradient in closed form);
- ``best executed``: the best point the loop ran in trials 1-60, by its true objective;
- ``random 60``: the best of 60 uniform points, by their true values (random search that knows
  every value exactly; mean of 20 draws per seed); ``random 1e5``: of 100,000.

Fractions as the study's: ``(f - random mean) / (optimum - random mean)``.

    python benchmarks/check_continuous_ceiling.py --seeds 6
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.optimize import minimize
from study_continuous import PREF_NOISE, box, kernel

from gaitpref.loop.learning import Learning
from gaitpref.loop.line import LineCoSpar
from gaitpref.loop.lines import LineSettings
from gaitpref.simulate.continuous import builtin, estimate_optimum
from gaitpref.simulate.points import PointUser, random_curve, run_points
from gaitpref.strategies import make_strategy

CELLS = [
    ("random-gp", 8, 0.0),
    ("random-gp", 8, 0.2),
    ("random-gp", 12, 0.0),
    ("random-gp", 12, 0.2),
    ("hartmann6", 8, 0.2),
    ("hartmann6", 12, 0.2),
]


def refined_best(loop: LineCoSpar, d: int, top: int = 5) -> np.ndarray:
    """The posterior mean's maximiser over the box, from the table's ``top`` best points."""
    post = loop.posterior
    assert post.fit is not None
    points = loop.space.points
    visited, alpha = points[post.visited], post.fit.alpha
    k = loop.gp.kernel
    ell = np.asarray(k.lengthscales(d))

    def negative(x: np.ndarray) -> tuple[float, np.ndarray]:
        z = (x[None, :] - visited) / ell
        w = k.variance * np.exp(-0.5 * (z * z).sum(axis=1)) * alpha
        return -float(w.sum()), (w[:, None] * z / ell).sum(axis=0)

    mean = np.asarray(post.mean)
    best_x, best_v = points[int(np.argmax(mean))], float(mean.max())
    for i in np.argsort(-mean)[:top]:
        res = minimize(negative, points[i], jac=True, method="L-BFGS-B", bounds=[(0, 1)] * d)
        if -res.fun > best_v:
            best_x, best_v = res.x, -float(res.fun)
    return best_x


def one(objective: str, d: int, noise: float, seed: int) -> tuple[float, ...]:
    domain = box(d)
    fn = builtin(objective, domain, seed)
    optimum = estimate_optimum(fn, domain, seed)[1]
    loop_seed, user_seed = np.random.SeedSequence(seed).spawn(2)
    loop = LineCoSpar(
        domain, kernel(objective, d), PREF_NOISE, line=LineSettings(50),
        strategy=make_strategy("self-sparring"), learning=Learning(fit="fixed"),
        n=1, buffer=1, seed=np.random.default_rng(loop_seed),
    )  # fmt: skip
    user = PointUser(fn, np.random.default_rng(user_seed), noise)
    res = run_points(loop, fn, user, 60, None, checkpoints=(60,))
    rand = float(random_curve(fn, domain, 4000, np.random.default_rng(10_000 + seed)).mean())
    rng = np.random.default_rng(seed)
    r60 = float(np.mean([fn(rng.uniform(size=(60, d))).max() for _ in range(20)]))
    r1e5 = float(fn(rng.uniform(size=(100_000, d))).max())
    refined = float(np.asarray(fn(refined_best(loop, d)[None, :]))[0])
    values = (res.best_at[60], refined, float(res.curve.max()), r60, r1e5)
    return tuple((v - rand) / (optimum - rand) for v in values)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, default=6)
    args = parser.parse_args()
    print("| objective | d | noise | table | refined | refined - table | best executed "
          "| random 60 | random 1e5 |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|")
    for objective, d, noise in CELLS:
        rows = np.array([one(objective, d, noise, s) for s in range(args.seeds)])
        mean, se = rows.mean(axis=0), rows.std(axis=0, ddof=1) / np.sqrt(len(rows))
        diff = rows[:, 1] - rows[:, 0]
        cells = [f"{m:.3f} ± {s:.3f}" for m, s in zip(mean, se, strict=True)]
        gain = f"{diff.mean():+.3f} ± {diff.std(ddof=1) / np.sqrt(len(diff)):.3f}"
        print(f"| {objective} | {d} | {noise} | {cells[0]} | {cells[1]} | {gain} | "
              f"{cells[2]} | {cells[3]} | {cells[4]} |", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
