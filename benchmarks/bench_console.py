"""Responsiveness of the operator console on the paper's 30 x 30 synthetic grid at 150 trials.

A session of the synthetic-2d config (n = 1, b = 1, coactive) is filled with 130 answers from a
simulated subject (the paper's objective 0) through the session API; then, for trials 131-170,
each step is timed as the operator's browser does it, through the console's ASGI app (FastAPI's
TestClient, SQLite in a temporary folder):

- ``answer + next page``: POST the confirmed answer form (303), then GET the trial page it
  redirects to (the next query is issued and logged, the page rendered);
- ``API answer + query``: POST /api/sessions/{id}/answers then GET .../query (a device script);
- ``posterior figure``: GET the trial page's posterior PNG (drawn once per answer, then cached;
  the browser fetches it after the page, so it is not part of the page's time).

Target (issue 6): answer + next page under 100 ms at 150 trials.

    python benchmarks/bench_console.py [--warm 130] [--timed 40]

Writes benchmarks/results/console.md and console.json.
"""

from __future__ import annotations

import argparse
import json
import re
import statistics
import tempfile
import time
import warnings
from pathlib import Path

warnings.filterwarnings("ignore", message="Using `httpx` with `starlette.testclient`")

from fastapi.testclient import TestClient  # noqa: E402

from gaitpref.console import create_app  # noqa: E402
from gaitpref.data import paper_objectives  # noqa: E402
from gaitpref.sessions.demo import SimulatedSubject  # noqa: E402

try:
    from _machine import machine_description, machine_markdown
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown

RESULTS = Path(__file__).parent / "results"


def _form(
    html: str, comparisons: list[tuple[int, int, str]], suggestions: list[object]
) -> dict[str, str]:
    token = re.search(r'name="csrf_token" value="([^"]+)"', html)
    query = re.search(r'name="query_id" value="(\d+)"', html)
    assert token and query, "the trial page has no answer form"
    data = {"csrf_token": token.group(1), "query_id": query.group(1), "confirmed": "1"}
    for i, j, outcome in comparisons:
        data[f"cmp-{i}-{j}"] = outcome
    for s in suggestions:
        data[f"sug-{s.action}-{s.feature}"] = s.move  # type: ignore[attr-defined]
    return data


def _stats(values: list[float]) -> dict[str, float]:
    ms = sorted(v * 1000 for v in values)
    return {
        "median_ms": round(statistics.median(ms), 1),
        "p90_ms": round(ms[int(0.9 * (len(ms) - 1))], 1),
        "max_ms": round(ms[-1], 1),
    }


def run(warm: int, timed: int) -> dict[str, dict[str, float]]:
    objective = paper_objectives()[0].reshape(-1)
    with tempfile.TemporaryDirectory() as tmp, TestClient(create_app(f"sqlite:///{tmp}/b.db")) as c:
        service = c.app.state.service  # type: ignore[attr-defined]
        session = service.create("synthetic-2d", "B01")
        subject = SimulatedSubject(session.config.space, objective, seed=0)
        for _ in range(warm):
            q = session.next_query()
            comps, suggs = subject.respond(q)
            session.answer(q.id, comps, suggs)
        sid = session.id
        page, answer_page, api, figure = c.get(f"/sessions/{sid}"), [], [], []
        for k in range(timed):
            q = session.pending
            comps, suggs = subject.respond(q)
            triples = [(x.first, x.second, x.outcome) for x in comps]
            if k % 2 == 0:  # the operator's browser: form post, redirect, next page
                data = _form(page.text, triples, suggs)
                t0 = time.perf_counter()
                r = c.post(f"/sessions/{sid}/answer", data=data, follow_redirects=False)
                page = c.get(r.headers["location"])
                answer_page.append(time.perf_counter() - t0)
                assert r.status_code == 303 and page.status_code == 200
            else:  # a device script through the API
                body = {
                    "query_id": q.id,
                    "comparisons": [list(t) for t in triples],
                    "suggestions": [[s.action, s.feature, s.move] for s in suggs],
                }
                t0 = time.perf_counter()
                r = c.post(f"/api/sessions/{sid}/answers", json=body)
                nxt = c.get(f"/api/sessions/{sid}/query")
                api.append(time.perf_counter() - t0)
                assert r.status_code == 200 and nxt.status_code == 200
                page = c.get(f"/sessions/{sid}")
            t0 = time.perf_counter()
            png = c.get(re.search(r'<img src="([^"]+)"', page.text).group(1))  # type: ignore[union-attr]
            figure.append(time.perf_counter() - t0)
            assert png.status_code == 200
        assert len(session.trials()) == warm + timed
    return {
        "answer + next page": _stats(answer_page),
        "API answer + query": _stats(api),
        "posterior figure (PNG)": _stats(figure),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--warm", type=int, default=130, help="answers before timing")
    parser.add_argument("--timed", type=int, default=40, help="answers timed")
    args = parser.parse_args()
    start = time.perf_counter()
    results = run(args.warm, args.timed)
    machine = machine_description()
    RESULTS.mkdir(exist_ok=True)
    payload = {"warm": args.warm, "timed": args.timed, "results": results, "machine": machine}
    (RESULTS / "console.json").write_text(json.dumps(payload, indent=2) + "\n")
    lines = [
        "# Console responsiveness (benchmarks/bench_console.py)",
        "",
        f"Synthetic-2d session (30 x 30 grid, n = 1, b = 1, coactive), trials {args.warm + 1}-"
        f"{args.warm + args.timed} timed through the console's ASGI app (TestClient, SQLite); half "
        "of them through the pages, half through the API. Target: answer + next page < 100 ms.",
        "",
        "| step | median | p90 | max |",
        "|---|---|---|---|",
        *[
            f"| {name} | {s['median_ms']} ms | {s['p90_ms']} ms | {s['max_ms']} ms |"
            for name, s in results.items()
        ],
        "",
        f"Whole benchmark: {time.perf_counter() - start:.1f} s.",
        "",
        "Machine:",
        "",
        machine_markdown(machine),
        "",
    ]
    (RESULTS / "console.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
