"""Two writer processes answering one session: both make progress, neither waits long.

Two processes open the same session of ``exo-1d-step-length`` (SQLite in a temporary folder) and,
for ``--seconds`` each, ask for the pending query and answer it (the first action preferred to the
first buffered one) as fast as they can.  An attempt whose query the other process answered first
is "stale" (refused, nothing written).  Per process: accepted answers, stale attempts, "session
busy" refusals, and the time of each attempt (next query + answer), which includes waiting for
the session's turn (``gaitpref.storage.turns``).

Between reading the query and answering it, each writer "thinks" for a random time up to
``--think-ms`` (default 20 ms, its own seeded generator): a person at a console does.  With no
think time (``--think-ms 0``) the two loops fall into lockstep: both read the same pending query,
the turns alternate fairly, and the first to answer always wins, so one writer's answers are all
stale although it is never kept waiting (the first table of the recorded results shows it).

Target (issue 15): both make progress, and neither waits more than 1 s at the median.  gaitpref
0.1.0 made 549 and 0 answers in 20 s (about 2 s per failed attempt).

    python benchmarks/bench_writers.py [--seconds 20] [--think-ms 20]

Writes benchmarks/results/writers.md and writers.json.
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

from gaitpref import QueryError, Session
from gaitpref.storage import SessionBusyError

try:
    from _machine import machine_description, machine_markdown
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown

RESULTS = Path(__file__).parent / "results"
CONFIG = "exo-1d-step-length"


def writer(
    url: str, session_id: int, seconds: float, start_at: float, think_ms: float, seed: int
) -> dict[str, object]:
    """One process's loop (see the module docstring); starts at wall time ``start_at``."""
    import numpy as np

    rng = np.random.default_rng(seed)
    session = Session.open(url, session_id)
    time.sleep(max(0.0, start_at - time.time()))
    accepted = stale = busy = 0
    waits: list[float] = []
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        t0 = time.perf_counter()
        try:
            q = session.next_query()
            pair = [(q.actions[0], q.buffer[0], "first")] if q.buffer else []
            if think_ms > 0:
                time.sleep(float(rng.uniform(0.0, think_ms)) / 1000)
            session.answer(q.id, pair, [])
            accepted += 1
        except QueryError:
            stale += 1
        except SessionBusyError:
            busy += 1
        waits.append(time.perf_counter() - t0)
    session.close()
    return {"accepted": accepted, "stale": stale, "busy": busy, "waits": waits}


def _ms(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return round(1000 * ordered[min(len(ordered) - 1, int(q * len(ordered)))], 1)


def run(seconds: float, think_ms: float) -> list[dict[str, object]]:
    with tempfile.TemporaryDirectory() as tmp:
        url = f"sqlite:///{tmp}/w.db"
        sid = Session.create(url, CONFIG, "W01", seed=0).id
        with ProcessPoolExecutor(2, mp_context=get_context("spawn")) as pool:
            start_at = time.time() + 8.0  # both processes have imported gaitpref by then
            futures = [
                pool.submit(writer, url, sid, seconds, start_at, think_ms, k) for k in range(2)
            ]
            runs = [f.result() for f in futures]
        check = Session.open(url, sid)
        executed = [e for e in check.events() if e.kind == "trial_executed"]
        assert len(executed) == sum(int(r["accepted"]) for r in runs)  # type: ignore[call-overload]
        assert len({e.payload["query"] for e in executed}) == len(executed)
        check.close()
    return runs


def _rows(runs: list[dict[str, object]]) -> list[dict[str, object]]:
    rows = []
    for k, r in enumerate(runs, 1):
        waits: list[float] = r["waits"]  # type: ignore[assignment]
        rows.append(
            {
                "writer": k,
                "accepted": r["accepted"],
                "stale": r["stale"],
                "busy": r["busy"],
                "attempts": len(waits),
                "median_ms": round(1000 * statistics.median(waits), 1) if waits else None,
                "p99_ms": _ms(waits, 0.99) if waits else None,
                "max_ms": round(1000 * max(waits), 1) if waits else None,
            }
        )
    return rows


def _table(rows: list[dict[str, object]]) -> list[str]:
    return [
        "| writer | accepted | stale | busy | attempts | median | p99 | max |",
        "|---|---|---|---|---|---|---|---|",
        *[
            f"| {r['writer']} | {r['accepted']} | {r['stale']} | {r['busy']} | {r['attempts']} "
            f"| {r['median_ms']} ms | {r['p99_ms']} ms | {r['max_ms']} ms |"
            for r in rows
        ],
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="how long both write")
    parser.add_argument("--think-ms", type=float, default=20.0, help="most think time, ms")
    parser.add_argument("--note", default="", help="a line about the conditions of this run")
    args = parser.parse_args()
    lockstep = _rows(run(args.seconds, 0.0))
    thinking = _rows(run(args.seconds, args.think_ms))
    machine = machine_description()
    RESULTS.mkdir(exist_ok=True)
    payload = {
        "seconds": args.seconds,
        "think_ms": args.think_ms,
        "writers_no_think": lockstep,
        "writers": thinking,
        "machine": machine,
        "note": args.note,
    }
    (RESULTS / "writers.json").write_text(json.dumps(payload, indent=2) + "\n")
    lines = [
        "# Two writers on one session (benchmarks/bench_writers.py)",
        "",
        f"Two processes answer one `{CONFIG}` session (SQLite) for {args.seconds:g} s each. An "
        "attempt = next query + answer, including the wait for the session's turn; stale = the "
        "other writer answered that query first (nothing written). Target: both make progress, "
        "median attempt under 1 s. (gaitpref 0.1.0: 549 and 0 answers in 20 s.)",
        "",
        f"With up to {args.think_ms:g} ms between reading the query and answering it (as a person "
        "does):",
        "",
        *_table(thinking),
        "",
        "As fast as they can (no think time): the turns alternate, so both read the same pending "
        "query and the first to answer always wins; the other is never kept waiting, but its "
        "answers are stale:",
        "",
        *_table(lockstep),
        "",
        *([args.note, ""] if args.note else []),
        machine_markdown(machine),
    ]
    (RESULTS / "writers.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
