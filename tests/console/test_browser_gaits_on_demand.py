"""A session with gaits made on demand (``[gaits] generator = "compass-hzd"``), run in a real
headless Chromium: the config uploaded, every gait optimised when first proposed, the 0.02 m
steps (no gait at 0.2 m/s) skipped and listed, never offered as a trial.  The issue's browser
test on a continuous 3-parameter space is ``test_browser_continuous.py``; this one is on a grid.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import httpx
import pytest

from tests.console.test_browser import answer_by_clicks
from tests.sessions.gaitkit import COMPASS

pytestmark = pytest.mark.browser


def test_gaits_on_demand_in_the_browser(chromium: Any, live: str, tmp_path: Path) -> None:
    config = tmp_path / "on-demand.toml"
    config.write_text(COMPASS, encoding="utf-8")
    context = chromium.new_context(viewport={"width": 1280, "height": 1000})
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.goto(live + "/")
    page.fill("#subject", "S01")
    page.set_input_files("input[name=config_file]", str(config))
    page.click("#create")
    page.wait_for_selector("text=Run now: trial 1")
    answer_by_clicks(page, 1, None, "no change")
    for trial in range(2, 6):
        answer_by_clicks(page, trial, "this one", "no change")
    assert page.locator("text=Gaits that could not be made").count() == 1
    skipped = page.locator("ul.infeasible li")
    assert skipped.count() == 1 and "L0.020-V0.200" in skipped.inner_text()
    walked = page.locator("#chronology tbody").inner_text()
    assert walked.count("-V0.200") >= 5 and "L0.020" not in walked
    events = httpx.get(f"{live}/api/sessions/1/events").json()
    kinds = [e["kind"] for e in events]
    assert kinds.count("gait_infeasible") == 1 and kinds.count("gait_made") >= 4
    assert errors == []
    context.close()
