"""The information-gain strategy's speed: ask (the strategy's proposal) and tell, per iteration.

Cases (issue 12, item 4; targets: under 50 ms an iteration on the 30 x 30 grid, under 0.5 s on
the 57,750-gait grid):

- ``2d``: the ``synthetic-2d`` config, 30 x 30 = 900 actions (every allowed action scored);
- ``6d``: the ``synthetic-6d`` config, 57,750 actions, ``sampler = "scalable"`` (candidates
  screened, ``strategies/infogain.py``).

Each with preferences alone, with ordinal ratings (four categories at the objective's quartiles,
``OrdinalRater``), with ratings and a region of avoidance under the single-level rule (``avoid =
1``, ``risk = 0.35``, ``cautious = 0``: ROIAL's mode, information gain over the region of interest;
at each ask the region needs the posterior variance of the gaits its bounds leave undecided,
``loop/safety.py``), and with the region a config gets by default since defaults version 0.4
(``risk = 0.35`` with the cautious level 0.6, ``explore = 1``: it needs the variance of most
unrated gaits). A
simulated user (a smooth GP objective, as ``bench_large.py``) answers CoSpar (n = 1, b = 1, the
strategy ``information-gain`` with its defaults) until the data holds 100 comparisons; the next
``--iterations`` iterations are timed one by one; then on to 300 comparisons and the same again.
Wall time and this process's CPU time are both recorded: the machine is shared, so CPU time is the
steadier figure.

    python benchmarks/bench_infogain.py [--iterations 10] [--cases 2d 6d]

Writes benchmarks/results/infogain.md and infogain.json.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from gaitpref import CoSpar, SimulatedUser, load_config
from gaitpref.loop.safety import Safety, default_risk
from gaitpref.model.ordinal import Ordinal
from gaitpref.simulate.raters import OrdinalRater
from gaitpref.strategies import InformationGain

try:
    from _machine import machine_description, machine_markdown
    from bench_large import gp_objective
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown
    from benchmarks.bench_large import gp_objective

RESULTS = Path(__file__).parent / "results"
CHECKPOINTS = (100, 300)
MODES = ("prefs", "ratings", "ratings + region", "ratings + cautious region")


def run_case(name: str, mode: str, iterations: int) -> list[dict[str, object]]:
    cfg = load_config({"2d": "synthetic-2d", "6d": "synthetic-6d"}[name])
    space, kernel, noise = cfg.space, cfg.kernel, cfg.noise
    rated = mode != "prefs"
    ordinal = Ordinal(["very bad", "bad", "okay", "good"], noise=noise) if rated else None
    region = {
        "ratings + region": Safety(avoid=1, risk=default_risk(1, 4)),
        "ratings + cautious region": Safety(avoid=1, risk=default_risk(1, 4), cautious=0.6),
    }.get(mode)
    loop = CoSpar(
        space,
        kernel,
        noise,
        n=1,
        buffer=1,
        seed=0,
        strategy=InformationGain(),
        sampler="scalable" if name == "6d" else "auto",
        ordinal=ordinal,
        safety=region,
    )
    objective = gp_objective(space, kernel.lengthscales(space.ndim)[0], seed=7)
    user = SimulatedUser(space, objective, np.random.default_rng(1))
    rater = OrdinalRater(space, objective, (0.25, 0.5, 0.75), np.random.default_rng(2))

    def iterate() -> tuple[float, float, float]:
        w0, c0 = time.perf_counter(), time.process_time()
        query = loop.ask()
        w1, c1 = time.perf_counter(), time.process_time()
        answers: list[object] = [*user.answer(query)]
        if rated:
            answers += rater.rate_all(query.actions)
        w2 = time.perf_counter()
        loop.tell(query, answers)
        return w1 - w0, c1 - c0, time.perf_counter() - w2

    rows = []
    for target in CHECKPOINTS:
        while len(loop.preferences) < target:
            iterate()
        visited = int(loop.posterior.visited.size)
        ask, ask_cpu, tell = np.array([iterate() for _ in range(iterations)]).T
        rows.append(
            {
                "case": name,
                "actions": len(space),
                "answers": mode,
                "sampler": loop.posterior.sampler,
                "comparisons": target,
                "visited": visited,
                "iterations": iterations,
                "median_ask_ms": 1e3 * float(np.median(ask)),
                "p95_ask_ms": 1e3 * float(np.percentile(ask, 95)),
                "median_ask_cpu_ms": 1e3 * float(np.median(ask_cpu)),
                "median_tell_ms": 1e3 * float(np.median(tell)),
                "median_iteration_ms": 1e3 * float(np.median(ask + tell)),
                "distinct_executed": len(set(loop.executed)),
                "executed": len(loop.executed),
            }
        )
    return rows


def _markdown(info: dict[str, object], rows: list[dict[str, object]]) -> str:
    lines = [
        "# The information-gain strategy (issue 12, item 4)",
        "",
        "`python benchmarks/bench_infogain.py` - CoSpar n = 1, b = 1 with `information-gain`",
        "(default settings), a simulated user and, with ratings, an ordinal rater at the",
        "objective's quartiles. Ask is the strategy's proposal (the loop's `ask`; CPU: this",
        "process's CPU time, steadier than wall time on a shared machine); tell is the loop's",
        "refit, the same for every strategy. Targets: an iteration under 50 ms on 30 x 30 and",
        "under 0.5 s on 57,750 actions. Mind the load average below: wall times include waiting",
        "for a core.",
        "",
        "| grid | actions | answers | path | comparisons | visited | median ask (ms) |"
        " p95 ask (ms) | ask CPU (ms) | median tell (ms) | median iteration (ms) |"
        " distinct / executed |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['case']} | {r['actions']:,} | {r['answers']} | "
            f"{r['sampler']} | {r['comparisons']} | {r['visited']} | {r['median_ask_ms']:.1f} | "
            f"{r['p95_ask_ms']:.1f} | {r['median_ask_cpu_ms']:.1f} | {r['median_tell_ms']:.1f} | "
            f"{r['median_iteration_ms']:.1f} | {r['distinct_executed']} / {r['executed']} |"
        )
    lines += ["", "Machine:", "", machine_markdown(info), ""]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=int, default=10)
    parser.add_argument("--cases", nargs="*", default=["2d", "6d"])
    parser.add_argument("--case", help=argparse.SUPPRESS)  # internal: one case, JSON to stdout
    parser.add_argument("--mode", choices=MODES, default="prefs", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.case:
        print(json.dumps(run_case(args.case, args.mode, args.iterations)))
        return
    rows: list[dict[str, object]] = []
    for name in args.cases:
        for mode in MODES:
            print(f"case {name}, {mode} ...", file=sys.stderr, flush=True)
            command = [sys.executable, __file__, "--case", name, "--iterations"]
            command += [str(args.iterations), "--mode", mode]
            out = subprocess.run(command, check=True, capture_output=True, text=True)
            rows += json.loads(out.stdout.strip().splitlines()[-1])
    info = machine_description()
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "infogain.json").write_text(json.dumps({"machine": info, "rows": rows}, indent=2))
    text = _markdown(info, rows)
    (RESULTS / "infogain.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
