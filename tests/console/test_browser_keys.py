"""The trial page from the keyboard alone, as an operator at the bench uses it (one hand on the
exoskeleton, the other on the keys), in a real headless Chromium: a held key stores nothing
twice and never confirms for the operator, Enter on a focused control does what that control
does (flag unsafe by Tab and Enter), typed reasons fire no shortcut, a rating is skipped with
``0``, every control has an accessible name, and the page works without JavaScript."""

from __future__ import annotations

from typing import Any

import httpx
import pytest

from gaitpref.console.trial_page import RECENT_TRIALS
from tests.console.conftest import keys_ready
from tests.console.test_ratings_safety import rated_config

pytestmark = pytest.mark.browser

#: every control of the page without an accessible name: a label, aria-label or its own text
#: (a placeholder is not a name: it goes when the operator types)
UNNAMED = """() => {
  const bad = [];
  for (const el of document.querySelectorAll('button, summary, a, input, select, textarea, img')) {
    if (el.type === 'hidden' || el.closest('dialog:not([open])')) continue;
    let name = (el.getAttribute('aria-label') || '').trim();
    if (!name && el.tagName === 'IMG') name = (el.getAttribute('alt') || '').trim();
    if (!name && ['INPUT', 'SELECT', 'TEXTAREA'].includes(el.tagName)) {
      name = [...(el.labels || [])].map((l) => l.textContent.trim()).join(' ');
    } else if (!name) name = el.textContent.trim();
    if (!name) bad.push(el.outerHTML.slice(0, 120));
  }
  return bad;
}"""


def trials(live: str, sid: int) -> list[dict[str, Any]]:
    return list(httpx.get(f"{live}/api/sessions/{sid}/trials").json())


def open_page(chromium: Any, url: str, **options: Any) -> tuple[Any, Any, list[str]]:
    context = chromium.new_context(viewport={"width": 1280, "height": 900}, **options)
    page = context.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.goto(url)
    if options.get("java_script_enabled", True):
        keys_ready(page)
    return context, page, errors


def test_a_held_enter_reviews_but_never_confirms(chromium: Any, live: str) -> None:
    sid = httpx.post(f"{live}/api/sessions", json={"config": rated_config(), "subject": "S01"})
    sid = sid.json()["id"]
    context, page, errors = open_page(chromium, f"{live}/sessions/{sid}")
    # Enter held down: the first press opens the review, the repeats confirm nothing
    page.keyboard.down("Enter")
    page.wait_for_selector("#confirm-dialog[open]")
    for _ in range(5):
        page.keyboard.down("Enter")  # auto-repeat (KeyboardEvent.repeat)
    page.keyboard.up("Enter")
    page.wait_for_timeout(300)
    assert page.is_visible("#confirm-dialog")
    assert trials(live, sid) == []
    # a fresh press confirms: one answer
    page.keyboard.press("Enter")
    page.wait_for_selector("#flash:has-text('Saved: trial 1.')")
    keys_ready(page)
    # a held digit is one choice; a held U opens the undo's review and undoes nothing
    page.keyboard.down("u")
    page.wait_for_selector("#confirm-dialog[open]")
    page.keyboard.down("u")
    page.keyboard.down("Enter")  # Enter pressed while U is held: that one is a real press
    page.keyboard.down("Enter")
    page.keyboard.up("Enter")
    page.keyboard.up("u")
    page.wait_for_selector("#flash:has-text('Undone')")
    assert trials(live, sid) == []
    assert errors == []
    context.close()


