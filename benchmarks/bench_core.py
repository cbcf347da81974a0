"""Speed of the CoSpar loop on the paper's synthetic 2-D benchmark (30 x 30 grid).

Times every iteration (ask + simulated answer + coactive suggestion + tell) over full 150-trial
runs of the synthetic-2d config (n = 1, b = 1, coactive; and n = 2, b = 0) on the authors'
objectives, and the wall time of each whole run.  Targets (issue 2): median iteration <= 5 ms over
trials 100-150, one 150-trial run <= 1.5 s on a 2-core machine.

    python benchmarks/bench_core.py [--runs 10]

Writes benchmarks/results/core.md and core.json.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from gaitpref import GradientCoactive, SimulatedUser, load_config
from gaitpref.data import paper_objectives

try:
    from _machine import machine_description, machine_markdown
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown

RESULTS = Path(__file__).parent / "results"


def one_run(n: int, b: int, coactive: bool, k: int, trials: int = 150) -> tuple[list, float]:
    cfg = load_config("synthetic-2d")
    objective = paper_objectives()[k]
    loop = cfg.make_loop(seed=k)
    loop.n, loop.buffer_size = n, b
    user = SimulatedUser(cfg.space, objective, np.random.default_rng(k))
    helper = GradientCoactive(cfg.space, objective) if coactive else None
    per_iteration = []  # (trials done after the iteration, seconds)
    done = 0
    start = time.perf_counter()
    while done < trials:
        t0 = time.perf_counter()
        q = loop.ask()
        comps = user.answer(q)
        suggs = helper.suggest_all(q.actions) if helper else []
        loop.tell(q, comps, suggs)
        done += len(q.actions)
        per_iteration.append((done, time.perf_counter() - t0))
    return per_iteration, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10)
    args = parser.parse_args()
    one_run(1, 1, True, 99, trials=10)  # warm-up (imports, caches)
    settings = {"n1_b1_coactive": (1, 1, True), "n2_b0": (2, 0, False)}
    results: dict[str, dict[str, float]] = {}
    for name, (n, b, co) in settings.items():
        late, run_times = [], []
        for k in range(args.runs):
            iters, total = one_run(n, b, co, k)
            late += [dt for done, dt in iters if done >= 100]
            run_times.append(total)
        results[name] = {
            "median_iteration_ms_trials_100_150": 1e3 * float(np.median(late)),
            "p95_iteration_ms_trials_100_150": 1e3 * float(np.percentile(late, 95)),
            "median_run_s": float(np.median(run_times)),
            "max_run_s": float(np.max(run_times)),
            "runs": args.runs,
        }
    info = machine_description()
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "core.json").write_text(json.dumps({"machine": info, "results": results}, indent=2))
    lines = [
        "# Core loop speed (30 x 30 synthetic grid, 150 trials)",
        "",
        "`python benchmarks/bench_core.py` - one iteration is ask + simulated answer + tell.",
        "Targets: median iteration <= 5 ms (trials 100-150), one 150-trial run <= 1.5 s.",
        "",
        "| setting | median iteration (ms) | p95 iteration (ms) | median run (s) | max run (s) |",
        "|---|---|---|---|---|",
    ]
    for name, r in results.items():
        lines.append(
            f"| {name} | {r['median_iteration_ms_trials_100_150']:.2f} | "
            f"{r['p95_iteration_ms_trials_100_150']:.2f} | {r['median_run_s']:.3f} | "
            f"{r['max_run_s']:.3f} |"
        )
    lines += [
        "",
        f"{args.runs} runs per setting (objectives 0..{args.runs - 1}).",
        "",
        "Machine:",
        "",
        machine_markdown(info),
        "",
    ]
    (RESULTS / "core.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
