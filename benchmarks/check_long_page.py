"""How large the console's trial page is in a long session, and how long it takes warm.

The session is ``bench_long.py``'s *grid* one (``exo-2d-rated``, its simulated subject, an
undo every 17 answers and an exclusion every 23), driven to ``--trials`` trials in one go; the
page is fetched through FastAPI's TestClient, once to open the session and then ``--repeat``
times warm (the median is reported: the machine's load moves single fetches by a factor of 2-3),
as the recent trials (``/sessions/{id}``) and as every trial (``?trials=all``).  Results are in
the notes of benchmarks/results/long.md.

    python benchmarks/check_long_page.py [--trials 400] [--repeat 9]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
import warnings
from pathlib import Path

warnings.filterwarnings("ignore", message="Using `httpx` with `starlette.testclient`")

from fastapi.testclient import TestClient  # noqa: E402

from gaitpref import Session, load_config  # noqa: E402
from gaitpref.console import create_app  # noqa: E402

try:
    from bench_long import Subject, _drive
except ImportError:  # run as a module
    from benchmarks.bench_long import Subject, _drive


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=400)
    parser.add_argument("--repeat", type=int, default=9)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        url = f"sqlite:///{Path(folder) / 'lab.db'}"
        with Session.create(url, load_config("exo-2d-rated"), "S01", seed=1) as s:
            _drive(s, Subject(s), args.trials, 0, [])
            sid = s.id
        with TestClient(create_app(url)) as client:
            for path in (f"/sessions/{sid}", f"/sessions/{sid}?trials=all"):
                r = client.get(path)
                assert r.status_code == 200, r.text
                times = []
                for _ in range(args.repeat):
                    t0 = time.perf_counter()
                    client.get(path)
                    times.append(time.perf_counter() - t0)
                warm = statistics.median(times)
                rows = r.text.count("<tr data-trial=")
                print(
                    f"{path}: {len(r.content) / 1000:.1f} kB, {rows} trials listed, "
                    f"{1000 * warm:.0f} ms warm (median)"
                )


if __name__ == "__main__":
    main()
