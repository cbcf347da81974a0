"""The console under load: 20 clients on loopback against one console serving three sessions.

One console (uvicorn, its own process, SQLite in a temporary folder) serves three sessions of
``exo-2d-length-duration``; ``--clients`` threads (default 20, a third per session) loop for
``--seconds`` (default 60): get the pending query, answer it (every comparison "first"), get the
next query, then fetch the posterior figure as the trial page's browser does.  Measured:

- ``answer + next query``: POST .../answers (200) then GET .../query, per accepted answer;
- ``stale``: answers refused with 409 because another client answered that query first (the
  expected outcome of several clients on one session; nothing written);
- ``posterior figure``: GET .../posterior.png, drawn once per answer and cached;
- any 5xx or transport error (none expected).

Target (issue 15): answer + next query p99 under 300 ms on these 2-core machines, with the
posterior figure drawn off the answer's request path.

    python benchmarks/bench_console_load.py [--clients 20] [--seconds 60] [--note "..."]

Writes benchmarks/results/console_load.md and console_load.json.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import socket
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path

import httpx

try:
    from _machine import machine_description, machine_markdown
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown

RESULTS = Path(__file__).parent / "results"
CONFIG = "exo-2d-length-duration"
SESSIONS = 3


def _serve(url: str, port: int) -> None:  # pragma: no cover - runs in the server process
    import uvicorn

    from gaitpref.console import create_app

    uvicorn.run(create_app(url), host="127.0.0.1", port=port, log_level="warning")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _client(base: str, sid: int, until: float, out: dict[str, list[float]], tally: Counter[str]):  # type: ignore[no-untyped-def]
    with httpx.Client(base_url=base, timeout=30) as c:
        while time.perf_counter() < until:
            try:
                q = c.get(f"/api/sessions/{sid}/query")
                if q.status_code != 200:
                    tally[f"query {q.status_code}"] += 1
                    continue
                body = {
                    "query_id": q.json()["query_id"],
                    "comparisons": [[i, j, "first"] for i, j in q.json()["comparisons"]],
                }
                t0 = time.perf_counter()
                a = c.post(f"/api/sessions/{sid}/answers", json=body)
                if a.status_code == 409:
                    tally["stale (409)"] += 1
                    continue
                if a.status_code != 200:
                    tally[f"answer {a.status_code}"] += 1
                    continue
                nxt = c.get(f"/api/sessions/{sid}/query")
                took = time.perf_counter() - t0
                tally["accepted"] += 1
                if nxt.status_code != 200:
                    tally[f"next query {nxt.status_code}"] += 1
                    continue
                out["answer + next query"].append(took)
                t1 = time.perf_counter()
                png = c.get(f"/sessions/{sid}/posterior.png")
                out["posterior figure"].append(time.perf_counter() - t1)
                if png.status_code != 200:
                    tally[f"figure {png.status_code}"] += 1
            except httpx.HTTPError as exc:
                tally[f"transport {type(exc).__name__}"] += 1


def _pct(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return round(1000 * ordered[min(len(ordered) - 1, int(q * len(ordered)))], 1)


def run(clients: int, seconds: float) -> tuple[dict[str, dict[str, float]], dict[str, int]]:
    with tempfile.TemporaryDirectory() as tmp:
        url, port = f"sqlite:///{tmp}/load.db", _free_port()
        server = multiprocessing.get_context("spawn").Process(target=_serve, args=(url, port))
        server.start()
        base = f"http://127.0.0.1:{port}"
        try:
            deadline = time.monotonic() + 60
            while True:
                try:
                    httpx.get(f"{base}/api/configs", timeout=2)
                    break
                except httpx.HTTPError:
                    if time.monotonic() > deadline or not server.is_alive():
                        raise RuntimeError("the console did not start") from None
                    time.sleep(0.2)
            sids = [
                httpx.post(
                    f"{base}/api/sessions", json={"config": CONFIG, "subject": f"L{k}"}
                ).json()["id"]
                for k in range(SESSIONS)
            ]
            out: dict[str, list[float]] = {"answer + next query": [], "posterior figure": []}
            tally: Counter[str] = Counter()
            until = time.perf_counter() + seconds
            threads = [
                threading.Thread(target=_client, args=(base, sids[k % SESSIONS], until, out, tally))
                for k in range(clients)
            ]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
        finally:
            server.terminate()
            server.join(10)
    stats = {
        name: {
            "count": len(v),
            "p50_ms": _pct(v, 0.5) if v else float("nan"),
            "p99_ms": _pct(v, 0.99) if v else float("nan"),
            "max_ms": round(1000 * max(v), 1) if v else float("nan"),
        }
        for name, v in out.items()
    }
    return stats, dict(tally)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clients", type=int, default=20)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--note", default="", help="a line about the conditions of this run")
    args = parser.parse_args()
    stats, tally = run(args.clients, args.seconds)
    machine = machine_description()
    RESULTS.mkdir(exist_ok=True)
    payload = {
        "clients": args.clients,
        "seconds": args.seconds,
        "sessions": SESSIONS,
        "results": stats,
        "outcomes": tally,
        "machine": machine,
        "note": args.note,
    }
    (RESULTS / "console_load.json").write_text(json.dumps(payload, indent=2) + "\n")
    lines = [
        "# The console under load (benchmarks/bench_console_load.py)",
        "",
        f"{args.clients} clients on loopback for {args.seconds:g} s against one console (uvicorn, "
        f"its own process, SQLite) serving {SESSIONS} `{CONFIG}` sessions; each client gets the "
        "query, answers, gets the next query, then fetches the posterior figure. "
        "Target: answer + next query p99 < 300 ms.",
        "",
        "| step | count | p50 | p99 | max |",
        "|---|---|---|---|---|",
        *[
            f"| {n} | {s['count']} | {s['p50_ms']} ms | {s['p99_ms']} ms | {s['max_ms']} ms |"
            for n, s in stats.items()
        ],
        "",
        "Outcomes: " + ", ".join(f"{k}: {v}" for k, v in sorted(tally.items())),
        "",
        *([args.note, ""] if args.note else []),
        "Machine:",
        "",
        machine_markdown(machine),
        "",
    ]
    (RESULTS / "console_load.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
