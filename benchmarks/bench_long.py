"""What the operator waits for as one subject's session grows to hundreds of trials.

A lab's long session: one simulated subject, several hundred trials over several days, paused
and resumed every 50 trials (the object closed and the session reopened from SQLite, as the next
day's terminal does), an answer undone every 17 answers, a trial excluded every 23, a rating
every third trial and a coactive suggestion every second.  Two configs:

- *grid*: ``exo-2d-rated`` (the paper's 2-D exoskeleton grid, 15 x 6, with ratings and a
  region of avoidance);
- *line*: ``compass-continuous-3d`` without its gait generator (continuous step length, step
  duration and step width, LineCoSpar lines of 20 points, self-sparring), with three rating
  labels: the point table grows with every query.

At each checkpoint (``--trials``, default 100, 200, 400) it times, in this process on the same
database: ``ask`` (``next_query``) and ``tell`` (``answer``), medians over the last 20 answers;
``resume`` (``Session.open``: the whole log replayed and checked); the confidence the terminal
states after each answer (``Session.confidence``, what the terminal runner adds to an answer);
``session show --no-figure`` and ``db check`` (the CLI in process, Typer's runner); the
console's trial page and ``/api/sessions/{id}/posterior`` (FastAPI's TestClient, a fresh app:
the first request opens the session, the second is served warm); the memory the resumed
session holds (tracemalloc, its state after the open) and the fit cache file beside the
database.  The export (``session export``: it replays the log again and states the confidence
after every answer, undo and exclusion) is timed at ``--export-at`` checkpoints only (default
100 and 200: it takes minutes past that on two cores).

    python benchmarks/bench_long.py [--trials 100,200,400] [--export-at 100,200] [--only grid|line]

Writes benchmarks/results/long.md and long.json.
"""

from __future__ import annotations

import argparse
import gc
import json
import statistics
import tempfile
import time
import tracemalloc
import warnings
from pathlib import Path
from typing import Any

import numpy as np

warnings.filterwarnings("ignore", message="Using `httpx` with `starlette.testclient`")

from fastapi.testclient import TestClient  # noqa: E402
from typer.testing import CliRunner  # noqa: E402

from gaitpref import Rating, Session, load_config  # noqa: E402
from gaitpref.cli.main import app as cli  # noqa: E402
from gaitpref.config import ExperimentConfig, parse_config  # noqa: E402
from gaitpref.console import create_app  # noqa: E402
from gaitpref.sessions import export_session  # noqa: E402
from gaitpref.sessions.demo import SimulatedSubject, bump_utility  # noqa: E402
from gaitpref.sessions.records import REASONS, SessionQuery  # noqa: E402

try:
    from _machine import machine_description, machine_markdown
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown

RESULTS = Path(__file__).parent / "results"
CONFIGS = Path(__file__).parent.parent / "configs"
GRID_LABELS = ["very bad", "bad", "okay", "good"]
LINE_LABELS = ["bad", "okay", "good"]
TARGET = np.array([0.11, 0.8, 0.2])  # the line subject's best (step length, duration, width)
SCALE = np.array([0.06, 0.3, 0.1])


def line_config() -> ExperimentConfig:
    """compass-continuous-3d with points instead of gaits made on demand, and ratings."""
    text = (CONFIGS / "compass-continuous-3d.toml").read_text()
    head, rest = text.split("[gaits]", 1)
    text = head + "[safety]" + rest.split("[safety]", 1)[1]
    text = text.replace('name = "compass-continuous-3d"', 'name = "long-line-3d"')
    return parse_config(text + '\n[feedback.rating]\nlabels = ["bad", "okay", "good"]\n')


class Subject:
    """Answers a query: comparisons (and coactive suggestions) from a utility, a rating."""

    def __init__(self, session: Session) -> None:
        self.line = session.config.subspace == "line"
        if not self.line:
            space = session.config.space
            self.utility = bump_utility(space)
            self.grid = SimulatedSubject(space, self.utility, seed=0)

    def answer(self, s: Session, q: SessionQuery, k: int) -> tuple[list[object], list[object]]:
        a = q.actions[0]
        if self.line:
            u = _line_utility(q.points[0])
            given: list[object] = [
                (a, b, "first" if u > _line_utility(s.space.points[b]) else "second")
                for b in q.buffer
                if b != a
            ]
            move = "+small" if q.points[0][0] < TARGET[0] else "-small"
            suggestions: list[object] = [(a, "step_length", move)]
            label = LINE_LABELS[0 if u < -4 else 1 if u < -1 else 2]
        else:
            comparisons, coactive = self.grid.respond(q)
            given, suggestions = list(comparisons), list(coactive)
            share = float(np.mean(self.utility < self.utility[a]))
            label = GRID_LABELS[min(3, int(1 + 3 * share))]
        if k % 3 == 0:
            given.append(Rating(a, label))
        return given, suggestions if k % 2 else []


