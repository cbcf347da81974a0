"""A warm-started session's time per answer against the size of the clinic it starts from.

Each earlier subject of a clinic (``S`` subjects, ``T`` answers each, the paper's 2-D grid
``exo-2d-length-duration``, each preferring its own step length and duration) answers through
the Session API into a fresh SQLite database; then a new subject's session is created from all
of them (``prior_from``) and answers ``NEW`` queries.  Timed, wall clock: the creation (the
earlier sessions replayed, ``rho`` fitted), each answer with the next query (the share
hypotheses weighed, the posterior refitted, a query proposed), the confidence the terminal and
the console show after each answer (``session_confidence``), and reopening the new session
(every earlier session and every answer replayed); and the memory each further answer leaves
held (``tracemalloc``, after the timed answers, over ``MEMORY_ANSWERS`` more: what the
session keeps per answer for undo and its history).  ``nodes``: the distinct (gait, subject)
pairs of the earlier sessions' answers, what the warm fit's cost grows with
(``MAX_PRIOR_NODES`` caps it).

    python benchmarks/bench_warm.py --out before.json        # with an earlier checkout's src
    python benchmarks/bench_warm.py --out after.json
    python benchmarks/bench_warm.py --report before.json after.json
    python benchmarks/bench_warm.py                          # as run_all.py runs it

``--report`` writes benchmarks/results/warm.md from runs written by ``--out`` (one column group
per run, labelled by ``--label``).  Without ``--out`` or ``--report`` this checkout's run goes to
``results/warm/now.json`` and the report tabulates every run kept in ``results/warm/`` (the
recorded one from before the share hypotheses were weighed in threads: ``before-070b543.json``).
"""

from __future__ import annotations

import argparse
import gc
import json
import tempfile
import time
import tracemalloc
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import numpy as np
from _machine import machine_description, machine_markdown

import gaitpref
from gaitpref import Session, load_config
from gaitpref.loop.stopping import StopRule
from gaitpref.sessions.confidence import session_confidence
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.space import FloatArray, Space

RESULT = Path(__file__).parent / "results" / "warm.md"
RUNS = RESULT.with_suffix("")  # results/warm/: the runs the report tabulates
CONFIG = "exo-2d-length-duration"
CLINICS = ((4, 30), (12, 30), (24, 30), (40, 60))  # (subjects, answers each)
NEW = 5
MEMORY_ANSWERS = 3
_T = TypeVar("_T")


def _utility(space: Space, rng: np.random.Generator) -> FloatArray:
    best = {f.name: f.values[0] + rng.uniform(0.3, 0.8) * f.span for f in space.features}
    return bump_utility(space, best)


def _answer(session: Session, subject: SimulatedSubject) -> None:
    query = session.next_query()
    comparisons, suggestions = subject.respond(query)
    session.answer(query.id, comparisons, suggestions)


def _clinic(url: str, subjects: int, answers: int) -> dict[str, float]:
    space = load_config(CONFIG).space
    rng = np.random.default_rng(subjects)
    for k in range(subjects):
        with Session.create(url, CONFIG, f"S{k:02d}", seed=k) as s:
            subject = SimulatedSubject(space, _utility(space, rng), seed=k)
            for _ in range(answers):
                _answer(s, subject)
    clock = _Clock()
    session = clock.time(
        "create",
        lambda: Session.create(
            url, CONFIG, "NEW", seed=99, prior_from=[f"S{k:02d}" for k in range(subjects)]
        ),
    )
    warm = session._state.loop.warm
    assert warm is not None
    data = warm.data
    nodes = int(np.unique(np.concatenate([data.first, data.second])).size)
    subject = SimulatedSubject(space, _utility(space, rng), seed=99)
    for _ in range(NEW):
        clock.time("answer", lambda: _answer(session, subject))
        clock.time("confidence", lambda: session_confidence(session._state, StopRule()))
    held = _held_per_answer(session, subject)
    sid = session.id
    session.close()
    clock.time("reopen", lambda: Session.open(url, sid).close())
    return {"subjects": subjects, "answers": answers, "nodes": nodes, "held_mib": held,
            **clock.medians()}  # fmt: skip


def _held_per_answer(session: Session, subject: SimulatedSubject) -> float:
    """MiB that each of ``MEMORY_ANSWERS`` further answers leaves allocated (Python and NumPy
    allocations, ``tracemalloc``), on average.  One answer first, traced but not counted: the
    session's current model is then allocated under tracing, and its replacement by the next
    answer's is not counted as growth (what was allocated before tracing started is never
    counted as freed)."""
    gc.collect()
    tracemalloc.start()
    try:
        _answer(session, subject)
        gc.collect()
        start = tracemalloc.get_traced_memory()[0]
        for _ in range(MEMORY_ANSWERS):
            _answer(session, subject)
        gc.collect()
        return (tracemalloc.get_traced_memory()[0] - start) / MEMORY_ANSWERS / 2**20
    finally:
        tracemalloc.stop()