def test_flag_unsafe_by_tab_and_enter_while_typing_fires_no_shortcut(
    chromium: Any, live: str
) -> None:
    sid = httpx.post(f"{live}/api/sessions", json={"config": rated_config(), "subject": "S02"})
    sid = sid.json()["id"]
    context, page, errors = open_page(chromium, f"{live}/sessions/{sid}")
    for key in ("Enter", "Enter"):
        page.keyboard.press(key)
        page.wait_for_timeout(50)
    page.wait_for_selector("#flash:has-text('Saved: trial 1.')")
    keys_ready(page)
    # Enter on the focused "Flag trial 1 unsafe" opens it (and does not review the answer)
    page.focus("#unsafe-last summary")
    page.keyboard.press("Enter")
    page.wait_for_selector("#unsafe-last[open]")
    assert not page.is_visible("#confirm-dialog")
    # the reason has the focus, to be typed at once
    page.wait_for_function("document.activeElement.name === 'reason'")
    assert page.evaluate("document.activeElement.closest('details').id") == "unsafe-last"
    # the reason's letters and digits are text, not shortcuts (q, w, e, 1, 2, u, m)
    page.keyboard.type("knee went 12 deg past; queue a rest, mum")
    assert page.input_value("#unsafe-last input[name=reason]") == (
        "knee went 12 deg past; queue a rest, mum"
    )
    assert page.locator("#answer-form input[type=radio]:checked:not([value=''])").count() == 0
    assert not page.is_visible("#confirm-dialog")
    page.keyboard.press("Enter")  # submits the flag's form: its review
    page.wait_for_selector("#confirm-dialog[open]")
    assert "Reason: knee went 12 deg past" in page.inner_text("#confirm-dialog ul")
    page.keyboard.press("Enter")
    page.wait_for_selector("#flash:has-text('Trial 1 flagged unsafe')")
    info = httpx.get(f"{live}/api/sessions/{sid}").json()
    assert info["unsafe"] == {"1": "knee went 12 deg past; queue a rest, mum"}
    keys_ready(page)
    # the note: typed text is no shortcut either, Esc leaves it and the keys work again
    page.keyboard.press("m")
    page.keyboard.type("1 2 0 u")
    page.keyboard.press("Escape")
    assert page.input_value("#note") == "1 2 0 u"
    assert page.locator("#answer-form input[type=radio]:checked:not([value=''])").count() == 0
    assert errors == []
    context.close()


def test_n_opens_the_last_trials_flag_which_still_takes_a_reason_and_the_confirm_step(
    chromium: Any, live: str
) -> None:
    sid = httpx.post(f"{live}/api/sessions", json={"config": rated_config(), "subject": "S08"})
    sid = sid.json()["id"]
    context, page, errors = open_page(chromium, f"{live}/sessions/{sid}")
    page.keyboard.press("n")  # no trial yet: nothing to flag, the key does nothing
    assert page.locator("#unsafe-last").count() == 0
    for key in ("Enter", "Enter"):
        page.keyboard.press(key)
        page.wait_for_timeout(50)
    page.wait_for_selector("#flash:has-text('Saved: trial 1.')")
    # the button shows its key (a flex item of its own: on a line of its own in innerText)
    assert " ".join(page.inner_text("#unsafe-last summary").split()) == "Flag trial 1 unsafe N"
    assert "N flag trial 1 unsafe" in (page.text_content("details.shortcuts ul") or "")
    keys_ready(page)
    # N while typing in a field is a letter: the note takes it, the flag stays shut
    page.keyboard.press("m")
    page.keyboard.type("no need")
    assert page.input_value("#note") == "no need"
    assert not page.is_visible("#unsafe-last input[name=reason]")
    page.keyboard.press("Escape")
    # N held down: the flag opens, the focus in its reason, and the repeats type nothing
    page.keyboard.down("n")
    page.keyboard.down("n")
    page.keyboard.down("n")
    page.keyboard.up("n")
    page.wait_for_selector("#unsafe-last[open]")
    page.wait_for_function("document.activeElement.name === 'reason'")
    assert page.evaluate("document.activeElement.closest('details').id") == "unsafe-last"
    assert page.input_value("#unsafe-last input[name=reason]") == ""
    assert not page.is_visible("#confirm-dialog")
    assert httpx.get(f"{live}/api/sessions/{sid}").json()["unsafe"] == {}  # nothing flagged
    # typed in the reason, n is a letter (it neither reopens nor leaves the field)
    page.keyboard.type("knee buckled on landing")
    assert page.input_value("#unsafe-last input[name=reason]") == "knee buckled on landing"
    page.keyboard.press("Enter")  # the flag's review
    page.wait_for_selector("#confirm-dialog[open]")
    assert page.get_by_role("dialog", name="Flag this trial unsafe?").is_visible()
    assert "Reason: knee buckled on landing" in page.inner_text("#confirm-dialog ul")
    assert httpx.get(f"{live}/api/sessions/{sid}").json()["unsafe"] == {}
    page.keyboard.press("Enter")  # confirmed
    page.wait_for_selector("#flash:has-text('Trial 1 flagged unsafe')")
    info = httpx.get(f"{live}/api/sessions/{sid}").json()
    assert info["unsafe"] == {"1": "knee buckled on landing"}
    assert page.input_value("#note") == ""  # the reload: the note was never sent
    # the last trial is flagged: no button, no key listed, N does nothing
    assert page.locator("#unsafe-last").count() == 0
    assert "flag trial" not in (page.text_content("details.shortcuts ul") or "")
    keys_ready(page)
    page.keyboard.press("n")
    page.wait_for_timeout(100)
    assert not page.is_visible("#confirm-dialog")
    assert page.locator("details.unsafe[open]").count() == 0
    assert errors == []
    context.close()


