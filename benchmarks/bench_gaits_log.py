"""Gaits carried by the log (issue 13): what a made gait adds to the log, and reopening a session.

A session on the 15 x 10 step length x duration grid with ``[gaits] generator = "compass-hzd"``
(``bench_gaits_on_demand.py``'s config), a simulated subject, ``--trials`` trials on SQLite.  Then:

1. *the log*: the JSON size of each ``gait_made`` / ``gait_infeasible`` payload, of its ``gait``
   part, and their share of the whole log;
2. *reopening* (``Session.open``: replay of the whole log), ``--repeats`` times each, wall and
   CPU seconds, mean and standard error: SQLite with the gait cache; SQLite without it (the
   gaits from the log); the same log in an in-memory database (no cache at all, as a
   PostgreSQL session has on every opening); and the same log as written before the log carried
   the gaits (payload version 1), without the cache: every gait optimised again.

    python benchmarks/bench_gaits_log.py [--trials 30] [--repeats 5] [--old-repeats 2]

Writes benchmarks/results/gaits_log.md and gaits_log.json.
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.storage import MemoryStorage, NewEvent, SessionSpec, Storage

try:
    from _machine import machine_description, machine_markdown
    from bench_gaits_on_demand import CONFIG
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown
    from benchmarks.bench_gaits_on_demand import CONFIG

RESULTS = Path(__file__).parent / "results"
GAIT_EVENTS = ("gait_made", "gait_infeasible")


def _mean_se(values: list[float]) -> dict[str, float]:
    arr = np.asarray(values)
    se = float(arr.std(ddof=1) / np.sqrt(arr.size)) if arr.size > 1 else float("nan")
    return {"mean": float(arr.mean()), "se": se, "n": int(arr.size)}


def _size(payload: object) -> int:
    return len(json.dumps(payload, separators=(",", ":")))


def record(url: str, trials: int) -> Session:
    cfg = parse_config(CONFIG)
    subject = SimulatedSubject(cfg.space, bump_utility(cfg.space), seed=0)
    s = Session.create(url, cfg, "BENCH", seed=1)
    while len(s.trials()) < trials:
        q = s.next_query()
        s.answer(q.id, *subject.respond(q))
    return s


def copy_into(target: Storage, source: Session, version_1: bool = False) -> int:
    """The session's spec and log written into ``target`` (gait events as payload version 1,
    without their gait, when ``version_1``): the copy's id."""
    rec = source.record
    spec = SessionSpec(
        rec.subject, rec.config_name, rec.config_text, rec.config_sha256, rec.seed,
        rec.software_version, dict(rec.meta),
    )  # fmt: skip
    events = []
    for e in source.events():
        if version_1 and e.kind in GAIT_EVENTS:
            old = {k: v for k, v in e.payload.items() if k != "gait"}
            events.append(NewEvent(e.kind, old, e.at, version=1))
        else:
            events.append(NewEvent(e.kind, e.payload, e.at, e.version))
    return target.create_session(spec, events, rec.status).id


Timing = dict[str, dict[str, float]]


def timed(opening: Callable[[], Session], before: Callable[[], None], n: int) -> Timing:
    """Wall and CPU seconds of ``opening()`` over ``n`` runs, each after ``before()``."""
    wall, cpu = [], []
    for _ in range(n):
        before()
        t0, c0 = time.perf_counter(), time.process_time()
        session = opening()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
        session.close()
    return {"wall_s": _mean_se(wall), "cpu_s": _mean_se(cpu)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=30)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--old-repeats", type=int, default=2)
    args = parser.parse_args()
    info = machine_description()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        url = f"sqlite:///{folder / 'lab.db'}"
        s = record(url, args.trials)
        events = s.events()
        gaits = [e for e in events if e.kind in GAIT_EVENTS]
        made = [e for e in gaits if e.kind == "gait_made"]
        sizes = {
            "gait_events": len(gaits),
            "infeasible": len(gaits) - len(made),
            "payload_bytes": _mean_se([_size(e.payload) for e in gaits]),
            "payload_max_bytes": max(_size(e.payload) for e in gaits),
            "gait_part_bytes": _mean_se([_size(e.payload["gait"]) for e in gaits]),
            "gait_events_total_bytes": sum(_size(e.payload) for e in gaits),
            "log_total_bytes": sum(_size(e.payload) for e in events),
            "events": len(events),
        }
        cache = folder / "lab.db.gaits"
        memory = MemoryStorage()
        new_id, old_id = copy_into(memory, s), copy_into(memory, s, version_1=True)

        def nothing() -> None:
            pass

        def no_cache() -> None:
            shutil.rmtree(cache, ignore_errors=True)

        Session.open(url, s.id).close()  # once first: imports, the cache read from disk
        opening: dict[str, Timing] = {}
        opening["SQLite, with the gait cache"] = timed(
            lambda: Session.open(url, s.id), nothing, args.repeats
        )
        opening["SQLite, no cache: gaits from the log"] = timed(
            lambda: Session.open(url, s.id), no_cache, args.repeats
        )
        opening["in memory (as PostgreSQL): gaits from the log"] = timed(
            lambda: Session.open(memory, new_id), nothing, args.repeats
        )
        opening["in memory, version-1 log: every gait optimised again"] = timed(
            lambda: Session.open(memory, old_id), nothing, args.old_repeats
        )
        s.close()
    lines = [
        "# Gaits carried by the log",
        "",
        machine_markdown(info),
        "",
        f'A session on the 15 x 10 grid with `generator = "compass-hzd"`, {args.trials} trials, '
        f"SQLite: {sizes['events']} events, of which {sizes['gait_events']} gait events "
        f"({sizes['infeasible']} infeasible).",
        "",
        "## The log",
        "",
        f"- a gait event's payload: {sizes['payload_bytes']['mean']:.0f} +- "
        f"{sizes['payload_bytes']['se']:.0f} bytes (max {sizes['payload_max_bytes']}), of which "
        f"the `gait` part {sizes['gait_part_bytes']['mean']:.0f} +- "
        f"{sizes['gait_part_bytes']['se']:.0f} bytes (compact JSON, mean +- se over the events)",
        f"- the gait events: {sizes['gait_events_total_bytes'] / 1e3:.1f} kB of a "
        f"{sizes['log_total_bytes'] / 1e3:.1f} kB log",
        "",
        "## Reopening the session (`Session.open`, mean +- se)",
        "",
        "| database, gaits | runs | wall [s] | CPU [s] |",
        "|---|---|---|---|",
        *[
            f"| {name} | {v['wall_s']['n']:.0f} | {v['wall_s']['mean']:.2f} +- "
            f"{v['wall_s']['se']:.2f} | {v['cpu_s']['mean']:.2f} +- {v['cpu_s']['se']:.2f} |"
            for name, v in opening.items()
        ],
        "",
    ]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "gaits_log.md").write_text("\n".join(lines))
    (RESULTS / "gaits_log.json").write_text(
        json.dumps({"machine": info, "log": sizes, "opening": opening}, indent=1) + "\n"
    )
    print("\n".join(lines))


if __name__ == "__main__":
    main()