class _Clock:
    """Wall clock and this process's CPU time (every thread's) of each call, by name."""

    def __init__(self) -> None:
        self.wall: dict[str, list[float]] = {}
        self.cpu: dict[str, list[float]] = {}

    def time(self, name: str, call: Callable[[], _T]) -> _T:
        wall, cpu = time.perf_counter(), time.process_time()
        out = call()
        self.wall.setdefault(name, []).append(time.perf_counter() - wall)
        self.cpu.setdefault(name, []).append(time.process_time() - cpu)
        return out

    def medians(self) -> dict[str, float]:
        out = {f"{k}_s": float(np.median(v)) for k, v in self.wall.items()}
        out |= {f"{k}_cpu_s": float(np.median(v)) for k, v in self.cpu.items()}
        return out


def run(out: Path, label: str, clinics: list[tuple[int, int]]) -> None:
    rows = []
    for subjects, answers in clinics:
        with tempfile.TemporaryDirectory() as tmp:
            row = _clinic(f"sqlite:///{Path(tmp) / 'clinic.db'}", subjects, answers)
        rows.append(row)
        print(label, json.dumps(row), flush=True)
    doc = {"label": label, "version": gaitpref.__version__, "rows": rows,
           "machine": machine_description()}  # fmt: skip
    out.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")


def report(paths: list[Path]) -> None:
    runs = [json.loads(p.read_text(encoding="utf-8")) for p in paths]
    head = "| earlier subjects x answers | nodes |"
    rule = "|---|---|"
    for r in runs:
        head += (
            f" create ({r['label']}) | answer + next query | confidence | reopen | MiB an answer |"
        )
        rule += "---|---|---|---|---|"
    lines = [
        "# Warm starts: time per answer against the clinic's size",
        "",
        "`python benchmarks/bench_warm.py` (module docstring): the paper's 2-D grid "
        f"(`{CONFIG}`), a new subject warm-started from every earlier one; seconds, wall clock "
        "(CPU time of every thread in brackets); answer and confidence: the median of the new "
        f"subject's first {NEW} answers; MiB an answer: what each of {MEMORY_ANSWERS} answers "
        "after one more leaves allocated (`tracemalloc`; not recorded before 2026-12-05).  "
        "Reopening replays every answer of the new session: 5 in runs without the memory "
        f"column, {NEW + 1 + MEMORY_ANSWERS} in runs with it.",
        "",
        "A run labelled by a commit ran that checkout's `src` (`PYTHONPATH`) with this script.  "
        "On a loaded machine the CPU time is the fairer comparison; where threads ran side by "
        "side (the share hypotheses, from 256 observations) it exceeds the wall clock.",
        "",
        head,
        rule,
    ]
    keyed = [{(row["subjects"], row["answers"]): row for row in r["rows"]} for r in runs]
    for subjects, answers in sorted(set().union(*keyed)):
        first = next(k[(subjects, answers)] for k in keyed if (subjects, answers) in k)
        line = f"| {subjects} x {answers} | {first['nodes']} |"
        for k in keyed:
            row = k.get((subjects, answers))
            cells = ("create_s", "answer_s", "confidence_s", "reopen_s")
            line += "".join(" - |" if row is None else f" {_cell(row, c)} |" for c in cells)
            held = None if row is None else row.get("held_mib")
            line += " - |" if held is None else f" {held:.1f} |"
        lines.append(line)
    for r in runs:
        lines += ["", f"Machine ({r['label']}, gaitpref {r['version']}):", "",
                  machine_markdown(r["machine"])]  # fmt: skip
    RESULT.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _cell(row: dict[str, float], name: str) -> str:
    """Wall clock, then CPU time in brackets when recorded (all threads: above the wall clock
    where threads ran side by side, and the fairer measure on a loaded machine)."""
    cpu = row.get(name.replace("_s", "_cpu_s"))
    return f"{row[name]:.2f}" + ("" if cpu is None else f" ({cpu:.2f})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="write this run's rows here (JSON)")
    parser.add_argument("--label", default="this checkout", help="the run's name in the report")
    parser.add_argument(
        "--clinics",
        default=",".join(f"{s}x{t}" for s, t in CLINICS),
        help="subjects x answers, comma-separated (default: %(default)s)",
    )
    parser.add_argument("--report", type=Path, nargs="+", help="runs to tabulate into warm.md")
    args = parser.parse_args()
    if args.report:
        report(args.report)
        return
    clinics = [tuple(int(v) for v in c.split("x")) for c in args.clinics.split(",")]
    if args.out is not None:
        run(args.out, args.label, [(s, t) for s, t in clinics])
        return
    RUNS.mkdir(exist_ok=True)  # no --out: this checkout as "now", tabulated with the runs kept
    run(RUNS / "now.json", "now", [(s, t) for s, t in clinics])
    report(sorted(RUNS.glob("*.json"), key=lambda p: (p.name == "now.json", p.name)))


if __name__ == "__main__":
    main()
