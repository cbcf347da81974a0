"""The session figure and the export on one BLAS thread against BLAS's default threads: the same
bytes, and the time.

``plots/session.py`` (the session figure) and ``sessions/export.py`` (the export's tables and its
posterior summary) compute on one BLAS thread (``model/threads.py``'s ``one_blas_thread``), as
ask, tell and the confidence do.  This script checks that it changed no float and measures what
it saves: sessions in a SQLite file, answered by ``bench_long.py``'s simulated subject
(``exo-2d-rated``, the 15 x 6 grid with ratings, a region of avoidance and one trial flagged
unsafe; ``synthetic-2d``, 30 x 30, comparisons and suggestions; the line path of
``bench_long.py``, whose point table grows with every query), each reopened before every figure
and every export (nothing cached), then drawn (``save_session_figure``) and exported (CSV) as
shipped and with the limit lifted (``one_blas_thread`` replaced by a no-op in both modules, as
before), alternating ``--rounds`` times after one untimed warm-up.  Compared byte for byte:
every export file (the manifest without its ``exported_at`` and its file hashes) and the
figure's PNG.

    python benchmarks/check_blas_outputs.py [--trials 100] [--line-trials 170] [--rounds 3]

Writes benchmarks/results/blas_outputs.md.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from _machine import machine_footer
from bench_long import Subject, _drive, line_config

import gaitpref.plots.session as figure_module
import gaitpref.sessions.export as export_module
from gaitpref import Rating, Session, load_config
from gaitpref.simulate.report import load_average

RESULT = Path(__file__).parent / "results" / "blas_outputs.md"
SHIPPED = (figure_module.one_blas_thread, export_module.one_blas_thread)


def _lift(lifted: bool) -> None:
    if lifted:
        figure_module.one_blas_thread = contextlib.nullcontext  # type: ignore[assignment]
        export_module.one_blas_thread = contextlib.nullcontext  # type: ignore[assignment]
    else:
        figure_module.one_blas_thread, export_module.one_blas_thread = SHIPPED


def _make(url: str, name: str, trials: int) -> tuple[int, int]:
    """A session answered to ``trials`` trials in force: its id and its gaits (points)."""
    cfg = line_config() if name == "line" else load_config(name)
    s = Session.create(url, cfg, "S01", seed=1)
    subject = Subject(s)
    if name == "synthetic-2d":  # no ratings in this config
        k = 0
        while len(s.trials()) < trials:
            q = s.next_query()
            given, suggestions = subject.answer(s, q, k)
            s.answer(q.id, [g for g in given if not isinstance(g, Rating)], suggestions)
            k += 1
    else:
        _drive(s, subject, trials, 0, [])
    if name == "exo-2d-rated":
        s.flag_unsafe(s.trials()[-3].number, "other")
    sid, gaits = s.id, len(s.space)
    s.close()
    return sid, gaits


def _files(folder: Path) -> dict[str, str]:
    out = {}
    for p in sorted(folder.iterdir()):
        data = p.read_bytes()
        if p.name == "manifest.json":
            manifest = json.loads(data)
            manifest.pop("exported_at")
            manifest.pop("files", None)  # the hashes of the files compared here
            data = json.dumps(manifest, sort_keys=True).encode()
        out[p.name] = hashlib.sha256(data).hexdigest()
    return out


def _one(url: str, sid: int, where: Path) -> tuple[float, float, dict[str, str]]:
    s = Session.open(url, sid)
    start = time.perf_counter()
    figure_module.save_session_figure(s, where / "figure.png")
    figure = time.perf_counter() - start
    s.close()
    s = Session.open(url, sid)
    start = time.perf_counter()
    export_module.export_session(s, where / "export", "csv")
    export = time.perf_counter() - start
    s.close()
    files = _files(where / "export")
    files["figure.png"] = hashlib.sha256((where / "figure.png").read_bytes()).hexdigest()
    return figure, export, files


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--trials", type=int, default=100, help="trials of each grid session")
    parser.add_argument("--line-trials", type=int, default=170, help="trials on the line path")
    parser.add_argument("--rounds", type=int, default=3, help="runs of each setting")
    args = parser.parse_args()
    if min(args.trials, args.line_trials, args.rounds) < 1:
        parser.error("--trials, --line-trials and --rounds must be at least 1")
    started, load_before = time.perf_counter(), load_average()[0]
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        url = f"sqlite:///{tmp / 'lab.db'}"
        for name, trials in (
            ("exo-2d-rated", args.trials),
            ("synthetic-2d", args.trials),
            ("line", args.line_trials),
        ):
            sid, gaits = _make(url, name, trials)
            times: dict[bool, tuple[list[float], list[float]]] = {True: ([], []), False: ([], [])}
            seen: set[str] = set()
            differing: set[str] = set()
            reference: dict[str, str] | None = None
            (tmp / f"{name}-warm").mkdir()
            _one(url, sid, tmp / f"{name}-warm")  # warm-up, not timed (imports, fonts)
            for r in range(args.rounds):
                for lifted in (True, False):
                    _lift(lifted)
                    where = tmp / f"{name}-{r}-{lifted}"
                    where.mkdir()
                    figure, export, files = _one(url, sid, where)
                    _lift(False)
                    times[lifted][0].append(figure)
                    times[lifted][1].append(export)
                    seen.add(json.dumps(files, sort_keys=True))
                    reference = reference or files
                    differing |= {k for k, v in files.items() if reference.get(k) != v}
            row = {
                "session": name,
                "trials": trials,
                "gaits": gaits,
                "files": len(reference or {}),
                "identical": len(seen) == 1,
                "differing": sorted(differing),
                "times": {str(k): v for k, v in times.items()},
            }
            rows.append(row)
            print(json.dumps(row), flush=True)

    def runs(values: list[float]) -> str:
        listed = ", ".join(f"{v:.2f}" for v in values)
        return f"{statistics.median(values):.2f} s ({listed})"

    lines = [
        "# The session figure and the export: one BLAS thread against the default threads",
        "",
        f"`python benchmarks/check_blas_outputs.py --trials {args.trials} --line-trials "
        f"{args.line_trials} --rounds {args.rounds}` (the script's docstring says what is "
        f"compared): the median of {args.rounds} runs of each setting, alternating (all runs in "
        "brackets); the figure is `save_session_figure`, the export `session export` (CSV), "
        "each on a session reopened from SQLite.",
        "",
        "| session | trials | gaits (points) | files compared | same bytes | "
        "figure, default threads | figure, one thread | export, default threads | "
        "export, one thread |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        t = row["times"]
        same = "yes" if row["identical"] else "no: " + ", ".join(row["differing"])
        lines.append(
            f"| {row['session']} | {row['trials']} | {row['gaits']} | {row['files']} | {same} | "
            f"{runs(t['True'][0])} | {runs(t['False'][0])} | {runs(t['True'][1])} | "
            f"{runs(t['False'][1])} |"
        )
    lines += machine_footer("Whole check", time.perf_counter() - started, load_before)
    RESULT.write_text("\n".join(lines), encoding="utf-8")


if __name__ == "__main__":
    main()
