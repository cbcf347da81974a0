"""Run every speed benchmark (every ``benchmarks/bench_*.py``, in name order: console, core,
gaits, large, sessions, startup, sweeps, threads, ...); each records its results in results/."""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).parent


def main() -> int:
    # no options: --help shows the docstring, anything else is refused before any benchmark
    argparse.ArgumentParser(description=__doc__).parse_args()
    failed = []
    for script in sorted(HERE.glob("bench_*.py")):
        print(f"== {script.name}", flush=True)
        if subprocess.call([sys.executable, str(script)], cwd=HERE.parent) != 0:
            failed.append(script.name)
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