def test_a_rating_is_skipped_with_0(chromium: Any, live: str) -> None:
    sid = httpx.post(f"{live}/api/sessions", json={"config": rated_config(), "subject": "S03"})
    sid = sid.json()["id"]
    context, page, errors = open_page(chromium, f"{live}/sessions/{sid}")
    skip = "fieldset[data-kind=rating] label.choice:has-text('no rating')"
    assert page.inner_text(f"{skip} kbd") == "0"
    page.keyboard.press("3")
    assert page.is_checked("fieldset[data-kind=rating] input[value='3']")
    page.keyboard.press("0")  # changed their mind: the trial goes unrated
    assert page.is_checked(f"{skip} input")
    # the review's Confirm takes the focus; Esc goes back to where it was
    page.click("fieldset[data-kind=rating] label.choice:has(input[value='2'])")
    page.keyboard.press("Enter")
    page.wait_for_selector("#confirm-dialog[open]")
    assert page.evaluate("document.activeElement.hasAttribute('data-confirm-yes')")
    page.keyboard.press("Escape")
    assert page.evaluate("document.activeElement.value") == "2"
    page.keyboard.press("0")
    assert page.is_checked(f"{skip} input")
    page.keyboard.press("Enter")
    page.wait_for_selector("#confirm-dialog[open]")
    page.keyboard.press("Enter")
    page.wait_for_selector("#flash:has-text('Saved: trial 1.')")
    assert [t["rating"] for t in trials(live, sid)] == [None]
    assert errors == []
    context.close()


def test_every_control_is_named_and_the_figure_described(chromium: Any, live: str) -> None:
    sid = httpx.post(f"{live}/api/sessions", json={"config": rated_config(), "subject": "S04"})
    sid = sid.json()["id"]
    context, page, errors = open_page(chromium, f"{live}/sessions/{sid}")
    page.keyboard.press("4")
    page.keyboard.press("Enter")
    page.wait_for_selector("#confirm-dialog[open]")
    # the confirm step is a dialog named by its question (as a screen reader announces it)
    assert page.get_by_role("dialog", name="Save this answer?").is_visible()
    page.keyboard.press("Enter")
    page.wait_for_selector("#flash:has-text('Saved: trial 1.')")
    page.evaluate("for (const d of document.querySelectorAll('details')) d.open = true")
    assert page.evaluate(UNNAMED) == []
    # the history's per-trial controls say which trial they act on
    row = "tr[data-trial='1']"
    assert page.get_attribute(f"{row} details.unsafe summary", "aria-label") == (
        "Flag trial 1 unsafe"
    )
    assert page.get_attribute(f"{row} details.exclude summary", "aria-label") == "Exclude trial 1"
    # the figure's text alternative says what it shows, the best gait included
    alt = page.get_attribute("#posterior", "alt") or ""
    assert alt.startswith("The model's utility over step length after 1 trial;")
    if page.locator("b#best").count():
        assert f"the best so far, {page.inner_text('b#best')}, is starred" in alt
    else:
        assert "no preference learned yet" in alt
    assert "region of avoidance are shaded grey and hatched" in alt  # the config avoids
    page.goto(f"{live}/sessions/{sid}/validation")
    page.click("#start-validation")
    page.wait_for_selector("#ranking-form")
    keys_ready(page)
    assert page.evaluate(UNNAMED) == []
    # picked by clicks, then Enter on the focused pick button reviews the ranking (as documented)
    for label in ("B", "A", "C"):
        page.click(f"[data-pick={label}]")
    page.keyboard.press("Enter")
    page.wait_for_selector("#confirm-dialog[open]")
    assert page.get_by_role("dialog", name="Record this ranking?").is_visible()
    page.keyboard.press("Escape")
    assert not page.is_visible("#confirm-dialog")
    # Enter on a focused link outside the form follows it (it reviewed the ranking)
    page.focus("a:has-text('Back to the trials')")
    page.keyboard.press("Enter")
    page.wait_for_url(f"{live}/sessions/{sid}")
    page.goto(f"{live}/")  # the sessions page and its create form
    assert page.evaluate(UNNAMED) == []
    assert errors == []
    context.close()


