"""Issue 16 screen: gates and challengers for both phases, on the learning study's runs.

The learning study's setting (``study_learning.py``: the paper's 100 objectives on the 30 x 30
grid, ``n = 1, b = 1``, coactive feedback from the gradient user, 150 trials, its seeds), with
screen-only strategies that the library does not ship, to find what moves trials 1-20, 31-150,
121-150 and the final argmax before building anything.  Each variant is ``key=value`` pairs
joined by ``,``:

- ``strategy``: ``gated`` (the library's ``gated-eubo``), ``sparring`` (``self-sparring``) or
  ``beat`` (below);
- ``halve``: a factor ``c`` (below 1): the EUBO challenger is chosen on the posterior refitted
  with every lengthscale times ``c`` (the loop's ``AskContext.rescaled``; for ``gated`` the
  library's ``early_scale``; the gate, the recommendation and the data stay the configured
  model's); ``halve_until``: only while fewer trials than this were run (``early_trials``);
- ``kappa`` (``beat`` only): with ``r`` the posterior mean's argmax, run ``r`` again unless some
  gait ``x`` has ``P(f_x > f_r) >= kappa`` (from the posterior's mean and covariance); else the
  EUBO challenger (of the buffered gait) among those gaits; ``eps``: with this probability a
  locked loop (no such gait) challenges among the gaits with at least half the largest
  ``P(f_x > f_r)`` instead of repeating; ``delta``: the gate asks for ``P(f_x > f_r + delta
  s) >= kappa`` instead, ``s`` the signal sd of the model then (fitted with ``fit=variance``);
  ``probe``: after this many repeats in a row, challenge as ``eps`` does, once;
- ``noise``: the model's probit noise (the study's config: 0.01, signal sd 0.01);
  ``ls``: the configured lengthscale (the study's "right" one: 0.15);
  ``fit=variance``: the signal variance fitted by the evidence every 20 answers (prior median
  1e-4, log-sd 3), the lengthscales fixed;
- ``subject``: ``noiseless`` or ``noisy`` (the study's indifferent subject);
  ``cw``: the coactive weight (suggestions enter with noise ``noise / cw``; the study's: 1);
- ``exact=1``: also the final argmax of the *exact* posterior mean of the same model and answers
  (``check_confidence_exact.py``'s sampler, 1000 draws), to tell the Laplace approximation's
  error from the model's.

    python benchmarks/screen_gates.py --objectives 100 "strategy=beat,kappa=0.08,noise=0.003"

Prints each variant's means (standard errors over objectives) and appends its runs to ``--out``
(JSON lines).  Results: ``docs/learning.md`` ("Gates that exploit a sharp posterior").
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np
from check_confidence_exact import answers_of, slice_sample_visited, smooth_given_visited
from joblib import Parallel, delayed
from scipy.stats import norm
from study_learning import BAND, NOISE, STUDY_SEED, TRIALS, config_text

from gaitpref.config import parse_config
from gaitpref.data import paper_objectives
from gaitpref.model.posterior import random_argmax
from gaitpref.simulate.noisy import IndifferentUser
from gaitpref.simulate.users import GradientCoactive, SimulatedUser
from gaitpref.strategies.base import AskContext, SelfSparring
from gaitpref.strategies.eubo import covariance_with, eubo_against
from gaitpref.strategies.hybrid import GatedEubo

VARIANCE_FIT = 'fit = "evidence"\nrefit_every = 20\n[model.prior]\nsignal_variance = [1e-4, 3.0]'


def parse_variant(text: str) -> dict[str, str]:
    out = dict(kv.split("=", 1) for kv in text.split(",") if kv)
    unknown = set(out) - {
        "strategy", "halve", "halve_until", "kappa", "eps", "noise", "ls", "fit", "subject", "cw",
        "delta", "probe", "exact",
    }  # fmt: skip
    if unknown:
        raise SystemExit(f"unknown keys {sorted(unknown)} in {text!r}")
    return out


class Beat:
    """Run the recommendation again unless a gait may beat it (``kappa``; module docstring)."""

    name = "screen-beat"

    def __init__(
        self, kappa: float, eps: float, halve: float, until: int, delta: float = 0.0,
        probe: int = 0,
    ) -> None:  # fmt: skip
        self.kappa, self.eps, self.halve, self.until = kappa, eps, halve, until
        self.delta, self.probe, self.locked = delta, probe, 0

    def propose(self, context: AskContext) -> tuple[int, ...]:
        post, rng = context.posterior, context.rng
        if not context.buffer:
            return (int(post.argmax_samples(rng, 1, context.allowed)[0]),)
        mu, var = np.asarray(post.mean), np.asarray(post.variance)
        r, b = int(np.argmax(mu)), context.buffer[0]
        sd = np.sqrt(np.maximum(var + var[r] - 2.0 * covariance_with(post, r), 1e-300))
        margin = self.delta * float(np.sqrt(post.kernel.variance))
        beats = norm.cdf((mu - mu[r] - margin) / sd)
        beats[r] = 0.0
        ok = beats >= self.kappa
        probing = self.probe > 0 and self.locked >= self.probe
        if not ok.any() and (probing or rng.random() < self.eps):
            ok = beats >= beats.max() / 2
        if not ok.any():
            self.locked += 1
            return (r,)
        self.locked = 0
        chooser = post
        if self.halve != 1.0 and context.trial < self.until and context.rescaled is not None:
            chooser = context.rescaled(self.halve)  # the loop's refit, as gated-eubo's early_scale
        values = np.where(ok, eubo_against(chooser, b), -np.inf)
        if b != r:
            values[b] = -np.inf
        if not np.isfinite(values).any():
            return (r,)
        return (random_argmax(values, rng),)


def one_run(variant: dict[str, str], k: int) -> dict[str, Any]:
    fit = VARIANCE_FIT if variant.get("fit") == "variance" else 'fit = "fixed"'
    model = 'ties = "drop"\n' + fit
    text = config_text("gated-eubo", model, float(variant.get("ls", 0.15)))
    text = text.replace("noise = 0.01", f"noise = {float(variant.get('noise', 0.01))}")
    weight = float(variant.get("cw", 1.0))
    cfg = parse_config(text.replace("coactive_weight = 1.0", f"coactive_weight = {weight}"))
    objective = paper_objectives()[k]
    loop_seed, user_seed = np.random.SeedSequence([STUDY_SEED, k]).spawn(2)
    loop = cfg.make_loop(seed=np.random.default_rng(loop_seed))
    halve = float(variant.get("halve", 1.0))
    until = int(variant.get("halve_until", 10**6))
    strategy = variant.get("strategy", "gated")
    if strategy == "beat":
        kappa, eps = float(variant.get("kappa", 0.08)), float(variant.get("eps", 0.0))
        delta, probe = float(variant.get("delta", 0.0)), int(variant.get("probe", 0))
        loop.strategy = Beat(kappa, eps, halve, until, delta, probe)
    elif strategy == "sparring":
        loop.strategy = SelfSparring()
    elif strategy == "gated":  # the library's, with its local challenger early
        loop.strategy = GatedEubo(early_scale=halve, early_trials=until)
    else:
        raise SystemExit(f"unknown strategy {strategy!r}")
    out, user = walk(loop, cfg.space, variant, objective, user_seed, k)
    if variant.get("exact") == "1":
        out["exact_argmax"] = exact_argmax(loop, user, k)
    return out


def walk(
    loop: Any, space: Any, variant: dict[str, str], objective: np.ndarray,
    user_seed: np.random.SeedSequence, k: int,
) -> tuple[dict[str, Any], SimulatedUser]:  # fmt: skip
    """Run ``loop`` for the study's trials with its subject (``variant["subject"]``) and the
    gradient user's coactive suggestions: the executed gaits' scores and the final argmax's
    (normalised), and the subject."""
    rng = np.random.default_rng(user_seed)
    user: SimulatedUser
    if variant.get("subject", "noiseless") == "noisy":
        user = IndifferentUser(space, objective, rng, noise=NOISE, band=BAND)
    else:
        user = SimulatedUser(space, objective, rng)
    coactive = GradientCoactive(space, objective)
    executed: list[int] = []
    repeats = 0
    start = time.perf_counter()
    while len(executed) < TRIALS:
        query = loop.ask()
        repeats += sum(1 for a in query.actions if a in query.buffer)
        loop.tell(query, list(user.answer(query)), coactive.suggest_all(query.actions))
        executed.extend(query.actions)
    scores = user.normalized(np.asarray(executed[:TRIALS], dtype=np.intp))
    out = {
        "objective": k,
        "scores": [float(s) for s in scores],
        "argmax": float(user.normalized([int(loop.posterior.argmax)])[0]),
        "repeats": repeats,
        "seconds": time.perf_counter() - start,
    }
    return out, user


def exact_argmax(loop: Any, user: SimulatedUser, k: int) -> float:
    """The normalised objective at the exact posterior mean's argmax (module docstring)."""
    post = loop.posterior
    winners, losers, sigma = answers_of(loop)
    rng = np.random.default_rng([k, 5])
    f_v = slice_sample_visited(post, winners, losers, sigma, rng, size=1000, burn=300)
    g = smooth_given_visited(post, f_v, rng)
    return float(user.normalized([int(np.argmax(g.mean(axis=0)))])[0])


