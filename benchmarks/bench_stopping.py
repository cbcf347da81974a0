"""The session's confidence after an answer: its time on three grids, before and after the budget.

Every confidence sample is a joint posterior draw over every gait, so its time grows with
``samples x gaits``.  For the paper's 30 x 30 grid (``synthetic-2d``), the shipped 57,750-gait
``synthetic-6d`` grid and a 32^4 = 1,048,576-gait grid (``bench_large.py``'s ``4d`` case), a
posterior of 150 random comparisons; after one warm-up draw, timed: the confidence with
``[stop] samples = 2000`` as every session read it before (on the 2**20 grid 100 samples,
scaled by 20: 2000 would take minutes), and with the count a session reads now
(``StopRule().samples_for(gaits)``: at most ``CONFIDENCE_VALUES`` sampled values, at least 100
samples).  A session states this after every
answer (terminal, console) and an export once per answer, undo and exclusion.

    python benchmarks/bench_stopping.py

Writes benchmarks/results/stopping.md.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from _machine import machine_description, machine_markdown
from bench_large import _case

from gaitpref import load_config
from gaitpref.loop.stopping import CONFIDENCE_VALUES, StopRule, confidence
from gaitpref.model import PreferenceGP

RESULT = Path(__file__).parent / "results" / "stopping.md"
COMPARISONS = 150
SCALED = 100  # samples timed (then scaled to 2000) where 2000 would take minutes


def _timed(post: object, samples: int) -> float:
    start = time.perf_counter()
    confidence(post, np.random.default_rng(1), samples=samples)  # type: ignore[arg-type]
    return time.perf_counter() - start


def main() -> None:
    # no options: --help shows the docstring, anything else is refused before the timing
    argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    ).parse_args()
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
        after = _timed(post, now)
        rows.append((label, gaits, before, gaits >= 500_000, now, after))
        print(label, f"{before:.2f} s", now, f"{after:.2f} s", flush=True)
    lines = [
        "# The confidence after an answer (`[stop] samples`)",
        "",
        "`python benchmarks/bench_stopping.py` - one confidence of a posterior of "
        f"{COMPARISONS} random comparisons; wall clock, one run each, after one warm-up draw.  "
        f"Budget: {CONFIDENCE_VALUES:,} sampled values (`CONFIDENCE_VALUES`), at least 100 "
        "samples.",
        "",
        "| grid | gaits | 2000 samples (before) | samples now | now |",
        "|---|---|---|---|---|",
    ]
    for label, gaits, before, scaled, now, after in rows:
        mark = f" ({SCALED} samples x 20)" if scaled else ""
        lines.append(f"| {label} | {gaits:,} | {before:.2f} s{mark} | {now} | {after:.2f} s |")
    lines += ["", "Machine:", "", machine_markdown(machine_description()), ""]
    RESULT.write_text("\n".join(lines), encoding="utf-8")


if __name__ == "__main__":
    main()
