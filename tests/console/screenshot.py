"""Take the README's screenshot of the trial page: ``python -m tests.console.screenshot``.

A 2-D session (exo-2d-length-duration) is answered for eight trials by a simulated subject
through the JSON API of a live console; the ninth trial's page is then shown in Chromium with a
comparison and a suggestion chosen, and saved to ``docs/console-trial.png``.
"""

from __future__ import annotations

import argparse
import tempfile
import warnings
from pathlib import Path

import httpx

from gaitpref.config import load_config
from gaitpref.console import create_app
from gaitpref.loop.cospar import Query
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from tests.console.live import launch_chromium, serve

CONFIG = "exo-2d-length-duration"


def answer_trials(base: str, trials: int) -> int:
    space = load_config(CONFIG).space
    subject = SimulatedSubject(space, bump_utility(space), seed=3)
    sid = int(
        httpx.post(f"{base}/api/sessions", json={"config": CONFIG, "subject": "S01"}).json()["id"]
    )
    for _ in range(trials):
        q = httpx.get(f"{base}/api/sessions/{sid}/query").json()

        actions = tuple(g["index"] for g in q["actions"])
        buffer = tuple(g["index"] for g in q["buffer"])
        comps, suggs = subject.respond(Query(q["query_id"], actions, buffer))  # type: ignore[arg-type]
        body = {
            "query_id": q["query_id"],
            "comparisons": [[c.first, c.second, c.outcome] for c in comps],
            "suggestions": [[s.action, s.feature, s.move] for s in suggs],
        }
        httpx.post(f"{base}/api/sessions/{sid}/answers", json=body).raise_for_status()
    return sid


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("docs/console-trial.png"))
    parser.add_argument("--trials", type=int, default=8)
    parser.add_argument("--full", action="store_true", help="the whole page, not the screen")
    args = parser.parse_args()
    warnings.filterwarnings("ignore")
    from playwright.sync_api import sync_playwright

    with (
        tempfile.TemporaryDirectory() as tmp,
        serve(create_app(f"sqlite:///{tmp}/shot.db")) as base,
    ):
        sid = answer_trials(base, args.trials)
        with sync_playwright() as p:
            browser = launch_chromium(p)
            page = browser.new_page(viewport={"width": 1366, "height": 1024}, device_scale_factor=1)
            page.goto(f"{base}/sessions/{sid}")
            page.wait_for_function("document.getElementById('posterior').naturalWidth > 0")
            page.wait_for_selector("html[data-keys=ready]", state="attached")  # keys taken
            page.keyboard.press("1")  # this one
            page.keyboard.press("w")  # step length: slightly longer
            page.mouse.move(0, 0)
            args.out.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(args.out), full_page=args.full)
            browser.close()
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