def test_the_trial_page_without_javascript(chromium: Any, live: str) -> None:
    sid = httpx.post(f"{live}/api/sessions", json={"config": rated_config(), "subject": "S05"})
    sid = sid.json()["id"]
    context, page, _ = open_page(chromium, f"{live}/sessions/{sid}", java_script_enabled=False)
    # the shortcuts are listed, the buttons show their keys, and the page still answers
    assert "Keyboard shortcuts" in page.inner_text("details.shortcuts summary")
    page.click("fieldset[data-kind=rating] label.choice:has-text('good')")
    page.click("#review")
    page.wait_for_selector("h1:has-text('Save this answer?')")
    assert "rated 'good'" in page.inner_text("ul.summary")
    page.click("button:has-text('Confirm')")
    page.wait_for_selector("#flash:has-text('Saved: trial 1.')")
    page.click("#unsafe-last summary")
    page.fill("#unsafe-last input[name=reason]", "stumbled")
    page.click("#unsafe-last button[type=submit]")
    page.wait_for_selector("h1:has-text('Flag this trial unsafe?')")
    page.click("button:has-text('Confirm')")
    page.wait_for_selector("#flash:has-text('Trial 1 flagged unsafe')")
    assert [t["rating"] for t in trials(live, sid)] == ["good"]
    assert httpx.get(f"{live}/api/sessions/{sid}").json()["unsafe"] == {"1": "stumbled"}
    context.close()


#: WCAG's contrast ratio of two CSS rgb() colours
CONTRAST = """([a, b]) => {
  const lum = (c) => {
    const [r, g, bl] = c.match(/\\d+/g).slice(0, 3).map((v) => {
      const s = Number(v) / 255;
      return s <= 0.03928 ? s / 12.92 : ((s + 0.055) / 1.055) ** 2.4;
    });
    return 0.2126 * r + 0.7152 * g + 0.0722 * bl;
  };
  const [hi, lo] = [lum(a), lum(b)].sort((x, y) => y - x);
  return (hi + 0.05) / (lo + 0.05);
}"""


def test_the_row_the_keys_answer_and_a_missing_one_are_seen_from_afar(
    chromium: Any, live: str
) -> None:
    sid = httpx.post(f"{live}/api/sessions", json={"config": rated_config(), "subject": "S06"})
    sid = sid.json()["id"]
    context, page, errors = open_page(chromium, f"{live}/sessions/{sid}")
    for key in ("Enter", "Enter"):
        page.keyboard.press(key)
    page.wait_for_selector("#flash:has-text('Saved: trial 1.')")
    keys_ready(page)
    group = "fieldset[data-kind=comparison]"
    style = "(el) => [getComputedStyle(el).borderTopColor, getComputedStyle(el).backgroundColor, "
    style += "getComputedStyle(el).borderTopStyle]"
    border, background, _ = page.eval_on_selector(f"{group}.active", style)
    # the highlighted row (where 1, 2, 0 go) stands out: WCAG's 3:1 for a control's boundary
    assert page.evaluate(CONTRAST, [border, background]) >= 3
    page.keyboard.press("Enter")  # not answered: the row is marked, by more than its colour
    assert page.is_visible("#hint")
    _, _, line = page.eval_on_selector(f"{group}.missing", style)
    assert line == "dashed"
    assert page.get_attribute(f"{group}.missing", "aria-invalid") == "true"
    page.keyboard.press("1")
    assert page.locator(f"{group}.missing").count() == 0
    assert page.get_attribute(group, "aria-invalid") is None
    assert errors == []
    context.close()