def _line_utility(point: object) -> float:
    return float(-np.sum(((np.asarray(point) - TARGET) / SCALE) ** 2))


def _drive(
    s: Session, subject: Subject, until: int, k: int, times: list[tuple[float, float]]
) -> int:
    """Answer until ``until`` trials are in force (undo, exclusions); the answers' count."""
    while len(s.trials()) < until:
        t0 = time.perf_counter()
        q = s.next_query()
        t1 = time.perf_counter()
        given, suggestions = subject.answer(s, q, k)
        t2 = time.perf_counter()
        s.answer(q.id, given, suggestions)
        times.append((t1 - t0, time.perf_counter() - t2))
        if k % 17 == 5:
            s.undo()
        if k % 23 == 11 and len(s.trials()) > 2:
            s.exclude(s.trials()[-2].number, REASONS[0])
        k += 1
    return k


def _timed(fn: Any) -> tuple[float, Any]:
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def _checkpoint(url: str, sid: int, tmp: Path, export: bool) -> dict[str, Any]:
    out: dict[str, Any] = {}
    gc.collect()
    out["resume_s"], s = _timed(lambda: Session.open(url, sid))
    out["events"] = s.last_seq
    out["points"] = len(s.space)
    s.close()
    gc.collect()
    tracemalloc.start()
    s = Session.open(url, sid)
    gc.collect()
    out["held_mb"] = tracemalloc.get_traced_memory()[0] / 2**20
    tracemalloc.stop()
    out["confidence_s"], _ = _timed(s.confidence)
    s.close()
    runner = CliRunner()
    out["show_s"], r = _timed(
        lambda: runner.invoke(cli, ["session", "show", str(sid), "--db", url, "--no-figure"])
    )
    assert r.exit_code == 0, r.output
    out["db_check_s"], r = _timed(lambda: runner.invoke(cli, ["db", "check", "--db", url]))
    assert r.exit_code == 0, r.output
    with TestClient(create_app(url)) as client:
        for name, path in (
            ("page", f"/sessions/{sid}"),
            ("posterior", f"/api/sessions/{sid}/posterior"),
        ):
            first, r = _timed(lambda p=path: client.get(p))
            assert r.status_code == 200, r.text
            warm, r = _timed(lambda p=path: client.get(p))
            assert r.status_code == 200, r.text
            out[f"console_{name}_first_s"], out[f"console_{name}_warm_s"] = first, warm
    fits = Path(url.removeprefix("sqlite:///") + ".fits") / f"{sid}.npz"
    out["fit_cache_kb"] = fits.stat().st_size / 1024 if fits.exists() else 0.0
    if export:
        with Session.open(url, sid) as s:
            where = tmp / f"export-{sid}-{s.last_seq}"
            out["export_s"], _ = _timed(lambda: export_session(s, where, "csv"))
    return out


def run(
    name: str, cfg: ExperimentConfig, checkpoints: list[int], export_at: set[int]
) -> list[dict[str, Any]]:
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        url = f"sqlite:///{tmp / 'lab.db'}"
        s = Session.create(url, cfg, "S01", seed=1)
        sid, subject = s.id, Subject(s)
        times: list[tuple[float, float]] = []
        k, pauses = 0, 0
        for target in checkpoints:
            while len(s.trials()) < target:  # a day's block of at most 50 trials, then a pause
                k = _drive(s, subject, min(target, len(s.trials()) + 50), k, times)
                s.pause()
                s.close()  # the next day: the session reopened from the database
                pauses += 1
                s = Session.open(url, sid)
                s.resume()
            last = np.array(times[-20:])
            row = {
                "config": name,
                "trials": len(s.trials()),
                "answers": k,
                "pauses": pauses,
                "ask_ms": 1e3 * statistics.median(last[:, 0]),
                "tell_ms": 1e3 * statistics.median(last[:, 1]),
            }
            s.close()
            row.update(_checkpoint(url, sid, tmp, target in export_at))
            rows.append(row)
            print(json.dumps(row), flush=True)
            s = Session.open(url, sid)
        s.close()
    return rows


COLUMNS = [
    ("config", "config", "{}"),
    ("trials", "trials", "{}"),
    ("events", "events", "{}"),
    ("points", "points", "{}"),
    ("ask_ms", "ask (ms)", "{:.0f}"),
    ("tell_ms", "tell (ms)", "{:.0f}"),
    ("confidence_s", "confidence (s)", "{:.2f}"),
    ("resume_s", "resume (s)", "{:.2f}"),
    ("show_s", "show (s)", "{:.2f}"),
    ("db_check_s", "db check (s)", "{:.2f}"),
    ("console_page_first_s", "page, first (s)", "{:.2f}"),
    ("console_page_warm_s", "page, warm (s)", "{:.3f}"),
    ("console_posterior_warm_s", "posterior API, warm (s)", "{:.3f}"),
    ("held_mb", "held (MB)", "{:.1f}"),
    ("fit_cache_kb", "fit cache (kB)", "{:.0f}"),
    ("export_s", "export (s)", "{:.1f}"),
]


