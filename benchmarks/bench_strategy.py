"""Speed of the default strategy's ask + tell late in a session (issue 16: under 5 ms at trial 150).

The learning study's config (``study_learning.config_text``: the paper's 30 x 30 synthetic grid
and kernel, ``n = 1, b = 1``) with no learning keys runs the defaults for new configs
(``gaitpref.config.DEFAULTS``: strategy, lengthscales fitted every 20 answers); the same config
with another ``strategy`` times the other strategies beside it.
Each run answers 150 trials with the paper's simulated subject and coactive suggestions (the
answers are not timed) and times ``ask`` and ``tell`` of trials 141-150 (the refit of trial 140
is outside the window; trial 160's would be the next).

    python benchmarks/bench_strategy.py [--runs 10]

Writes benchmarks/results/strategy.md and strategy.json.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from gaitpref import GradientCoactive, SimulatedUser
from gaitpref.config import DEFAULTS, parse_config
from gaitpref.data import paper_objectives

try:
    from _machine import machine_description, machine_markdown
    from study_learning import config_text
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown
    from benchmarks.study_learning import config_text

RESULTS = Path(__file__).parent / "results"
AVERAGE = 'hyper = "average"'  # issue 16 item 2: lengthscale hypotheses averaged
TRIALS, WINDOW = 150, 10


def one_run(strategy: str | None, k: int, model: str = "") -> list[tuple[float, float, float]]:
    """(ask, tell, ask + tell CPU) seconds of the last ``WINDOW`` trials of one run on objective
    ``k``; the first two are wall-clock time, the third the process's CPU time (one BLAS thread),
    which a loaded shared machine inflates far less.  ``model``: ``[model]`` keys added."""
    cfg = parse_config(config_text(strategy or DEFAULTS["cospar"]["strategy"], model))
    objective = paper_objectives()[k]
    loop = cfg.make_loop(seed=k)
    user = SimulatedUser(cfg.space, objective, np.random.default_rng(k))
    helper = GradientCoactive(cfg.space, objective)
    out = []
    for trial in range(1, TRIALS + 1):
        c0, t0 = time.process_time(), time.perf_counter()
        q = loop.ask()
        c1, t1 = time.process_time(), time.perf_counter()
        comparisons, suggestions = user.answer(q), helper.suggest_all(q.actions)
        c2, t2 = time.process_time(), time.perf_counter()
        loop.tell(q, comparisons, suggestions)
        c3, t3 = time.process_time(), time.perf_counter()
        if trial > TRIALS - WINDOW:
            out.append((t1 - t0, t3 - t2, (c1 - c0) + (c3 - c2)))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10)
    args = parser.parse_args()
    one_run(None, 99)  # warm-up (imports, caches)
    default = DEFAULTS["cospar"]["strategy"]
    arms: dict[str, tuple[str | None, str]] = {f"default ({default})": (None, "")}
    arms.update(
        {s: (s, "") for s in ("plausible-eubo", "gated-eubo", "self-sparring") if s != default}
    )
    arms["gated-eubo, hyper = average"] = ("gated-eubo", AVERAGE)
    results: dict[str, dict[str, float]] = {}
    for name, (strategy, model) in arms.items():
        times = np.array([t for k in range(args.runs) for t in one_run(strategy, k, model)])
        both = times[:, 0] + times[:, 1]
        results[name] = {
            "median_ask_tell_cpu_ms": 1e3 * float(np.median(times[:, 2])),
            "p95_ask_tell_cpu_ms": 1e3 * float(np.percentile(times[:, 2], 95)),
            "median_ask_ms": 1e3 * float(np.median(times[:, 0])),
            "median_tell_ms": 1e3 * float(np.median(times[:, 1])),
            "median_ask_tell_ms": 1e3 * float(np.median(both)),
            "p95_ask_tell_ms": 1e3 * float(np.percentile(both, 95)),
            "runs": args.runs,
        }
    info = machine_description()
    RESULTS.mkdir(exist_ok=True)
    payload = {"machine": info, "results": results}
    (RESULTS / "strategy.json").write_text(json.dumps(payload, indent=2))
    lines = [
        "# Ask + tell late in a session (30 x 30 synthetic grid, trials 141-150)",
        "",
        "`python benchmarks/bench_strategy.py` - a config with only the space and the model runs",
        "the defaults for new configs (strategy, lengthscales fitted every 20 answers, n = 1,",
        "b = 1); the simulated answers are not timed.  Target (issue 16): the default's ask + tell",
        "under 5 ms at trial 150.",
        "",
        "Wall-clock medians on a loaded machine mostly measure the other processes; the CPU",
        "columns (the process's CPU time, one BLAS thread) are what an idle core would take.",
        "",
        "| strategy | median ask (ms) | median tell (ms) | median ask + tell (ms) | p95 (ms) "
        "| median ask + tell, CPU (ms) | p95, CPU (ms) |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, r in results.items():
        lines.append(
            f"| {name} | {r['median_ask_ms']:.2f} | {r['median_tell_ms']:.2f} | "
            f"{r['median_ask_tell_ms']:.2f} | {r['p95_ask_tell_ms']:.2f} | "
            f"{r['median_ask_tell_cpu_ms']:.2f} | {r['p95_ask_tell_cpu_ms']:.2f} |"
        )
    lines += [
        "",
        f"{args.runs} runs per strategy (objectives 0..{args.runs - 1}), {WINDOW} trials each.",
        "",
        "Machine (2-core shared VM; the load average says how busy it was):",
        "",
        machine_markdown(info),
        "",
    ]
    (RESULTS / "strategy.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
