"""Issue 13's browser test: a session on a continuous 3-parameter space with gaits made on demand
(the shipped ``compass-continuous-3d``: compass-hzd over continuous step length and duration and
a step-width label), created and answered in a real headless Chromium: each trial's gait id is
shown as it is run and logged as shown, the posterior figure is drawn, and undo works."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import httpx
import pytest

from tests.console.test_browser import answer_by_clicks

pytestmark = pytest.mark.browser

ID = re.compile(r"L\d\.\d{3}-T\d\.\d{3}-W\d\.\d{3}#[0-9a-f]{8}")


def test_a_continuous_session_with_gaits_on_demand_in_the_browser(
    chromium: Any, live: str, tmp_path: Path
) -> None:
    context = chromium.new_context(viewport={"width": 1280, "height": 1000})
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.goto(live + "/")
    assert "continuous: step_length, step_duration, step_width" in page.inner_text("#config")
    page.fill("#subject", "S01")
    page.select_option("#config", "compass-continuous-3d")
    page.click("#create")
    page.wait_for_selector("text=Run now: trial 1")
    shown = []
    for trial in range(1, 7):
        now = ID.findall(page.inner_text("main"))
        assert now, f"trial {trial}: the page shows the gait id to run"
        shown.append(now[0])
        answer_by_clicks(page, trial, None if trial == 1 else "this one", "no change")
    events = httpx.get(f"{live}/api/sessions/1/events").json()
    logged = [e["payload"]["gait_id"] for e in events if e["kind"] == "trial_executed"]
    assert len(logged) == 6 and all(ID.fullmatch(g) for g in logged)
    assert logged == shown  # the gait run at each trial is the one the page named
    made = {e["payload"]["gait_id"] for e in events if e["kind"] == "gait_made"}
    assert set(logged) <= made
    chronology = page.locator("#chronology tbody").inner_text()
    assert all(g in chronology for g in logged)
    src = page.get_attribute("#posterior", "src")
    png = httpx.get(f"{live}{src}")  # no grid to draw: the posterior at the trials' points
    assert png.status_code == 200 and png.content.startswith(b"\x89PNG")
    page.wait_for_function(
        "() => { const i = document.querySelector('#posterior'); "
        "return i.complete && i.naturalWidth > 0; }"
    )
    assert errors == []
    context.close()
