"""Speed of durable sessions: one answer committed to SQLite, and resuming by replay.

- *answer latency*: ``next_query()`` (logged) + ``answer()`` (one transaction), as an operator's
  terminal does per trial, for a simulated subject; SQLite in WAL mode with ``synchronous=FULL``
  (every commit is fsynced) against the in-memory store (the CoSpar work alone plus bookkeeping);
- *resume*: ``Session.open`` of a session with T trials, replaying and checking the whole log.

Configs: the paper's 2-D exoskeleton grid (15 x 6) and the 30 x 30 synthetic grid.  There is no
target in the issue; the point is that storage adds little to an iteration and that resuming a
long session takes well under a second.

    python benchmarks/bench_sessions.py [--trials 150]

Writes benchmarks/results/sessions.md and sessions.json.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from gaitpref import Session, load_config
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.storage import MemoryStorage, Storage

try:
    from _machine import machine_description, machine_markdown
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown

RESULTS = Path(__file__).parent / "results"


def _run(db: str | Storage, config: str, trials: int) -> tuple[list[float], int]:
    cfg = load_config(config)
    subject = SimulatedSubject(cfg.space, bump_utility(cfg.space), seed=0)
    s = Session.create(db, cfg, "BENCH", seed=1)
    times = []
    while len(s.trials()) < trials:
        t0 = time.perf_counter()
        q = s.next_query()
        comparisons, suggestions = subject.respond(q)
        s.answer(q.id, comparisons, suggestions)
        times.append(time.perf_counter() - t0)
    sid = s.id
    s.close()
    return times, sid


def _resume(db: str | Storage, sid: int, repeats: int = 5) -> float:
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        s = Session.open(db, sid)
        best = min(best, time.perf_counter() - t0)
        s.close()
    return float(best)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=150)
    args = parser.parse_args()
    _run(MemoryStorage(), "exo-1d-step-length", 5)  # warm-up
    results: dict[str, dict[str, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for config in ("exo-2d-length-width", "synthetic-2d"):
            url = f"sqlite:///{Path(tmp) / (config + '.db')}"
            sql_times, sid = _run(url, config, args.trials)
            mem = MemoryStorage()
            mem_times, mem_sid = _run(mem, config, args.trials)
            results[config] = {
                "trials": args.trials,
                "sqlite_median_answer_ms": 1e3 * float(np.median(sql_times)),
                "sqlite_p95_answer_ms": 1e3 * float(np.percentile(sql_times, 95)),
                "memory_median_answer_ms": 1e3 * float(np.median(mem_times)),
                "sqlite_resume_s": _resume(url, sid),
                "memory_resume_s": _resume(mem, mem_sid),
            }
    info = machine_description()
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "sessions.json").write_text(
        json.dumps({"machine": info, "results": results}, indent=2) + "\n"
    )
    lines = [
        "# Session speed: answers committed to SQLite, and resuming by replay",
        "",
        "`python benchmarks/bench_sessions.py` - an answer is next_query() + answer(), both",
        "committed (SQLite: WAL, synchronous=FULL); resume is Session.open replaying the whole log",
        "(best of 5).",
        "",
        "| config | trials | SQLite answer median (ms) | SQLite answer p95 (ms) | "
        "in-memory answer median (ms) | resume from SQLite (s) | resume in memory (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, r in results.items():
        lines.append(
            f"| {name} | {r['trials']:.0f} | {r['sqlite_median_answer_ms']:.1f} | "
            f"{r['sqlite_p95_answer_ms']:.1f} | {r['memory_median_answer_ms']:.1f} | "
            f"{r['sqlite_resume_s']:.3f} | {r['memory_resume_s']:.3f} |"
        )
    lines += ["", "Machine:", "", machine_markdown(info), ""]
    (RESULTS / "sessions.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
