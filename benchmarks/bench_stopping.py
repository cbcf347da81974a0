"""The session's confidence after an answer: its time on three grids, before and after the budget,
and with BLAS's default threads against the one thread it runs on.

Every confidence sample is a joint posterior draw over every gait, so its time grows with
``samples x gaits``.  For the paper's 30 x 30 grid (``synthetic-2d``), the shipped 57,750-gait
``synthetic-6d`` grid and a 32^4 = 1,048,576-gait grid (``bench_large.py``'s ``4d`` case), a
posterior of 150 random comparisons; after one warm-up draw, timed: the confidence with
``[stop] samples = 2000`` as every session read it before the budget (on the 2**20 grid 100
samples, scaled by 20: 2000 would take minutes), and with the count a session reads now
(``StopRule().samples_for(gaits)``: at most ``CONFIDENCE_VALUES`` sampled values, at least 100
samples), that count both as shipped (one BLAS thread, ``loop/stopping.py``'s
``one_blas_thread``) and with the limit lifted (``one_blas_thread`` replaced by a no-op, so BLAS
uses its default threads, as the confidence did before commit d46c2f3): ``--repeats`` runs of
each, alternating so that load from other work hits both alike, their median.  A session states
the confidence after every answer (terminal, console) and an export once per answer, undo and
exclusion.

    python benchmarks/bench_stopping.py [--repeats 3]

Writes benchmarks/results/stopping.md.
"""

from __future__ import annotations

import argparse
import contextlib
import time
from pathlib import Path

import numpy as np
from _machine import machine_footer
from bench_large import _case

import gaitpref.loop.stopping as stopping
from gaitpref import load_config
from gaitpref.loop.stopping import CONFIDENCE_VALUES, StopRule, confidence
from gaitpref.model import PreferenceGP
from gaitpref.simulate.report import load_average

RESULT = Path(__file__).parent / "results" / "stopping.md"
COMPARISONS = 150
SCALED = 100  # samples timed (then scaled to 2000) where 2000 would take minutes


#: The run before the confidence was held to one BLAS thread (a record, not measured here).
PREVIOUS = [
    "Before (default BLAS threads): the run of commit 1deed69 on the same kind of machine "
    "(2 cores, AMD EPYC, load 0.79), one run each: 2000 samples took 0.40 s, 7.47 s and "
    "114.48 s (100 samples x 20) on the three grids, the count read now 0.28 s, 1.04 s and "
    "5.90 s.  Runs at another load compare poorly: the last two columns above compare both "
    "settings in one run.",
]


def _timed(post: object, samples: int, *, lifted: bool = False) -> float:
    shipped = stopping.one_blas_thread
    if lifted:  # BLAS's default threads, as before d46c2f3
        stopping.one_blas_thread = contextlib.nullcontext  # type: ignore[assignment]
    try:
        start = time.perf_counter()
        confidence(post, np.random.default_rng(1), samples=samples)  # type: ignore[arg-type]
        return time.perf_counter() - start
    finally:
        stopping.one_blas_thread = shipped


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--repeats", type=int, default=3, help="runs of each thread setting")
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    started, load_before = time.perf_counter(), load_average()[0]
    cfg = load_config("synthetic-2d")
    cases = [("30 x 30 (synthetic-2d)", cfg.space, cfg.kernel, cfg.noise)]
    cases += [(label, *_case(name)) for label, name in (("synthetic-6d", "6d"), ("32^4", "4d"))]
    rows = []
    for label, space, kernel, noise in cases:
        gaits = len(space)
        rng = np.random.default_rng(0)
        pairs = np.array([rng.choice(gaits, 2, replace=False) for _ in range(COMPARISONS)])
        post = PreferenceGP(space, kernel, noise).posterior(pairs[:, 0], pairs[:, 1])
        now = StopRule().samples_for(gaits)
        _timed(post, 1)  # the first draw builds what every later one reuses
        before = _timed(post, 2000) if gaits < 500_000 else _timed(post, SCALED) * 2000 / SCALED
        lifted, one = [], []
        for _ in range(args.repeats):
            lifted.append(_timed(post, now, lifted=True))
            one.append(_timed(post, now))
        row = (label, gaits, before, gaits >= 500_000, now, lifted, one)
        rows.append(row)
        print(label, f"{before:.2f} s", now, lifted, one, flush=True)
    lines = [
        "# The confidence after an answer (`[stop] samples`)",
        "",
        f"`python benchmarks/bench_stopping.py --repeats {args.repeats}` - one confidence of a "
        f"posterior of {COMPARISONS} random comparisons; wall clock after one warm-up draw.  "
        f"Budget: {CONFIDENCE_VALUES:,} sampled values (`CONFIDENCE_VALUES`), at least 100 "
        "samples.  2000 samples (before the budget): one run, on one BLAS thread as the "
        "confidence runs now.  The count a session reads now: the median of "
        f"{args.repeats} runs with BLAS's default threads (the confidence before commit "
        f"d46c2f3) and of {args.repeats} on one BLAS thread (now), alternating (all runs in "
        "brackets).",
        "",
        "| grid | gaits | 2000 samples (before the budget) | samples now | "
        "default BLAS threads (before) | one BLAS thread (now) |",
        "|---|---|---|---|---|---|",
    ]
    for label, gaits, before, scaled, now, lifted, one in rows:
        mark = f" ({SCALED} samples x 20)" if scaled else ""
        runs = [f"{np.median(t):.3f} s ({', '.join(f'{x:.3f}' for x in t)})" for t in (lifted, one)]
        lines.append(
            f"| {label} | {gaits:,} | {before:.2f} s{mark} | {now} | {runs[0]} | {runs[1]} |"
        )
    lines += [
        "",
        *PREVIOUS,
        *machine_footer("Whole benchmark", time.perf_counter() - started, load_before),
    ]
    RESULT.write_text("\n".join(lines), encoding="utf-8")


if __name__ == "__main__":
    main()
