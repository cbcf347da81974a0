"""A warm-started session in a real headless Chromium: an earlier subject's session answered
through the API, a new one created from the sessions page with "Warm start from" filled in,
and the confidence on the trial page after every answer."""

from __future__ import annotations

import re
from typing import Any

import httpx
import pytest

pytestmark = pytest.mark.browser

CONFIG = "exo-1d-step-length"
SENTENCE = re.compile(r"^\d+% that G\d+ is within 5% of the best$")


def _earlier_session(live: str, answers: int) -> tuple[int, int]:
    """Session of S01 with ``answers`` answers (every comparison: first); its event count."""
    sid = int(
        httpx.post(f"{live}/api/sessions", json={"config": CONFIG, "subject": "S01"}).json()["id"]
    )
    for _ in range(answers):
        q = httpx.get(f"{live}/api/sessions/{sid}/query").json()
        body = {
            "query_id": q["query_id"],
            "comparisons": [[i, j, "first"] for i, j in q["comparisons"]],
        }
        assert httpx.post(f"{live}/api/sessions/{sid}/answers", json=body).status_code == 200
    return sid, len(httpx.get(f"{live}/api/sessions/{sid}/events").json())


def test_a_warm_started_session_from_the_create_form(chromium: Any, live: str) -> None:
    earlier, events = _earlier_session(live, 5)
    page = chromium.new_page(viewport={"width": 1280, "height": 1000})
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.goto(live + "/")
    page.fill("#subject", "S02")
    page.select_option("#config", CONFIG)
    page.fill("#prior_from", "S01")
    page.click("#create")
    page.wait_for_selector("text=Run now: trial 1")
    sid = int(page.url.rsplit("/", 1)[1])
    assert sid != earlier
    assert page.inner_text("#warm") == f"Warm-started from session {earlier}."
    # a warm start made now starts the subject alone (prior_share_gate): the confidence comes
    # with their answers, as in a cold session

    for trial in (1, 2, 3):
        if trial > 1:
            page.click("fieldset[data-kind=comparison] label.choice:has-text('this one')")
        page.click("fieldset[data-kind=suggestion] label.choice:has-text('no change')")
        page.click("#review")
        page.wait_for_selector("#confirm-dialog[open]")
        page.click("#confirm-dialog [data-confirm-yes]")
        page.wait_for_selector(f"#flash:has-text('Saved: trial {trial}.')")
        if trial == 1:  # no comparison yet ("no change" alone): nothing learnt
            continue
        assert SENTENCE.match(page.inner_text("#confidence b")), f"no confidence after {trial}"
        assert "expected shortfall" in page.inner_text("#confidence")

    created = httpx.get(f"{live}/api/sessions/{sid}/events").json()[0]["payload"]
    assert [p["session"] for p in created["prior_from"]] == [earlier]
    assert len(httpx.get(f"{live}/api/sessions/{earlier}/events").json()) == events  # only read
    assert errors == []
    page.close()