def test_two_gaits_a_query_answered_by_keys_alone(chromium: Any, live: str) -> None:
    """compass-gait asks two new gaits a query (n = 2): 2 answers the comparison, the letters
    suggest for the highlighted gait, . and , move between the gaits; a tie is 0."""
    sid = httpx.post(f"{live}/api/sessions", json={"config": "compass-gait", "subject": "S07"})
    sid = sid.json()["id"]
    context, page, errors = open_page(chromium, f"{live}/sessions/{sid}")
    assert page.locator("fieldset[data-kind=comparison]").count() == 1
    assert page.locator("fieldset[data-kind=suggestion]").count() == 2
    active = "fieldset[data-kind=suggestion].active"
    page.keyboard.press("0")  # no preference ...
    assert page.is_checked("fieldset[data-kind=comparison] input[value=none]")
    page.keyboard.press("2")  # ... then the second after all
    page.keyboard.press("w")  # first gait: slightly longer
    assert page.get_attribute(active, "data-position") == "0"
    page.keyboard.press(".")  # the next gait
    assert page.get_attribute(active, "data-position") == "1"
    page.keyboard.press("t")  # second gait: shorter
    page.keyboard.press(",")  # back to the first
    page.keyboard.press("q")  # first gait: longer after all
    page.keyboard.press("Enter")
    page.wait_for_selector("#confirm-dialog[open]")
    page.keyboard.press("Enter")
    page.wait_for_selector("#flash:has-text('Saved: trial 1, 2.')")
    first, second = (page.locator(f"tr[data-trial='{t}'] td") for t in (1, 2))
    assert first.nth(2).inner_text() == "< trial 2"
    assert first.nth(3).inner_text().startswith("step length: longer")
    assert second.nth(3).inner_text().startswith("step length: shorter")
    assert errors == []
    context.close()


def test_an_old_trial_is_excluded_from_the_list_of_every_trial(chromium: Any, live: str) -> None:
    """A long session's page lists the recent trials; "Show all" lists every one, and an old
    trial's exclusion (the confirm dialog) goes back to that list."""
    sid = httpx.post(
        f"{live}/api/sessions", json={"config": "exo-1d-step-length", "subject": "S06"}
    )
    sid = sid.json()["id"]
    for _ in range(RECENT_TRIALS + 2):
        q = httpx.get(f"{live}/api/sessions/{sid}/query").json()
        body = {
            "query_id": q["query_id"],
            "comparisons": [[i, j, "first"] for i, j in q["comparisons"]],
        }
        assert httpx.post(f"{live}/api/sessions/{sid}/answers", json=body).status_code == 200
    context, page, errors = open_page(chromium, f"{live}/sessions/{sid}")
    assert page.locator("#chronology tr[data-trial]").count() == RECENT_TRIALS
    page.click("#all-trials")
    page.wait_for_selector("#recent-trials")
    assert page.locator("#chronology tr[data-trial]").count() == RECENT_TRIALS + 2
    row = "#chronology tr[data-trial='1']"
    page.click(f"{row} details.exclude summary")
    page.select_option(f"{row} select[name=reason]", "stumble")
    page.click(f"{row} .exclude-form button[type=submit]")
    page.wait_for_selector("#confirm-dialog[open]")
    page.click("#confirm-dialog [data-confirm-yes]")
    page.wait_for_selector("#flash:has-text('Trial 1 excluded')")
    assert "trials=all" in page.url
    assert page.locator("#chronology tr[data-trial]").count() == RECENT_TRIALS + 2
    assert [t["excluded"] for t in trials(live, sid) if t["trial"] == 1] == ["stumble"]
    page.click("#recent-trials")
    page.wait_for_selector("#all-trials")
    assert page.locator("#chronology tr[data-trial]").count() == RECENT_TRIALS
    assert errors == []
    context.close()


