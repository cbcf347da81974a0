"""The console in a real headless Chromium (Debian's, driven by Playwright): a whole session
with clicks and keyboard shortcuts, undo, validation and export; and two tabs answering the
same query, of which one answer is kept."""

from __future__ import annotations

import csv
import io
import zipfile
from pathlib import Path
from typing import Any

import httpx
import pytest

from tests.console.conftest import keys_ready

pytestmark = pytest.mark.browser


def saved(page: Any, trial: int) -> None:
    page.wait_for_selector(f"#flash:has-text('Saved: trial {trial}.')")


def asks_nothing(page: Any) -> bool:
    """The page asks no comparison: the new gait is the buffered one (the page says so, as the
    terminal does; it asked the gait against itself, an answer kept and not modelled)."""
    if page.locator("fieldset[data-kind=comparison]").count():
        return False
    assert "are the same gait: nothing to compare" in page.inner_text(".not-asked")
    return True


def answer_by_clicks(page: Any, trial: int, comparison: str | None, move: str) -> None:
    if comparison is not None and not asks_nothing(page):
        page.click(f"fieldset[data-kind=comparison] label.choice:has-text('{comparison}')")
    page.click(f"fieldset[data-kind=suggestion] label.choice:has-text('{move}')")
    page.click("#review")
    page.wait_for_selector("#confirm-dialog[open]")
    page.click("#confirm-dialog [data-confirm-yes]")
    saved(page, trial)


def answer_by_keys(page: Any, trial: int, keys: str) -> None:
    """``keys``: the comparison's digit first (left out where the page asks none), then the
    suggestion's letter."""
    if asks_nothing(page):
        keys = keys[1:]
    keys_ready(page)
    for key in keys:
        page.keyboard.press(key)
    page.keyboard.press("Enter")  # review
    page.wait_for_selector("#confirm-dialog[open]")
    page.keyboard.press("Enter")  # confirm
    saved(page, trial)


def test_a_whole_session_in_the_browser(chromium: Any, live: str, tmp_path: Path) -> None:
    context = chromium.new_context(accept_downloads=True, viewport={"width": 1280, "height": 1000})
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.goto(live + "/")
    page.fill("#subject", "S01")
    page.select_option("#config", "exo-1d-step-length")
    page.click("#create")
    page.wait_for_selector("text=Run now: trial 1")
    assert page.url.endswith("/sessions/1")

    # trial 1 has nothing to compare with yet: a suggestion only
    answer_by_clicks(page, 1, None, "slightly longer")
    # a comparison must be answered before the review opens
    keys_ready(page)
    page.keyboard.press("Enter")
    assert page.is_visible("#hint") and not page.is_visible("#confirm-dialog")
    nothing_asked = []
    for trial in range(2, 11):
        if asks_nothing(page):
            nothing_asked.append(trial)
        if trial % 2:
            choice = "this one" if trial % 3 else "no preference"
            answer_by_clicks(page, trial, choice, "shorter" if trial == 5 else "no change")
        else:
            answer_by_keys(page, trial, "1w" if trial < 8 else "2e")
    assert page.locator("#chronology tbody tr").count() == 10
    assert page.locator("text=Run now: trial 11").count() == 1
    # trials 3 and 6 walk the gait of the trial before: nothing to compare, nothing asked
    assert nothing_asked == [3, 6]

    # undo the last answer with its shortcut, then answer trial 10 again
    keys_ready(page)
    page.keyboard.press("u")
    page.wait_for_selector("#confirm-dialog[open]")
    page.keyboard.press("Enter")
    page.wait_for_selector("#flash:has-text('Undone')")
    assert page.locator("text=Run now: trial 10").count() == 1
    assert page.locator("#chronology tbody tr").count() == 9
    answer_by_keys(page, 10, "1")
    info = httpx.get(f"{live}/api/sessions/1").json()
    assert info["trials"] == 10
    page.wait_for_function("document.getElementById('posterior').naturalWidth > 0")  # the figure

    # blind validation: keys A/B/C rank, Enter reviews, Enter confirms
    page.click("#validation-link")
    page.click("#start-validation")
    page.wait_for_selector("#ranking-form")
    keys_ready(page)
    for key in ("b", "a", "c"):
        page.keyboard.press(key)
    assert page.input_value("#rank1") == "B" and page.input_value("#rank3") == "C"
    page.keyboard.press("Enter")
    page.wait_for_selector("#confirm-dialog[open]")
    page.keyboard.press("Enter")
    page.wait_for_selector("#round-1")
    assert page.locator("#tau-1").inner_text() in {"1.00", "0.33", "-0.33", "-1.00"}

    # export from the trial page
    page.goto(f"{live}/sessions/1")
    with page.expect_download() as download:
        page.click("#export-csv")
    path = tmp_path / "export.zip"
    download.value.save_as(path)
    with zipfile.ZipFile(path) as zf:
        rows = list(csv.DictReader(io.StringIO(zf.read("session-1/trials.csv").decode())))
        compared = list(csv.DictReader(io.StringIO(zf.read("session-1/comparisons.csv").decode())))
    kept = [r for r in rows if r["undone"] == "false"]
    assert [int(r["trial"]) for r in kept] == list(range(1, 11))
    assert compared and all(r["first_action"] != r["second_action"] for r in compared)
    assert errors == []
    context.close()


def test_two_tabs_answering_the_same_query_keep_one_answer(chromium: Any, live: str) -> None:
    sid = httpx.post(
        f"{live}/api/sessions", json={"config": "exo-1d-step-length", "subject": "S02"}
    ).json()["id"]
    q = httpx.get(f"{live}/api/sessions/{sid}/query").json()
    httpx.post(f"{live}/api/sessions/{sid}/answers", json={"query_id": q["query_id"]})
    context = chromium.new_context()
    first, second = context.new_page(), context.new_page()
    for page in (first, second):
        page.goto(f"{live}/sessions/{sid}")
        page.wait_for_selector("text=Run now: trial 2")
    answer_by_keys(first, 2, "1")
    keys_ready(second)
    for key in ("2", "Enter"):
        second.keyboard.press(key)
    second.wait_for_selector("#confirm-dialog[open]")
    second.keyboard.press("Enter")
    second.wait_for_selector("#error")
    assert "already answered" in second.inner_text("#error")
    assert "Nothing was written" in second.inner_text("#error")
    log = httpx.get(f"{live}/api/sessions/{sid}/events").json()
    outcomes = [e["payload"]["outcome"] for e in log if e["kind"] == "comparison_answered"]
    assert outcomes == ["first"]  # the first tab's answer, once
    second.click("#back-to-trial")
    second.wait_for_selector("text=Run now: trial 3")
    context.close()
