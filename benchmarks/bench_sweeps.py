"""Speed of the paper's full Fig. 4 study: 6 settings (+ random) x 100 objectives x 150 trials.

Target (issue 3): under 10 minutes on one 2-core machine with ``jobs = 2``; the authors' code
needs 500-600 s per run here, about 100 hours for the 600 runs.  Records wall time, runs per
second and the load average (a shared machine) in ``results/sweeps.{json,md}``.

    python benchmarks/bench_sweeps.py [--runs 100] [--jobs 2] [--backend joblib|ray]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from _machine import machine_description, machine_markdown

from gaitpref.simulate.paper2d import paper_2d_study
from gaitpref.simulate.sweep import run_study

TARGET_S = 600.0
RESULTS = Path(__file__).parent / "results"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--backend", choices=("joblib", "ray"), default="joblib")
    args = parser.parse_args()
    study = paper_2d_study(runs=args.runs)
    load_before = os.getloadavg()
    result = run_study(study, backend=args.backend, jobs=args.jobs, progress=True)
    load_after = os.getloadavg()
    record = {
        "study": f"paper-2d: {len(study.settings) - 1} settings + random x {args.runs} runs "
        "x 150 trials",
        "runs": len(study),
        "backend": result.backend,
        "jobs": result.jobs,
        "wall_s": round(result.seconds, 1),
        "runs_per_s": round(len(study) / result.seconds, 2),
        "target_s": TARGET_S,
        "meets_target": bool(result.seconds <= TARGET_S * args.runs / 100),
        "load_before": [round(v, 2) for v in load_before],
        "load_after": [round(v, 2) for v in load_after],
        "machine": machine_description(),
    }
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "sweeps.json").write_text(json.dumps(record, indent=2) + "\n")
    (RESULTS / "sweeps.md").write_text(
        "# Sweep speed: the paper's full Fig. 4 study\n\n"
        "`python benchmarks/bench_sweeps.py` (the same study as `gaitpref bench paper-2d`).\n"
        f"Target: under {TARGET_S:.0f} s for 6 settings x 100 runs x 150 trials on 2 cores.\n\n"
        f"- {record['study']}: {record['runs']} runs\n"
        f"- backend `{result.backend}`, {result.jobs} jobs: **{record['wall_s']} s** "
        f"({record['runs_per_s']} runs/s), target met: {record['meets_target']}\n"
        f"- load average before {record['load_before']}, after {record['load_after']} "
        "(1/5/15 min; a shared machine)\n\nMachine:\n\n"
        + machine_markdown(record["machine"])  # type: ignore[arg-type]
        + "\n"
    )
    print(json.dumps(record))
    return 0 if record["meets_target"] else 1


if __name__ == "__main__":
    sys.exit(main())
