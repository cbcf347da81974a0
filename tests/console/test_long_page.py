"""A long session's trial page: it lists the last ``RECENT_TRIALS`` trials with their forms and
links to the list of every trial (``?trials=all``), from which an old trial is flagged, its flag
withdrawn or it is excluded, each going back to that list; what the page derives from the
trials (the flash after a post, the last trial's flag, the undo) reads every trial."""

from __future__ import annotations

import re

import httpx
from fastapi.testclient import TestClient

from gaitpref.console.trial_page import RECENT_TRIALS
from tests.console.conftest import answer_once, event_count, new_session
from tests.console.htmlforms import Form, forms_of

TRIALS = RECENT_TRIALS + 5


def rows(html: str) -> list[int]:
    return [int(t) for t in re.findall(r'<tr data-trial="(\d+)"', html)]


def form_to(html: str, action: str) -> Form:
    """The chronology's form posting to ``action`` (the last trial's flag is also beside the
    undo, above it)."""
    found = [f for f in forms_of(html).values() if f.action == action]
    assert found, f"no form posts to {action}"
    return found[-1]


def post(client: TestClient, url: str, data: dict[str, str]) -> httpx.Response:
    response: httpx.Response = client.post(url, data=data, follow_redirects=False)
    return response


def confirmed(client: TestClient, form: Form, back: str, **fill: str) -> str:
    """Post ``form`` (with ``fill``), check its confirm step's Back goes to ``back``, confirm:
    where the redirect goes."""
    step = post(client, form.action, {**form.fields, **fill})
    assert step.status_code == 200, step.text
    assert f'href="{back}">Back</a>' in step.text
    done = post(client, form.action, forms_of(step.text)["form1"].fields)
    assert done.status_code == 303, done.text
    return done.headers["location"]


def long_session(client: TestClient) -> int:
    sid = new_session(client)
    for _ in range(TRIALS):
        answer_once(client, sid)
    return sid


def test_the_page_lists_the_recent_trials_and_links_to_every_one(client: TestClient) -> None:
    sid = long_session(client)
    html = client.get(f"/sessions/{sid}").text
    assert f"Trials ({TRIALS})" in html
    assert rows(html) == list(range(TRIALS, TRIALS - RECENT_TRIALS, -1))  # newest first
    assert f'href="/sessions/{sid}?trials=all#chronology" id="all-trials"' in html
    assert f"Show all {TRIALS} trials" in html
    # the forms of the trials listed only, besides the last trial's flag and the undo
    for trial in (1, TRIALS - RECENT_TRIALS):
        assert f"/trials/{trial}/unsafe" not in html and f"/trials/{trial}/exclude" not in html
    assert 'id="unsafe-last" data-key="n"' in html and f"Flag trial {TRIALS} unsafe" in html
    assert 'id="undo-form"' in html
    everything = client.get(f"/sessions/{sid}?trials=all").text
    assert rows(everything) == list(range(TRIALS, 0, -1))
    assert "all-trials" not in everything
    assert f'href="/sessions/{sid}#chronology" id="recent-trials"' in everything
    for trial in (1, TRIALS):  # every row's forms go back to this list
        for action in ("unsafe", "exclude"):
            forms = [f for f in forms_of(everything).values() if f.action.endswith(action)]
            assert all(f.fields["trials"] == "all" for f in forms)
            assert any(f.action == f"/sessions/{sid}/trials/{trial}/{action}" for f in forms)
    assert 'id="unsafe-last" data-key="n"' in everything
    assert client.get(f"/sessions/{sid}?trials=some").status_code == 422


def test_a_short_session_lists_every_trial_without_a_link(client: TestClient) -> None:
    sid = new_session(client)
    for _ in range(3):
        answer_once(client, sid)
    for url in (f"/sessions/{sid}", f"/sessions/{sid}?trials=all"):
        html = client.get(url).text
        assert rows(html) == [3, 2, 1]
        assert "all-trials" not in html and "recent-trials" not in html