#: the columns whose growth with the session is summarised (log-log slope, first to last)
GROWTH = ["ask_ms", "tell_ms", "confidence_s", "resume_s", "show_s", "db_check_s", "held_mb",
          "export_s"]  # fmt: skip


#: How to read the table (what the code does, not a claim about one run's numbers).
READING = [
    "Reading it: a resume replays the log and makes every refit again (the state is never",
    "stored; the replay checks every proposal), so it costs what the session's asks and tells",
    "cost together.  On the grid a fit reads at most the 90 gaits and the observations, so",
    "ask, tell and the confidence stay flat and resume, show and db check grow about linearly.",
    "On the line path every query adds points to the table the model is fitted over (points",
    "column), and a fit and an ask cost about the cube of it: resume, show and db check grow",
    "about with the square of the session.  The memory a session holds grows with the square",
    "of the table while answers keep their posterior's factors for undo, until 256 visited",
    "points (cospar.STRIP_FROM_VISITED), then linearly; the fit cache beside the database",
    "starts at 256 visited points (model/fit_memo.py MEMO_FROM).  The export replays the log",
    "once more and draws the confidence after every answer, undo and exclusion (up to 2000",
    "posterior samples each, on one BLAS thread: with BLAS's default threads this machine took",
    "0.2-0.9 s a confidence, 68 s and 71 s to export 100 and 200 grid trials, in 60b4265).",
    "Timings on a shared two-core machine vary by a factor of 2-3 between runs (load below).",
]


def growth(rows: list[dict[str, Any]]) -> list[str]:
    """Per config, how each timing grows with the trials between its first and last checkpoint
    that have it: the exponent k of ``value ~ trials^k`` (1 linear, 2 quadratic)."""
    lines = []
    for name in dict.fromkeys(r["config"] for r in rows):
        mine = [r for r in rows if r["config"] == name]
        said = []
        for key in GROWTH:
            have = [r for r in mine if r.get(key)]
            if len(have) < 2:
                continue
            a, b = have[0], have[-1]
            k = np.log(b[key] / a[key]) / np.log(b["trials"] / a["trials"])
            said.append(f"{key} {k:.1f}")
        span = f"{mine[0]['trials']} to {mine[-1]['trials']} trials"
        lines.append(f"- {name} ({span}): " + ", ".join(said))
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", default="100,200,400", help="checkpoints, comma-separated")
    parser.add_argument(
        "--export-at", default="100,200", help="checkpoints with an export ('' none)"
    )
    parser.add_argument("--only", choices=["grid", "line"], default=None)
    args = parser.parse_args()
    checkpoints = sorted(int(t) for t in args.trials.split(","))
    export_at = {int(t) for t in args.export_at.split(",") if t}
    start = time.perf_counter()
    configs = {"grid": load_config("exo-2d-rated"), "line": line_config()}
    rows: list[dict[str, Any]] = []
    for name, cfg in configs.items():
        if args.only in (None, name):
            rows += run(name, cfg, checkpoints, export_at)
    machine = machine_description()
    RESULTS.mkdir(exist_ok=True)
    payload = {"checkpoints": checkpoints, "rows": rows, "machine": machine}
    (RESULTS / "long.json").write_text(json.dumps(payload, indent=2) + "\n")
    lines = [
        "# Long sessions: what the operator waits for as a session grows",
        "",
        f"`python benchmarks/bench_long.py --trials {args.trials} --export-at {args.export_at}`"
        " (see the script's docstring for the session and what is timed).",
        "",
        "| " + " | ".join(title for _, title, _ in COLUMNS) + " |",
        "|" + "---|" * len(COLUMNS),
    ]
    for row in rows:
        cells = [fmt.format(row[key]) if key in row else "-" for key, _, fmt in COLUMNS]
        lines.append("| " + " | ".join(cells) + " |")
    lines += [
        "",
        "Growth: the exponent k of value ~ trials^k between the first and the last checkpoint",
        "that has the value (1: linear in the session's length, 2: quadratic):",
        "",
        *growth(rows),
        "",
        *READING,
        "",
        f"Whole benchmark: {time.perf_counter() - start:.0f} s.",
        "",
        "Machine:",
        "",
        machine_markdown(machine),
        "",
    ]
    (RESULTS / "long.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