def test_rapid_enters_across_a_save_never_answer_the_next_page(chromium: Any, live: str) -> None:
    """exo-1d-step-length asks no comparison at trial 3 (n = 1, b = 1): an empty answer is
    valid there. Enters pressed quickly on after trial 2's confirm, across the post and its
    redirect, land on the freshly loaded page: they review and confirm nothing, so trial 3,
    never walked, is not saved; a deliberate press once the page is ready still works."""
    sid = httpx.post(
        f"{live}/api/sessions", json={"config": "exo-1d-step-length", "subject": "S09"}
    )
    sid = sid.json()["id"]
    q = httpx.get(f"{live}/api/sessions/{sid}/query").json()
    assert q["comparisons"] == []  # trial 1, by the API
    body = {"query_id": q["query_id"], "comparisons": []}
    assert httpx.post(f"{live}/api/sessions/{sid}/answers", json=body).status_code == 200
    context, page, errors = open_page(chromium, f"{live}/sessions/{sid}")  # keys ready
    assert page.locator("fieldset[data-kind=comparison]").count() == 1
    page.keyboard.press("1")
    # review, confirm, then on pressing: the next page loads among these presses
    for gap in (40, 30, 60, 30, 80, 30, 50, 30, 70, 30, 40, 60, 30, 50, 30, 40):
        page.keyboard.press("Enter")
        page.wait_for_timeout(gap)
    page.wait_for_selector("#flash:has-text('Saved: trial 2.')")
    assert page.locator("fieldset[data-kind=comparison]").count() == 0  # trial 3: none asked
    keys_ready(page)
    page.wait_for_timeout(200)  # a post the presses started would have landed by now
    assert [t["trial"] for t in trials(live, sid)] == [1, 2]
    assert "Saved: trial 2." in page.inner_text("#flash")
    assert not page.is_visible("#confirm-dialog")
    # a press after the guard: the review, and a fresh press confirms
    page.keyboard.press("Enter")
    page.wait_for_selector("#confirm-dialog[open]")
    page.keyboard.press("Enter")
    page.wait_for_selector("#flash:has-text('Saved: trial 3.')")
    assert [t["trial"] for t in trials(live, sid)] == [1, 2, 3]
    assert errors == []
    context.close()


def test_an_enter_held_across_a_save_never_confirms_the_next_pages_review(
    chromium: Any, live: str
) -> None:
    """Enter held down from trial 2's confirm: on the next page (trial 3, no comparison asked)
    its repeats neither open the review nor confirm one opened by a click."""
    sid = httpx.post(
        f"{live}/api/sessions", json={"config": "exo-1d-step-length", "subject": "S10"}
    )
    sid = sid.json()["id"]
    q = httpx.get(f"{live}/api/sessions/{sid}/query").json()
    body = {"query_id": q["query_id"], "comparisons": []}
    assert httpx.post(f"{live}/api/sessions/{sid}/answers", json=body).status_code == 200
    context, page, errors = open_page(chromium, f"{live}/sessions/{sid}")
    page.keyboard.press("1")
    page.keyboard.press("Enter")
    page.wait_for_selector("#confirm-dialog[open]")
    page.keyboard.down("Enter")  # confirms, and stays down
    page.wait_for_selector("#flash:has-text('Saved: trial 2.')")
    page.keyboard.down("Enter")  # its repeats, on the new page
    assert not page.is_visible("#confirm-dialog")
    page.click("#review")  # the review, opened by a click while Enter is still down
    page.wait_for_selector("#confirm-dialog[open]")
    for _ in range(3):
        page.keyboard.down("Enter")
        page.wait_for_timeout(40)
    page.keyboard.up("Enter")
    keys_ready(page)
    page.wait_for_timeout(200)  # a post the repeats started would have landed by now
    assert page.is_visible("#confirm-dialog")
    assert [t["trial"] for t in trials(live, sid)] == [1, 2]
    page.keyboard.press("Enter")  # a fresh press confirms
    page.wait_for_selector("#flash:has-text('Saved: trial 3.')")
    assert [t["trial"] for t in trials(live, sid)] == [1, 2, 3]
    assert errors == []
    context.close()
