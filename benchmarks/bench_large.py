"""CoSpar over large grids: ask + tell at 300 comparisons, peak memory, and the dense/scalable
crossover that ``sampler="auto"`` uses.

Cases (issue 7):

- ``6d``: the ``synthetic-6d`` config, 11 x 7 x 6 x 5 x 5 x 5 = 57,750 actions (target: median
  ask + tell under 0.5 s at 300 comparisons);
- ``4d``: 32^4 = 1,048,576 actions on [0, 1]^4, lengthscale 0.25, the same scales (target: under
  5 s, peak memory under 4 GB).

Each case runs in its own process (so its peak RSS is its own): a simulated user with a smooth GP
objective (drawn by the Kronecker sampler) and gradient coactive feedback drives CoSpar (n = 1,
b = 1) until the data holds 300 comparisons; the next ``--iterations`` iterations (ask +
simulated answer + suggestion + tell) are timed one by one.  Peak memory: the process's maximum
RSS (everything, Python included) and the tracemalloc peak of one further iteration.

The crossover: the ask of a fresh posterior (150 random preferences) on the dense and the
scalable path, for grids from 15 to 1,600 actions, with one BLAS thread as CoSpar uses there.

The 30 x 30 grid must not get slower: with ``--baseline SRC`` (the ``src`` directory of another
gaitpref tree, e.g. ``git archive main | tar -x -C /tmp/main``) the n = 1, b = 1 coactive
150-trial runs of ``bench_core.py`` are timed for that tree and this one, interleaved in rounds so
that load from other work hits both alike.

    python benchmarks/bench_large.py [--iterations 15] [--cases 6d 4d] [--baseline /tmp/main/src]

Writes benchmarks/results/large.md and large.json.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import resource
import subprocess
import sys
import time
import timeit
import tracemalloc
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_info, threadpool_limits

from gaitpref import CoSpar, Feature, GradientCoactive, SimulatedUser, Space, load_config
from gaitpref.model import DENSE_MAX_ACTIONS, Posterior, PreferenceGP, SquaredExponential
from gaitpref.model.kronecker import KroneckerPriorSampler

try:
    from _machine import machine_description, machine_markdown
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown

RESULTS = Path(__file__).parent / "results"
COMPARISONS = 300


def _grid(shape: tuple[int, ...]) -> Space:
    return Space([Feature.linspace(f"x{i + 1}", 0.0, 1.0, n) for i, n in enumerate(shape)])


def _case(name: str) -> tuple[Space, SquaredExponential, float]:
    if name == "6d":
        cfg = load_config("synthetic-6d")
        return cfg.space, cfg.kernel, cfg.noise
    if name == "4d":
        shape = (32, 32, 32, 32)
        space = Space(
            [
                Feature.linspace(f"x{i + 1}", 0, 1, n, coactive=(0.07, 0.13))
                for i, n in enumerate(shape)
            ]
        )
        return space, SquaredExponential(0.25, 1e-4, 1e-5), 0.01
    raise SystemExit(f"unknown case {name!r}; cases are 6d and 4d")


def gp_objective(space: Space, lengthscale: float, seed: int) -> np.ndarray:
    """A smooth random objective: one sample of a unit-variance GP over the grid."""
    kernel = SquaredExponential(lengthscale, 1.0, 0.0)
    return KroneckerPriorSampler(space, kernel).sample(np.random.default_rng(seed), 1)[0]


def run_case(name: str, iterations: int) -> dict[str, object]:
    space, kernel, noise = _case(name)
    ell = kernel.lengthscales(space.ndim)[0]
    objective = gp_objective(space, ell, seed=7)
    loop = CoSpar(space, kernel, noise, n=1, buffer=1, seed=0)
    user = SimulatedUser(space, objective, np.random.default_rng(1))
    helper = GradientCoactive(space, objective)

    def iterate() -> tuple[float, float]:
        t0 = time.perf_counter()
        query = loop.ask()
        t1 = time.perf_counter()
        suggestions = helper.suggest_all(query.actions)
        answers = user.answer(query)
        t2 = time.perf_counter()
        loop.tell(query, answers, suggestions)
        return t1 - t0, time.perf_counter() - t2

    start = time.perf_counter()
    while len(loop.preferences) < COMPARISONS:
        iterate()
    warmup = time.perf_counter() - start
    prefs_before, visited_before = len(loop.preferences), int(loop.posterior.visited.size)
    asks, tells = np.array([iterate() for _ in range(iterations)]).T
    tracemalloc.start()
    iterate()
    _, traced_peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    post = dataclasses.replace(loop.posterior)
    t0 = time.perf_counter()
    _ = post.mean
    t1 = time.perf_counter()
    _ = post.variance
    t2 = time.perf_counter()
    total = asks + tells
    return {
        "case": name,
        "actions": len(space),
        "shape": list(space.shape),
        "sampler": loop.posterior.sampler,
        "comparisons_at_start": prefs_before,
        "comparisons_at_end": len(loop.preferences),
        "visited_at_start": visited_before,
        "warmup_iterations_s": round(warmup, 2),
        "iterations": iterations,
        "median_ask_tell_s": float(np.median(total)),
        "p95_ask_tell_s": float(np.percentile(total, 95)),
        "median_ask_s": float(np.median(asks)),
        "median_tell_s": float(np.median(tells)),
        "mean_all_actions_s": t1 - t0,
        "variance_all_actions_s": t2 - t1,
        "tracemalloc_peak_one_iteration_mb": traced_peak / 2**20,
        "max_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "best_executed_normalized": float(np.max(user.normalized(loop.executed))),
    }


def crossover() -> list[dict[str, object]]:
    rng = np.random.default_rng(0)
    rows = []
    shapes = [(15,), (24,), (40,), (60,), (8, 10), (15, 6), (10, 10), (15, 10), (12, 12)]
    shapes += [(16, 16), (20, 20), (25, 25), (30, 30), (8, 8, 8), (40, 40)]
    with threadpool_limits(limits=1, user_api="blas"):
        for shape in shapes:
            space = _grid(shape)
            kernel = SquaredExponential(0.2, 1e-4, 1e-5)
            w, lose = rng.integers(0, len(space), (2, 150))
            keep = w != lose
            times = {}
            for sampler in ("dense", "scalable"):
                gp = PreferenceGP(space, kernel, 0.01, sampler=sampler)
                post = gp.posterior(w[keep], lose[keep])

                def ask(post: Posterior = post) -> None:
                    dataclasses.replace(post).argmax_samples(rng, 1)

                times[sampler] = min(timeit.repeat(ask, number=50, repeat=7)) / 50
            rows.append(
                {
                    "shape": "x".join(map(str, shape)),
                    "actions": len(space),
                    "visited": int(post.visited.size),
                    "dense_ask_us": 1e6 * times["dense"],
                    "scalable_ask_us": 1e6 * times["scalable"],
                }
            )
    return rows


_CORE_SNIPPET = """
import json, sys
sys.path.insert(0, "benchmarks")
from bench_core import one_run
one_run(1, 1, True, 99, trials=10)
out = []
for k in KS:
    iters, total = one_run(1, 1, True, k)
    out.append([total, [dt for done, dt in iters if done >= 100]])
