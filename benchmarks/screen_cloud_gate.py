"""Issue 13 screen: the cloud's points as challengers only, the gate read on the lines.

With ``[cospar] line_cloud = 180`` gated EUBO never repeats the buffered point (a Thompson
sample's argmax among 180 close neighbours is almost never the buffered point itself;
``docs/results/continuous/notes.md``, "The shipped cloud through the whole study"), so a search
that should settle keeps challenging.  This screen keeps the cloud for EUBO's challenger and
reads the gate (the Thompson draws that decide whether to repeat the buffered point) on the
lines' points only, as the default arm does.  It patches the loop: ``draw_line`` records how
many of a query's points are the lines' (the cloud's come after them, as ``draw_line`` stacks
them), ``LineCoSpar._on_line`` the mask of those points, and ``GatedEubo.propose`` reads its
gate on that mask.

The default line arm otherwise (gated EUBO, lengthscales fitted every 20 answers, four lines of
50 points, the study's seeds and subjects, ``study_continuous.one_run``), to trial 60; prints the
best@60 fraction per seed for each cell, to be paired with the recorded default and cloud runs
(``docs/results/continuous/default-lines/results.json`` and ``cloud-180.json``)::

    python benchmarks/screen_cloud_gate.py [SEEDS [CELLS...]]

CELLS are ``objective:d:noise`` (default: the five cells the cloud moved, without coactive
feedback).
"""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import study_continuous as sc
from _usage import positional

import gaitpref.loop.line as line_mod
from gaitpref.strategies import hybrid
from gaitpref.strategies.acquire import eubo_fill

sc.TRIALS = 60
_real_draw = line_mod.draw_line
_real_on_line = line_mod.LineCoSpar._on_line
_state: dict[str, Any] = {"lines": {}, "gate": None}


def _draw(space: Any, settings: Any, seed: int, origin: Any, towards: Any = None) -> Any:
    line = _real_draw(space, settings, seed, origin, towards)
    bare = _real_draw(space, dataclasses.replace(settings, cloud=0), seed, origin, towards)
    _state["lines"][id(line)] = len(bare.points)
    return line


def _on_line(self: Any, line: Any) -> Any:
    space, allowed = _real_on_line(self, line)
    count = _state["lines"].get(id(line), len(line.points))
    _, ids = self.space.extended(line.points[:count])
    gate = np.zeros(len(space), dtype=bool)
    gate[ids] = True
    _state["gate"] = gate & allowed
    return space, allowed


def _propose(self: Any, context: Any) -> tuple[int, ...]:
    mask = _state["gate"]
    if mask is None or len(mask) != len(context.allowed) or not mask.any():
        mask = context.allowed
    picks = [int(a) for a in context.posterior.argmax_samples(context.rng, self.gates, mask)]
    if not context.buffer:
        return eubo_fill(self._chooser(context), picks[:1], None)
    if context.n == 1:
        for pick in picks:
            if pick in context.buffer:
                return (pick,)
    return eubo_fill(self._chooser(context), [], None)


line_mod.draw_line = _draw
line_mod.LineCoSpar._on_line = _on_line  # type: ignore[method-assign]
if not os.environ.get("PLAIN"):  # PLAIN=1: the shipped cloud, to check the patches
    hybrid.GatedEubo.propose = _propose  # type: ignore[method-assign]

ARGS = positional(__doc__, 0)
SEEDS = int(ARGS[0]) if ARGS else 12
CELLS = ARGS[1:] or [
    "random-gp:12:0.0",
    "random-gp:12:0.2",
    "random-gp:8:0.0",
    "random-gp:8:0.2",
    "hartmann6:8:0.2",
]
out: list[dict[str, Any]] = []
for cell in CELLS:
    objective, d, noise = cell.split(":")
    fr = []
    for seed in range(SEEDS):
        r = sc.one_run(
            "line", objective, int(d), False, float(noise), seed, None, "gated-eubo",
            "evidence", 4, 50, 180,
        )  # fmt: skip
        out.append(r)
        v = r["best_at"]["60"]
        fr.append((v - r["random_mean"]) / (r["optimum"] - r["random_mean"]))
    a = np.array(fr)
    print(cell, round(a.mean(), 3), round(a.std(ddof=1) / np.sqrt(SEEDS), 3),
          np.round(a, 3).tolist(), flush=True)  # fmt: skip
Path("/tmp/cloud_gate.json").write_text(json.dumps(out))