def summary(runs: list[dict[str, Any]]) -> str:
    scores = np.array([r["scores"] for r in runs])
    cells = {
        "1-20": scores[:, :20].mean(1),
        "31-150": scores[:, 30:].mean(1),
        "121-150": scores[:, 120:].mean(1),
        "argmax": np.array([r["argmax"] for r in runs]),
    }
    se = np.sqrt(len(runs))
    parts = [f"{k} {v.mean():.3f} ({v.std(ddof=1) / se:.3f})" for k, v in cells.items()]
    if "exact_argmax" in runs[0]:
        exact = np.array([r["exact_argmax"] for r in runs])
        diff = exact - cells["argmax"]
        parts.append(
            f"exact argmax {exact.mean():.3f} ({exact.std(ddof=1) / se:.3f}; "
            f"- argmax {diff.mean():+.4f} ± {diff.std(ddof=1) / se:.4f})"
        )
    repeats = np.mean([r["repeats"] for r in runs]) / TRIALS
    return " | ".join(parts) + f" | repeats {repeats:.2f}"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("variants", nargs="+")
    parser.add_argument("--objectives", type=int, default=100)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("out/screen-gates.jsonl"))
    args = parser.parse_args()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    for text in args.variants:
        variant = parse_variant(text)
        runs = Parallel(n_jobs=args.jobs)(
            delayed(one_run)(variant, k) for k in range(args.objectives)
        )
        print(f"{text}: {summary(runs)}", flush=True)
        with args.out.open("a") as fh:
            fh.write(json.dumps({"variant": text, "runs": runs}) + "\n")


if __name__ == "__main__":
    main()
