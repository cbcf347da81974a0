"""Screen (issue 14): the stopping rule's confidence from another model of the same answers.

``check_stop_calibration.py`` finds the default loop (gated EUBO, lengthscales fitted every 20
answers) overconfident above 0.7 with noiseless subjects.  This screen keeps that loop as it is
(the same runs: same seeds, same proposals) and states, beside the product's confidence, the
confidence of a second posterior of the same answers:

- ``variance SD``: hyperparameters refitted with the signal variance free too (its log-normal
  prior's sd ``SD``; the product holds it, ``docs/learning.md``), from the loop's current ones;
- ``config``: the config's own kernel (lengthscales as written, never fitted);
- ``config-variance SD``: the config's lengthscales held, the signal variance fitted (log-sd
  ``SD``);
- ``dedupe``: the loop's own kernel, each distinct answered pair counted once (a pair answered
  again the same way, as the gate's repeat of the best against the challenger it just beat,
  adds no second term).

    python benchmarks/screen_confidence_kernel.py variance 3.0 [--objectives 100]
    python benchmarks/screen_confidence_kernel.py config 0 [--objectives 100]
    python benchmarks/screen_confidence_kernel.py config-variance 3.0 [--objectives 100]
    python benchmarks/screen_confidence_kernel.py dedupe 0 [--objectives 100]

prints both calibrations (cluster bootstrap over subjects) and writes the rows to ``--out``.
It reads the loop's private fitting helpers: a screen, not product code.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
from joblib import Parallel, delayed

from gaitpref.data import paper_objectives
from gaitpref.loop.stopping import confidence
from gaitpref.model.hyperfit import LogNormal, fit_hyperparameters
from gaitpref.simulate.population import cluster_bootstrap
from gaitpref.simulate.users import SimulatedUser

sys.path.insert(0, str(Path(__file__).resolve().parent))
from check_stop_calibration import SAMPLES, TOLERANCE, arm_config


def one(k: int, mode: str, sd: float, trials: int, every: int) -> list[dict[str, Any]]:
    config = arm_config("default")
    raw = paper_objectives().reshape(100, -1)[k]
    u = (raw - raw.mean()) / raw.std()
    loop_ss, user_ss, sure_ss = np.random.SeedSequence([16, k]).spawn(3)  # check's seeds
    loop = config.make_loop(seed=np.random.default_rng(loop_ss))
    user = SimulatedUser(config.space, u, np.random.default_rng(user_ss), noise=0.0)
    rng, other_rng = np.random.default_rng(sure_ss), np.random.default_rng([99, k])
    span = float(u.max() - u.min())
    prior = dataclasses.replace(loop.prior, variance=LogNormal(loop.prior.variance.median, sd))
    if mode == "config-variance":  # the lengthscales held at the config's
        held = tuple(LogNormal(p.median, 0.0) for p in prior.lengthscale)
        prior = dataclasses.replace(prior, lengthscale=held)
    hyper = loop.hyper  # the config's kernel
    rows = []
    for t in range(1, trials + 1):
        query = loop.ask()
        loop.tell(query, user.answer(query))
        if t % every:
            continue
        product = confidence(loop.posterior, rng, tolerance=TOLERANCE, samples=SAMPLES)
        if mode in ("variance", "config-variance"):
            base = loop.hyper if mode == "variance" else hyper
            start = dataclasses.replace(base, variance=hyper.variance)
            hyper = fit_hyperparameters(loop.space, start, loop._data(loop.answers), prior).after
        if mode == "dedupe":
            post = loop._fit(_once(loop.answers), gp=loop.gp, hyper=loop.hyper)
        else:
            post = loop._fit(loop.answers, gp=loop._gp(hyper), hyper=hyper)
        other = confidence(post, other_rng, tolerance=TOLERANCE, samples=SAMPLES)
        rows.append(
            {
                "t": t,
                "product": product.probability,
                "product_right": bool(u.max() - u[product.recommended] <= TOLERANCE * span),
                "other": other.probability,
                "other_right": bool(u.max() - u[other.recommended] <= TOLERANCE * span),
                "signal_variance": hyper.variance,
            }
        )
    return rows


def _once(answers: list[Any]) -> list[Any]:
    """``answers`` with each (winner, loser) pair's preference kept at its first answer only."""
    seen: set[tuple[int, int]] = set()
    kept = []
    for answer in answers:
        prefs = []
        for p in answer.preferences:
            if (p.winner, p.loser) not in seen:
                seen.add((p.winner, p.loser))
                prefs.append(p)
        kept.append(dataclasses.replace(answer, preferences=tuple(prefs)))
    return kept


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("mode", choices=("variance", "config", "config-variance", "dedupe"))
    parser.add_argument("sd", type=float, help="variance: the prior's log-sd (config: ignored)")
    parser.add_argument("--objectives", type=int, default=100)
    parser.add_argument("--trials", type=int, default=150)
    parser.add_argument("--every", type=int, default=5)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("out/screen_confidence_kernel.json"))
    args = parser.parse_args()
    runs = Parallel(n_jobs=args.jobs)(
        delayed(one)(k, args.mode, args.sd, args.trials, args.every) for k in range(args.objectives)
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(runs) + "\n", encoding="utf-8")
    for name in ("product", "other"):
        rows = cluster_bootstrap(
            [([r[name] for r in run], [r[f"{name}_right"] for r in run]) for run in runs],
            np.random.default_rng(1),
        )
        print(name)
        for b in rows:
            print(
                f"  {b['lo']:.1f}-{b['hi']:.1f}: {b['count']} stated, {b['clusters']} subjects, "
                f"stated {b['stated']:.3f}, observed {b['observed']:.3f}, "
                f"gap {b['observed'] - b['stated']:+.3f} (se {b['se']:.3f})"
            )


if __name__ == "__main__":
    main()
