"""Issue 13 screen: what makes the line path learn faster in 8-D and 12-D without coactive feedback.

A cheap screen before the full study (``study_continuous.py``): the cells whose best@60 target
was not met plus guard cells, few seeds, the first 60 trials only; each variant is one setting
for every cell (strategy along the line, line direction, points per line, kernel lengthscale,
hyperparameter fit, model noise).  Prints, per variant, every cell's best@60 fraction (mean ±
standard error over seeds) and appends the runs to ``--out`` (JSON lines).

    python benchmarks/screen_lines.py --seeds 3 "strategy=gated-eubo" "direction=coordinate" ...

A variant is ``key=value`` pairs joined by ``,``: ``strategy`` (a strategy's name),
``direction`` (random, coordinate; ``descent``: along the posterior mean's gradient at the
best point, ``descent:0.5``: half of the lines random instead; ``thompson``: towards the
argmax of one posterior sample over 1,000 uniform points, ``thompson:M`` over ``M``; screen
only, the library has no such rules), ``points`` (per line), ``scale`` (``study``: the
study's kernel; a number: that fraction of the range for every feature), ``fit`` (fixed,
evidence), ``noise`` (the model's probit noise), ``span`` (below 1: each line cut to the
segment ``|t| <= span`` around the best point, in range-normalised units, a trust region; the
screen patches
``gaitpref.loop.lines.line_points`` for it, the library has no such setting), ``early``
(gated-eubo's ``early_scale``: a local challenger during the first 20 trials; 1: off),
``burst`` (gated-eubo's exploration burst, ``FROM-UNTIL``: self-sparring for the trials after
the first ``FROM`` up to trial ``UNTIL``, defaults 0.9's ``20-45``; ``0``: off), ``star``
(``LineSettings.lines``, ``[cospar] line_count``: lines per query, all through the best point,
the strategy choosing among all their points; the key's ``1`` is LineCoSpar's one line, a
config's default since defaults 0.10 is 4).
Results: ``docs/results/continuous/notes.md``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

import gaitpref.loop.lines as _lines
from gaitpref import SquaredExponential
from gaitpref.loop.learning import Learning
from gaitpref.loop.line import LineCoSpar, on_points
from gaitpref.loop.lines import LineSettings
from gaitpref.simulate.continuous import (
    HARTMANN6_MAX,
    builtin,
    estimate_optimum,
    random_gp_lengthscale,
)
from gaitpref.simulate.points import PointCoactive, PointUser, random_curve, run_points
from gaitpref.space import FloatArray
from gaitpref.strategies import make_strategy

TRIALS = 60
FAILING = [
    ("hartmann6", 12, False, 0.0),
    ("hartmann6", 12, False, 0.2),
    ("random-gp", 8, False, 0.0),
    ("random-gp", 8, False, 0.2),
    ("random-gp", 12, False, 0.0),
    ("random-gp", 12, False, 0.2),
]
GUARDS = [("hartmann6", 8, False, 0.2), ("random-gp", 12, True, 0.0)]
BASE = {
    "strategy": "self-sparring",
    "direction": "random",
    "points": "50",
    "scale": "study",
    "fit": "fixed",
    "noise": "0.05",
    "span": "1",
    "early": "1",
    "burst": "0",
    "star": "1",
}
_OPTIMA: dict[tuple[str, int, int], tuple[float, float]] = {}


def _gated_settings(early: str, burst: str = "0") -> dict[str, float]:
    """gated-eubo's ``early_scale`` (``early=0.5``; ``1``: the strategy's own settings) and
    exploration burst (``burst=20-45``; ``0``: off)."""
    out: dict[str, float] = {} if float(early) == 1.0 else {"early_scale": float(early)}
    if burst != "0":
        start, end = (int(v) for v in burst.split("-"))
        out |= {"sparring_from": start, "sparring_until": end}
    return out


def parse(spec: str) -> dict[str, str]:
    out = dict(BASE)
    for part in filter(None, spec.split(",")):
        key, value = part.split("=")
        if key not in BASE:
            raise ValueError(f"unknown variant key {key!r} (keys: {', '.join(BASE)})")
        out[key] = value
    return out


_ORIGINAL = _lines.line_points


def _spanned(span: float) -> None:
    """Screen only: lines cut to ``|t| <= span`` (normalised units) around the best point."""
    original = _ORIGINAL

    def cut(space: Any, origin: Any, v: Any, count: int) -> Any:
        lo, full = _lines._spans(space)
        u0 = (origin - lo) / np.where(full > 0, full, 1.0)
        pts = original(space, origin, v, count * 8)
        t = ((pts - lo) / np.where(full > 0, full, 1.0) - u0) @ v
        keep = np.abs(t) <= span + 1e-12
        sel = pts[keep]
        idx = np.unique(np.round(np.linspace(0, len(sel) - 1, count)).astype(int))
        out = sel[idx]
        if not np.any(np.all(out == origin, axis=1)):
            out = np.vstack([out, origin])
        return out

    _lines.line_points = cut if span < 1 else original


class ThompsonLines(LineCoSpar):
    """Screen only: lines from the best point towards the argmax of one posterior sample over
    ``candidates`` points drawn uniformly in the box (and the table's points), a Thompson draw
    of where the optimum lies; the candidates and the sample come from the loop's generator."""

    candidates: int = 1000

    def _towards(self) -> FloatArray | None:
        best = self.best_point()
        if best is None:
            return None
        draws = [_lines.random_point(self.domain, self.rng) for _ in range(self.candidates)]
        cloud = np.array(draws)
        space, _ = self.space.extended(cloud)
        post = on_points(self.posterior, space)
        target = space.points[int(post.argmax_samples(self.rng, 1)[0])]
        move = _lines.normalised(self.domain, target - best)
        return None if not np.any(move) else move


class DescentLines(LineCoSpar):
    """Screen only: lines along the posterior mean's gradient at the best point (LineBO's
    DescentLineBO, Kirschner et al. 2019), by central differences in normalised units; with
    ``mix`` > 0, that share of the lines random instead (drawn from the loop's generator)."""

    mix: float = 0.0

    def _towards(self) -> FloatArray | None:
        best = self.best_point()
        if best is None:
            return None
        if self.mix > 0 and self.rng.random() < self.mix:
            return None  # "coactive" direction without a target: a random one
        lo, span = _lines._spans(self.domain)
        h = 1e-3
        ups = np.minimum(best[None, :] + h * np.diag(span), lo + span)
        downs = np.maximum(best[None, :] - h * np.diag(span), lo)
        space, ids = self.space.extended(np.vstack([ups, downs]))
        mean = np.asarray(on_points(self.posterior, space).mean)
        d = best.size
        width = np.diag(ups - downs) / np.where(span > 0, span, 1.0)
        grad = (mean[ids[:d]] - mean[ids[d:]]) / np.where(width > 0, width, 1.0)
        return None if not np.any(grad) else grad


def one(variant: dict[str, str], cell: tuple[str, int, bool, float], seed: int) -> float:
    from study_continuous import box

    objective, d, coactive, noise = cell
    domain = box(d)
    fn = builtin(objective, domain, seed)
    key = (objective, d, seed)
    if key not in _OPTIMA:
        opt = HARTMANN6_MAX if objective == "hartmann6" else estimate_optimum(fn, domain, seed)[1]
        rand = random_curve(fn, domain, 4000, np.random.default_rng(10_000 + seed))
        _OPTIMA[key] = (float(opt), float(rand.mean()))
    optimum, random_mean = _OPTIMA[key]
    if variant["scale"] == "study":
        scale = 0.25 if objective == "hartmann6" else random_gp_lengthscale(d)
    else:
        scale = float(variant["scale"])
    _spanned(float(variant["span"]))
    loop_seed, user_seed = np.random.SeedSequence(seed).spawn(2)
    descent = variant["direction"].startswith("descent")
    thompson = variant["direction"].startswith("thompson")
    direction = "coactive" if descent or thompson else variant["direction"]
    cls = DescentLines if descent else ThompsonLines if thompson else LineCoSpar
    loop = cls(
        domain,
        SquaredExponential(scale, 1.0, 1e-6),
        float(variant["noise"]),
        n=1,
        buffer=1,
        seed=np.random.default_rng(loop_seed),
        strategy=make_strategy(
            variant["strategy"], **_gated_settings(variant["early"], variant["burst"])
        ),
        learning=Learning(fit=variant["fit"]),  # type: ignore[arg-type]
        line=LineSettings(int(variant["points"]), direction, int(variant["star"])),  # type: ignore[arg-type]
    )
    if descent and ":" in variant["direction"]:
        loop.mix = float(variant["direction"].split(":")[1])  # type: ignore[attr-defined]
    if thompson and ":" in variant["direction"]:
        loop.candidates = int(variant["direction"].split(":")[1])  # type: ignore[attr-defined]
    user = PointUser(fn, np.random.default_rng(user_seed), noise)
    helper = PointCoactive(fn, domain, seed=seed) if coactive else None
    res = run_points(loop, fn, user, TRIALS, helper, checkpoints=(TRIALS,))
    return (res.best_at[TRIALS] - random_mean) / (optimum - random_mean)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("variants", nargs="+")
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("/tmp/screen_lines.jsonl"))
    args = parser.parse_args()
    for spec in args.variants:
        variant = parse(spec)
        start = time.perf_counter()
        row: dict[str, Any] = {"variant": variant, "spec": spec, "cells": {}}
        parts = []
        for cell in FAILING + GUARDS:
            seeds = range(args.first_seed, args.first_seed + args.seeds)
            fr = [one(variant, cell, s) for s in seeds]
            name = f"{cell[0][:2]}{cell[1]}{'co' if cell[2] else ''}{'n' if cell[3] else ''}"
            row["cells"][name] = fr
            a = np.array(fr)
            parts.append(f"{name} {a.mean():.2f}±{a.std(ddof=1) / np.sqrt(a.size):.2f}")
        fail_mean = np.mean([np.mean(v) for v in list(row["cells"].values())[: len(FAILING)]])
        row["seconds"] = time.perf_counter() - start
        row["seeds"] = list(seeds)
        print(
            f"{spec or 'base':55s} failing-mean {fail_mean:.3f} | {' '.join(parts)} "
            f"[{row['seconds']:.0f}s]",
            flush=True,
        )
        with args.out.open("a") as fh:
            fh.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    main()