def test_an_old_trial_is_flagged_withdrawn_and_excluded_from_the_list_of_all(
    client: TestClient,
) -> None:
    sid = long_session(client)
    page, everything = f"/sessions/{sid}", f"/sessions/{sid}?trials=all"
    flag = form_to(client.get(everything).text, f"{page}/trials/1/unsafe")
    where = confirmed(client, flag, everything, reason="knee buckled")
    assert where == f"{page}?flagged=1&replaced=0&trials=all"
    html = client.get(where).text
    assert "Trial 1 flagged unsafe" in html and rows(html)[-1] == 1
    assert "unsafe: knee buckled" in html
    # the flash reads every trial: the page of the recent ones says it too, trial 1 unlisted
    recent = client.get(f"{page}?flagged=1&replaced=0").text
    assert "Trial 1 flagged unsafe" in recent and 1 not in rows(recent)
    withdraw = form_to(html, f"{page}/trials/1/unsafe/withdraw")
    where = confirmed(client, withdraw, everything)
    assert where == f"{page}?withdrawn=1&trials=all"
    html = client.get(where).text
    assert "The unsafe flag of trial 1 was withdrawn." in html
    assert "The unsafe flag of trial 1 was withdrawn." in client.get(f"{page}?withdrawn=1").text
    exclude = form_to(html, f"{page}/trials/2/exclude")
    where = confirmed(client, exclude, everything, reason="stumble")
    assert where.startswith(f"{page}?excluded=2&replaced=") and where.endswith("&trials=all")
    html = client.get(where).text
    assert "Trial 2 excluded: its answers left the model." in html
    assert "excluded: stumble" in html
    trials = client.get(f"/api/sessions/{sid}/trials").json()
    assert [t["excluded"] for t in trials if t["trial"] == 2] == ["stumble"]
    # a form of the recent page goes back to it
    flag = form_to(client.get(page).text, f"{page}/trials/{TRIALS}/unsafe")
    assert "trials" not in flag.fields
    where = confirmed(client, flag, page, reason="slipped")
    assert where == f"{page}?flagged={TRIALS}&replaced=0"


def test_a_trial_form_naming_another_list_is_refused_before_anything_is_written(
    client: TestClient,
) -> None:
    sid = long_session(client)
    everything = client.get(f"/sessions/{sid}?trials=all").text
    before = event_count(client, sid)
    for action, reason in (("unsafe", "knee"), ("exclude", "stumble")):
        form = form_to(everything, f"/sessions/{sid}/trials/1/{action}")
        bad = {**form.fields, "reason": reason, "trials": "some", "confirmed": "1"}
        r = post(client, form.action, bad)
        assert r.status_code == 422 and "trials" in r.text and "&#39;all&#39;" in r.text
    assert event_count(client, sid) == before


def test_the_notes_are_cut_as_the_trials_and_every_one_is_behind_show_all(
    client: TestClient,
) -> None:
    """The page showed the last 20 notes and no way to the older ones."""
    sid = new_session(client)
    for k in range(1, RECENT_TRIALS + 4):
        posted = client.post(f"/api/sessions/{sid}/notes", json={"text": f"note number {k}"})
        assert posted.status_code in (200, 201), posted.text
    html = client.get(f"/sessions/{sid}").text
    shown = [int(k) for k in re.findall(r"note number (\d+)<", html)]
    assert shown == list(range(RECENT_TRIALS + 3, 3, -1))  # the newest 20, newest first
    assert f"The last {RECENT_TRIALS} of {RECENT_TRIALS + 3} notes" in html
    assert f'href="/sessions/{sid}?trials=all#notes"' in html
    every = client.get(f"/sessions/{sid}?trials=all").text
    assert [int(k) for k in re.findall(r"note number (\d+)<", every)] == list(
        range(RECENT_TRIALS + 3, 0, -1)
    )
    assert 'id="notes-recent"' not in every
    few = new_session(client)
    client.post(f"/api/sessions/{few}/notes", json={"text": "one note"})
    assert 'id="notes-recent"' not in client.get(f"/sessions/{few}").text
