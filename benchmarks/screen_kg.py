"""Issue 16 screen: a knowledge-gradient challenger late, on the learning study's runs.

The learning study's setting (``study_learning.py``: the paper's 100 objectives on the 30 x 30
grid, ``n = 1, b = 1``, coactive feedback from the gradient user, 150 trials, its seeds), as
``screen_gates.py`` runs it, with one screen-only strategy: ``gated-eubo`` (its Thompson gate,
and its EUBO challenger with the local challenger early, ``early_scale = 0.5`` over the first
20 trials) whose challenger from trial ``kg_from`` on is the one-step knowledge gradient
(Frazier, Powell and Dayanik 2008) of a comparison with the buffered gait instead of EUBO's:

    KG(x) = sum_y P(y) max_g mu_g(y) - max_g mu_g,

``y`` the answer to "x or the buffered gait b", ``mu_g(y)`` the posterior mean after it, one
assumed-density-filtering step on the probit of ``d = f_x - f_b`` (``c^2 = 2 s^2 + var d``,
``z = y mean(d) / c``; every mean moves by ``cov(g, d) y phi(z) / (Phi(z) c)``).  EUBO prizes a
challenger that could be much better than ``b`` (often a far, uncertain gait); KG prizes one
whose answer would change which gait is recommended, which late in a run is a comparison among
the few gaits near the top.  Candidates: the ``cands`` gaits of largest ``mu + 2 sd`` (b
excluded).  When no candidate has KG above ``1e-12`` of the signal sd, the EUBO challenger.
Variant keys: ``kg_from`` (trial; default 20), ``cands`` (default 100), ``subject``
(``noiseless``, ``noisy``), ``ls`` (the configured lengthscale), ``early`` (``early_scale``;
default 0.5; 1 for none), ``gate`` (0: no gate, always a challenger), ``star`` (1: KG*, each
candidate's best KG per answer over the comparison answered 1, 2, 4, ..., 64 times, as a
Gaussian observation with the probit noise over the square root of that count: the plain KG is
zero wherever no single answer can change the recommendation), ``late`` (``runnerup``: instead
of KG, the gait of largest posterior mean but the buffered one).  Results: ``docs/learning.md``.

    python benchmarks/screen_kg.py --objectives 100 "kg_from=1000" "kg_from=20" "kg_from=20,star=1"
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np
from joblib import Parallel, delayed
from scipy.stats import norm
from screen_gates import summary, walk
from study_learning import STUDY_SEED, config_text

from gaitpref.config import parse_config
from gaitpref.data import paper_objectives
from gaitpref.model.posterior import random_argmax
from gaitpref.strategies.base import AskContext
from gaitpref.strategies.hybrid import GatedEubo


def knowledge_gradient(
    mu: np.ndarray, cov: np.ndarray, b: int, cands: np.ndarray, noise: float
) -> np.ndarray:
    """KG of comparing each candidate with ``b`` (module docstring)."""
    cols = cov[:, cands] - cov[:, [b]]  # cov(g, d_x), A x c
    var_d = np.maximum(cov[cands, cands] + cov[b, b] - 2.0 * cov[cands, b], 1e-300)
    mean_d = mu[cands] - mu[b]
    c = np.sqrt(2.0 * noise**2 + var_d)
    best = mu.max()
    out = np.zeros(cands.size)
    for y in (1.0, -1.0):
        z = y * mean_d / c
        p = norm.cdf(z)
        ratio = np.exp(norm.logpdf(z) - norm.logcdf(z))  # phi / Phi, stable in the tail
        moved = mu[:, None] + cols * (y * ratio / c)[None, :]
        out += p * moved.max(axis=0)
    return out - best


class KgGated:
    name = "screen-kg"

    def __init__(
        self, kg_from: int, cands: int, noise: float, early: float, gate: bool, star: bool
    ) -> None:
        self.kg_from, self.cands, self.noise, self.gate = kg_from, cands, noise, gate
        self.star = star
        self.late = "kg"
        self.eubo = GatedEubo(early_scale=early, early_trials=20)

    def propose(self, context: AskContext) -> tuple[int, ...]:
        if context.trial < self.kg_from or not context.buffer:
            return self.eubo.propose(context)
        post, rng, b = context.posterior, context.rng, context.buffer[0]
        if self.gate:
            pick = int(post.argmax_samples(rng, 1, context.allowed)[0])
            if pick == b:
                return (b,)
        mu = np.asarray(post.mean)
        if self.late == "runnerup":  # the best mean but the buffered gait's
            values = mu.copy()
            values[b] = -np.inf
            return (random_argmax(values, rng),)
        cov = post.covariance()
        sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
        ucb = mu + 2.0 * sd
        ucb[b] = -np.inf
        cands = np.argsort(-ucb)[: self.cands]
        kg = knowledge_gradient(mu, cov, b, cands, self.noise)
        if self.star:  # KG*: the best value per answer of the comparison answered k times
            for k in (2, 4, 8, 16, 32, 64):
                kg = np.maximum(
                    kg, knowledge_gradient(mu, cov, b, cands, self.noise / np.sqrt(k)) / k
                )
        if kg.max() <= 1e-12 * float(np.sqrt(post.kernel.variance)):
            return self.eubo.propose(context)
        return (int(cands[random_argmax(kg, rng)]),)


def one_run(variant: dict[str, str], k: int) -> dict[str, Any]:
    text = config_text("gated-eubo", 'ties = "drop"\nfit = "fixed"', float(variant.get("ls", 0.15)))
    cfg = parse_config(text)
    objective = paper_objectives()[k]
    loop_seed, user_seed = np.random.SeedSequence([STUDY_SEED, k]).spawn(2)
    loop = cfg.make_loop(seed=np.random.default_rng(loop_seed))
    loop.strategy = KgGated(
        int(variant.get("kg_from", 20)), int(variant.get("cands", 100)), loop.gp.noise,
        float(variant.get("early", 0.5)), variant.get("gate", "1") == "1",
        variant.get("star", "0") == "1",
    )  # fmt: skip
    loop.strategy.late = variant.get("late", "kg")
    return walk(loop, cfg.space, variant, objective, user_seed, k)[0]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("variants", nargs="+")
    parser.add_argument("--objectives", type=int, default=100)
    parser.add_argument("--first", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("out/screen-kg.jsonl"))
    args = parser.parse_args()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    for text in args.variants:
        variant = dict(kv.split("=", 1) for kv in text.split(",") if kv)
        runs = Parallel(n_jobs=args.jobs)(
            delayed(one_run)(variant, k) for k in range(args.first, args.first + args.objectives)
        )
        print(f"{text}: {summary(runs)}", flush=True)
        with args.out.open("a") as fh:
            fh.write(json.dumps({"variant": text, "runs": runs}) + "\n")


if __name__ == "__main__":
    main()
