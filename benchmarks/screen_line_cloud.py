"""Issue 13 screen: a cloud of points around the best point besides the star of lines, on the
12-D random-GP cells without coactive feedback (noiseless, then noisy), to trial 60.

The line path's default arm (gated EUBO, lengthscales fitted, four lines of 50 points), with the
study's seeds and settings (``study_continuous.one_run``); ``cloud`` patches ``draw_line`` to add
``PER`` points at each of ``SCALES`` (Gaussian steps in normalised coordinates around the line's
origin, clipped to the box) from the query's second query on: the screen that preceded
``[cospar] line_cloud`` (which draws its cloud from the line's own seed, and on the first query
too).  Prints the best@60 fraction of each seed.

    python benchmarks/screen_line_cloud.py base
    python benchmarks/screen_line_cloud.py cloud 0.05,0.1,0.2 60 [FIRST_SEED [LINES [SEEDS]]]
"""

from __future__ import annotations

import dataclasses

import numpy as np
import study_continuous as sc
from _usage import positional

import gaitpref.loop.line as line_mod
from gaitpref.loop import lines as line_geometry

sc.TRIALS = 60
real = line_mod.draw_line
ARGS = positional(__doc__, 1, 6)
if ARGS[0] not in ("base", "cloud"):
    raise SystemExit(f"screen_line_cloud.py: {ARGS[0]!r}: the variant is base or cloud")
SCALES = [float(x) for x in ARGS[1].split(",")] if len(ARGS) > 1 else [0.05, 0.1, 0.2]
PER = int(ARGS[2]) if len(ARGS) > 2 else 60
FIRST = int(ARGS[3]) if len(ARGS) > 3 else 0
LINES = int(ARGS[4]) if len(ARGS) > 4 else 4
SEEDS = int(ARGS[5]) if len(ARGS) > 5 else 12


def cloud(space, settings, seed, origin, towards=None):
    ln = real(space, settings, seed, origin, towards)
    if origin is None:
        return ln
    rng = np.random.default_rng([seed, 7])
    lo, span = line_geometry._spans(space)
    u0 = (np.asarray(origin) - lo) / span
    pts = [np.clip(u0 + rng.normal(0, s, (PER, space.ndim)), 0, 1) for s in SCALES]
    raw = lo + np.vstack(pts) * span
    pts = line_geometry._distinct(np.vstack([ln.points, raw]))
    pts.setflags(write=False)
    return dataclasses.replace(ln, points=pts)


variant = ARGS[0]
if variant == "cloud":
    line_mod.draw_line = cloud
for noise in (0.0, 0.2):
    fr = []
    for seed in range(FIRST, FIRST + SEEDS):
        r = sc.one_run(
            "line", "random-gp", 12, False, noise, seed, None, "gated-eubo", "evidence", LINES, 50
        )
        v = r["best_at"]["60"]
        fr.append((v - r["random_mean"]) / (r["optimum"] - r["random_mean"]))
    fr = np.array(fr)
    print(
        variant,
        SCALES,
        PER,
        noise,
        round(fr.mean(), 3),
        round(fr.std(ddof=1) / np.sqrt(SEEDS), 3),
        np.round(fr, 3).tolist(),
        flush=True,
    )
