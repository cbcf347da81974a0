"""Issue 13 screen: recommend the posterior mean's maximiser over the box, not over the table.

The line path's recommendation (``LineCoSpar.best_point``, the study's ``best@T``) is the
posterior mean's argmax over its table: the visited points and the current lines.  The mean is
a smooth function of the point, ``mu(x) = k(x, V) alpha`` with ``alpha = K_VV^-1 mu_V``
(``K_VV`` with the kernel's jitter), so it can be maximised over the continuous box by L-BFGS-B
from the table's ten best points.  This screen runs the default line arm of
``study_continuous.py`` (gated EUBO, evidence-fitted lengthscales, four lines of 50 points; the
study's seeds, kernel and subjects) to trial 60 and reports both recommendations as the study's
fraction of the way from random selection to the optimum.

    python benchmarks/screen_continuous_max.py 12 0.0 0 12   # d, subject noise, seeds a..b-1

Result (2026-12-04, 12-D random GP without coactive feedback, seeds 0-11):
``docs/results/continuous/notes.md``, "The mean's maximiser over the box".
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable

import numpy as np
import study_continuous as sc
from _usage import positional
from numpy.typing import NDArray
from scipy.optimize import minimize

from gaitpref.loop.learning import Learning
from gaitpref.loop.line import LineCoSpar
from gaitpref.loop.lines import LineSettings
from gaitpref.model.posterior import Posterior
from gaitpref.pointset import PointSet
from gaitpref.simulate.continuous import builtin, estimate_optimum
from gaitpref.simulate.points import PointUser, random_curve
from gaitpref.strategies import make_strategy

Vector = NDArray[np.float64]


def negative_mean(post: Posterior, space: PointSet) -> Callable[[Vector], tuple[float, Vector]]:
    """``x -> (-mu(x), -grad mu(x))`` for the squared-exponential kernel's posterior mean."""
    visited = space.points_of(post.visited)
    ls = np.array(post.kernel.lengthscales(space.ndim))
    var = post.kernel.variance
    diff = (visited[:, None, :] - visited[None, :, :]) / ls
    gram = var * np.exp(-0.5 * (diff * diff).sum(-1)) + post.kernel.jitter * np.eye(len(visited))
    alpha = np.linalg.solve(gram, post.mean_at(post.visited))

    def f(x: Vector) -> tuple[float, Vector]:
        z = (x[None, :] - visited) / ls
        k = var * np.exp(-0.5 * (z * z).sum(1))
        grad = -(k * alpha) @ (z / ls)
        return -float(k @ alpha), -grad

    return f


def run(d: int, noise: float, seed: int, trials: int = 60) -> dict[str, float]:
    domain = sc.box(d)
    fn = builtin("random-gp", domain, seed)
    optimum = estimate_optimum(fn, domain, seed)[1]
    loop_seed, user_seed = np.random.SeedSequence(seed).spawn(2)
    loop = LineCoSpar(
        domain, sc.kernel("random-gp", d), sc.PREF_NOISE, line=LineSettings(50, "random", 4),
        strategy=make_strategy("gated-eubo"), learning=Learning(fit="evidence"), n=1, buffer=1,
        seed=np.random.default_rng(loop_seed),
    )  # fmt: skip
    user = PointUser(fn, np.random.default_rng(user_seed), noise)
    done = 0
    while done < trials:
        query = loop.ask()
        loop.tell(query, user.answer(query, loop.space), [])
        done += len(query.actions)
    post, space = loop.posterior, loop.space
    rand = float(random_curve(fn, domain, 4000, np.random.default_rng(10_000 + seed)).mean())
    table_best = space.points_of([post.argmax])[0]
    f = negative_mean(post, space)
    best_x, best_mu = table_best, -f(table_best)[0]
    for i in np.argsort(post.mean)[::-1][:10]:
        res = minimize(f, space.points[i], jac=True, method="L-BFGS-B", bounds=[(0.0, 1.0)] * d)
        if -res.fun > best_mu:
            best_mu, best_x = -float(res.fun), res.x

    def fraction(x: Vector) -> float:
        return (float(fn(x[None])[0]) - rand) / (optimum - rand)

    return {
        "seed": seed, "noise": noise, "table": fraction(table_best), "box": fraction(best_x),
        "moved": float(np.linalg.norm(best_x - table_best)),
    }  # fmt: skip


def main() -> None:
    args = positional(__doc__, 4, 4)
    d, noise = int(args[0]), float(args[1])
    rows = []
    for seed in range(int(args[2]), int(args[3])):
        start = time.perf_counter()
        rows.append(run(d, noise, seed))
        print(json.dumps(rows[-1]), f"{time.perf_counter() - start:.1f} s", flush=True)
    table = np.array([r["table"] for r in rows])
    gain = np.array([r["box"] for r in rows]) - table
    se = gain.std(ddof=1) / np.sqrt(len(gain)) if len(gain) > 1 else float("nan")
    print(f"table {table.mean():.3f}  box {table.mean() + gain.mean():.3f}  "
          f"box - table {gain.mean():+.3f} ± {se:.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