print(json.dumps(out))
"""


def core_comparison(
    baseline: str, label: str, rounds: int = 5, per_round: int = 2
) -> dict[str, dict[str, object]]:
    """150-trial synthetic-2d runs (n = 1, b = 1, coactive) of ``baseline`` and this tree."""
    here = str(Path(__file__).resolve().parent.parent / "src")
    runs: dict[str, list] = {"baseline": [], "this branch": []}
    for r in range(rounds):
        ks = list(range(r * per_round, (r + 1) * per_round))
        for name, src in (("baseline", baseline), ("this branch", here)):
            env = {**os.environ, "PYTHONPATH": src}
            code = _CORE_SNIPPET.replace("KS", repr(ks))
            out = subprocess.run(
                [sys.executable, "-c", code],
                cwd=Path(__file__).resolve().parent.parent,
                env=env,
                check=True,
                capture_output=True,
                text=True,
            )
            runs[name] += json.loads(out.stdout.strip().splitlines()[-1])
    summary: dict[str, dict[str, object]] = {}
    for name, values in runs.items():
        late = [dt for _, its in values for dt in its]
        summary[name] = {
            "label": label if name == "baseline" else "this tree",
            "median_run_s": float(np.median([t for t, _ in values])),
            "median_iteration_ms_trials_100_150": 1e3 * float(np.median(late)),
            "runs": len(values),
        }
    return summary


def _markdown(
    info: dict[str, object], cases: list[dict], cross: list[dict], core: dict | None
) -> str:
    lines = [
        "# CoSpar on large grids (issue 7)",
        "",
        "`python benchmarks/bench_large.py` - n = 1, b = 1 with coactive feedback; one iteration",
        "is ask + simulated answer + suggestion + tell, timed at 300 comparisons.",
        "Targets: 57,750 actions median under 0.5 s; 1,048,576 actions under 5 s and 4 GB.",
        "",
        "| grid | actions | path | comparisons | visited | median ask+tell (s) | p95 (s) |"
        " ask (s) | tell (s) | peak RSS (MB) | tracemalloc peak (MB) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c in cases:
        lines.append(
            f"| {'x'.join(map(str, c['shape']))} | {c['actions']:,} | {c['sampler']} | "
            f"{c['comparisons_at_start']}-{c['comparisons_at_end']} | {c['visited_at_start']} | "
            f"{c['median_ask_tell_s']:.3f} | {c['p95_ask_tell_s']:.3f} | {c['median_ask_s']:.3f} | "
            f"{c['median_tell_s']:.3f} | {c['max_rss_mb']:.0f} | "
            f"{c['tracemalloc_peak_one_iteration_mb']:.0f} |"
        )
    lines += [
        "",
        "Also over all actions (not part of ask + tell): the posterior mean "
        + ", ".join(f"{c['mean_all_actions_s']:.3f} s ({c['case']})" for c in cases)
        + "; the variance (``O(A m^2)``, blocked) "
        + ", ".join(f"{c['variance_all_actions_s']:.1f} s ({c['case']})" for c in cases)
        + ".",
        "",
        '## Dense or scalable: the crossover behind `sampler = "auto"`',
        "",
        "Ask on a fresh posterior (150 random preferences; includes building `K_{:,V}`), one BLAS",
        f"thread, best of 7 x 50. `auto` uses the dense path up to {DENSE_MAX_ACTIONS} actions.",
        "",
        "| grid | actions | visited | dense ask (us) | scalable ask (us) | faster |",
        "|---|---|---|---|---|---|",
    ]
    for r in cross:
        faster = "dense" if r["dense_ask_us"] < r["scalable_ask_us"] else "scalable"
        lines.append(
            f"| {r['shape']} | {r['actions']} | {r['visited']} | {r['dense_ask_us']:.0f} | "
            f"{r['scalable_ask_us']:.0f} | {faster} |"
        )
    if core is not None:
        lines += [
            "",
            "## The 30 x 30 grid (synthetic-2d, n = 1, b = 1, coactive, 150 trials)",
            "",
            f"Baseline: {core['baseline']['label']}; runs interleaved in rounds.",
            "",
            "| code | median run (s) | median iteration, trials 100-150 (ms) | runs |",
            "|---|---|---|---|",
        ]
        for label in ("baseline", "this branch"):
            c = core[label]
            lines.append(
                f"| {label} | {c['median_run_s']:.3f} | "
                f"{c['median_iteration_ms_trials_100_150']:.2f} | {c['runs']} |"
            )
    lines += ["", "Machine:", "", machine_markdown(info), ""]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=int, default=15)
    parser.add_argument("--cases", nargs="*", default=["6d", "4d"])
    parser.add_argument("--baseline", help="src/ of another gaitpref tree to compare 30 x 30 with")
    parser.add_argument("--baseline-label", help="how to name the baseline (e.g. main at abc123)")
    parser.add_argument("--case", help=argparse.SUPPRESS)  # internal: one case, JSON to stdout
    args = parser.parse_args()
    if args.case:
        print(json.dumps(run_case(args.case, args.iterations)))
        return
    cases = []
    for name in args.cases:
        print(f"case {name} ...", file=sys.stderr, flush=True)
        out = subprocess.run(
            [sys.executable, __file__, "--case", name, "--iterations", str(args.iterations)],
            check=True,
            capture_output=True,
            text=True,
        )
        cases.append(json.loads(out.stdout.strip().splitlines()[-1]))
    print("crossover ...", file=sys.stderr, flush=True)
    cross = crossover()
    core = None
    if args.baseline:
        print("30 x 30 against the baseline ...", file=sys.stderr, flush=True)
        core = core_comparison(args.baseline, args.baseline_label or f"`{args.baseline}`")
    info = machine_description()
    info["blas"] = ", ".join(
        f"{i['internal_api']} {i.get('version')} ({i['num_threads']} threads)"
        for i in threadpool_info()
        if i["user_api"] == "blas"
    )
    RESULTS.mkdir(exist_ok=True)
    payload = {"machine": info, "cases": cases, "crossover": cross, "core_30x30": core}
    (RESULTS / "large.json").write_text(json.dumps(payload, indent=2))
    text = _markdown(info, cases, cross, core)
    (RESULTS / "large.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
