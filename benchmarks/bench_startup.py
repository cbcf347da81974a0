"""Start-up time of the ``gaitpref`` command against bare ``python -c "import numpy"``.

Times, in the same run and interleaved (round robin, so a change in machine load hits every
command alike): ``import numpy``, ``import gaitpref``, ``gaitpref --help`` and
``gaitpref session list --db <a SQLite file with 3 sessions>``; each in a fresh interpreter,
``--runs`` times after one warm-up, reporting the median and the spread (as hyperfine does).  The
target (issue 11): ``gaitpref --help`` within 1.5x of ``import numpy``.  The ``gaitpref`` command
is run as its console script does (``from gaitpref.cli import main; main()``) with this
checkout's ``src/`` first on the path.  Also records where the import time of ``--help`` and
``session list`` goes (``python -X importtime``).  Writes ``benchmarks/results/startup.md``.

    python benchmarks/bench_startup.py [--runs 21]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _machine import machine_description, machine_markdown

ROOT = Path(__file__).resolve().parents[1]
RESULT = ROOT / "benchmarks" / "results" / "startup.md"
CLI = "from gaitpref.cli import main; main()"
TARGET = 1.5


def _env() -> dict[str, str]:
    path = os.environ.get("PYTHONPATH", "")
    return {
        **os.environ,
        "PYTHONPATH": str(ROOT / "src") + (os.pathsep + path if path else ""),
        "COLUMNS": "120",
        "NO_COLOR": "1",
    }


def commands(db: str) -> dict[str, list[str]]:
    py = sys.executable
    return {
        'python -c "import numpy"': [py, "-c", "import numpy"],
        'python -c "import gaitpref"': [py, "-c", "import gaitpref"],
        "gaitpref --help": [py, "-c", CLI, "--help"],
        "gaitpref session list --db <sqlite>": [py, "-c", CLI, "session", "list", "--db", db],
    }


def _once(argv: list[str], env: dict[str, str]) -> float:
    start = time.perf_counter()
    subprocess.run(argv, env=env, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def time_all(cmds: dict[str, list[str]], runs: int) -> dict[str, list[float]]:
    env = _env()
    times: dict[str, list[float]] = {name: [] for name in cmds}
    for argv in cmds.values():  # warm-up: the file cache, .pyc files
        _once(argv, env)
    for _ in range(runs):
        for name, argv in cmds.items():
            times[name].append(_once(argv, env))
    return times


def import_time_by_package(argv: list[str], top: int = 8) -> list[tuple[str, float]]:
    """Import time (ms, the modules' own time summed by top-level package) for ``argv``."""
    run = subprocess.run(
        [argv[0], "-X", "importtime", *argv[1:]],
        env=_env(),
        capture_output=True,
        text=True,
        check=True,
    )
    totals: dict[str, float] = {}
    for line in run.stderr.splitlines():
        if not line.startswith("import time:") or "cumulative" in line:
            continue
        self_us, _, name = line.removeprefix("import time:").split("|")
        package = name.strip().split(".")[0]
        totals[package] = totals.get(package, 0.0) + int(self_us) / 1000
    return sorted(totals.items(), key=lambda kv: -kv[1])[:top]


def make_db(folder: Path) -> str:
    from gaitpref import Session

    url = f"sqlite:///{folder / 'bench.db'}"
    for k in range(3):
        Session.create(url, "exo-1d-step-length", f"S0{k + 1}", seed=k).close()
    return url


def report(
    times: dict[str, list[float]], imports: dict[str, list[tuple[str, float]]], runs: int
) -> str:
    base = statistics.median(times['python -c "import numpy"'])
    rows = []
    for name, ts in times.items():
        med = statistics.median(ts)
        q = statistics.quantiles(ts, n=10)
        rows.append(
            f"| `{name}` | {med * 1000:.0f} | {min(ts) * 1000:.0f} | {q[0] * 1000:.0f}-"
            f"{q[-1] * 1000:.0f} | {med / base:.2f}x |"
        )
    help_ratio = statistics.median(times["gaitpref --help"]) / base
    verdict = "meets" if help_ratio <= TARGET else "misses"
    lines = [
        "# Start-up time: `import gaitpref` and the `gaitpref` command",
        "",
        f"`python benchmarks/bench_startup.py` - each command in a fresh interpreter, {runs} runs "
        "after one warm-up, interleaved; wall clock including interpreter start.",
        "",
        "| command | median (ms) | min (ms) | 10-90% (ms) | vs `import numpy` |",
        "|---|---|---|---|---|",
        *rows,
        "",
        f"`gaitpref --help` is {help_ratio:.2f}x bare `import numpy`: it {verdict} the target "
        f"({TARGET}x). `import gaitpref` loads only `gaitpref.errors` (the public names load on "
        "first use); `--help` loads Typer, Click and parts of Rich, no NumPy; `session list` "
        "loads SQLAlchemy and reads the database, without the model, SciPy's optimizers, "
        "matplotlib or a web framework (`tests/cli/test_startup.py`); most of its time is "
        "SQLAlchemy and Alembic (with Mako and Pygments), imported by `gaitpref.storage` to "
        "check the schema revision.",
        "",
        "Where the import time goes (`-X importtime`, one run, each module's own time summed by "
        "top-level package; the largest first):",
        "",
        *(
            f"- `{name}`: " + ", ".join(f"{pkg} {ms:.0f} ms" for pkg, ms in rows)
            for name, rows in imports.items()
        ),
        "",
        "Machine:",
        "",
        machine_markdown(machine_description()),
        "",
    ]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=21)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        cmds = commands(make_db(Path(tmp)))
        times = time_all(cmds, args.runs)
        imports = {
            name: import_time_by_package(cmds[name])
            for name in ("gaitpref --help", "gaitpref session list --db <sqlite>")
        }
    text = report(times, imports, args.runs)
    RESULT.write_text(text, encoding="utf-8")
    print(text)


if __name__ == "__main__":
    main()
