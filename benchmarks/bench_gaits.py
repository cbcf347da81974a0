"""Gait-generation benchmark: the paper's COT sweep and gait library, timed and verified.

1. 15 step lengths in [0.08, 0.18] m at 0.2 m/s (one warm-started chain; target < 20 s), each gait
   then checked on the full hybrid model (5 steps from its orbit);
2. the 15 x 10 library over step length x step duration in [0.85, 1.15] s (target < 3 min on 2
   cores, all gaits feasible).

Results, with the machine's description, go to ``benchmarks/results/gaits.md``; ``--figures DIR``
also renders the documentation figures.  Run: ``.venv/bin/python benchmarks/bench_gaits.py``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

try:
    from _machine import machine_description, machine_markdown
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown
from gaitpref.gaits import build_library, cot_over_step_length, simulate_gait
from gaitpref.gaits.figures import default_ids, render_library_figure

LENGTHS = np.linspace(0.08, 0.18, 15)
DURATIONS = np.linspace(0.85, 1.15, 10)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=2, help="processes for the 15 x 10 library")
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/gaits.md"))
    parser.add_argument("--figures", type=Path, default=None, help="also write figures here")
    args = parser.parse_args()
    lines = ["# Gait generation benchmark", "", machine_markdown(machine_description()), ""]

    t0 = time.perf_counter()
    sweep = build_library(LENGTHS, speed=0.2, n_jobs=1)
    t_sweep = time.perf_counter() - t0
    curve = cot_over_step_length(sweep)
    t0 = time.perf_counter()
    sims = [simulate_gait(g, sweep.params, steps=5) for g in sweep.gaits if g.feasible]
    t_sim = time.perf_counter() - t0
    lines += [
        "## COT over step length at 0.2 m/s (15 gaits, one process, warm-started chain)",
        "",
        f"- time: **{t_sweep:.2f} s** ({t_sweep / len(sweep):.3f} s per gait; target < 20 s)",
        f"- feasible: **{int(curve.feasible.sum())} / {len(sweep)}**",
        f"- least COT {np.nanmin(curve.cot):.5f} at {curve.best_step_length:.4f} m "
        "(U-shaped: interior minimum)",
        f"- full-model check (5 steps from each orbit, {t_sim:.1f} s): max orbit error after 5 "
        f"steps {max(s.orbit_error[-1] for s in sims):.1e}, all returned: "
        f"{all(s.returned_to_orbit for s in sims)}; min normal force "
        f"{min(s.min_normal_force for s in sims):.1f} N (weight "
        f"{sweep.params.total_mass * sweep.params.gravity:.1f} N); max friction ratio "
        f"{max(s.max_friction_ratio for s in sims):.3f}; lowest late swing-foot height "
        f"{min(s.min_late_swing_height for s in sims):.1e} m",
        "",
        "| step length [m] | COT | step duration [s] | delta^2 |",
        "|---|---|---|---|",
    ]
    for gait in sweep.gaits:
        lines.append(
            f"| {gait.step_length:.4f} | {gait.cot:.5f} | {gait.step_duration:.4f} "
            f"| {gait.delta_squared:.4f} |"
        )

    t0 = time.perf_counter()
    lib = build_library(LENGTHS, step_durations=DURATIONS, n_jobs=args.jobs)
    t_lib = time.perf_counter() - t0
    cot = lib.cot_grid()
    lines += [
        "",
        f"## Library: 15 step lengths x 10 step durations ({args.jobs} processes)",
        "",
        f"- time: **{t_lib:.2f} s** ({t_lib / len(lib):.3f} s per gait; target < 180 s)",
        f"- feasible: **{len(lib) - len(lib.infeasible())} / {len(lib)}** (target: all)",
        f"- COT range {np.nanmin(cot):.5f} .. {np.nanmax(cot):.5f}; least at "
        f"{lib.gait_id(int(np.nanargmin(cot)))}",
        "",
    ]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines))
    print("\n".join(lines))
    if args.figures is not None:
        args.figures.mkdir(parents=True, exist_ok=True)
        best = int(np.nanargmin(curve.cot))
        ends = [sweep.gait_id(i) for i in dict.fromkeys((0, best, len(sweep) - 1))]
        render_library_figure(sweep, ends, args.figures / "gaits_cot_speed.png")
        render_library_figure(lib, default_ids(lib), args.figures / "gaits_library.png")
        print(f"figures written to {args.figures}")


if __name__ == "__main__":
    main()
