"""An answer form posted again to the query it answered (a double click or a re-sent form
without JavaScript, the browser's "resubmit" after back or reload).

The same answer again is not an error: the page redirects (303) to the trial page, which says
the answer was already saved, and nothing is written.  Another answer to the answered query is
refused (409) saying so and how to change it (undo).  The JSON API is unchanged: any answer to a
query that is not pending is 409 (its clients are programs).
"""

from __future__ import annotations

from typing import Any

import httpx
from fastapi.testclient import TestClient

from tests.console.conftest import answer_once, event_count, new_session
from tests.console.htmlforms import forms_of
from tests.console.test_ratings_safety import gait, rated_config

SAVED = "That answer was already saved (trial {}); nothing was stored twice."


def post(client: TestClient, sid: int, data: dict[str, str]) -> httpx.Response:
    response: httpx.Response = client.post(
        f"/sessions/{sid}/answer", data=data, follow_redirects=False
    )
    return response


def answer_form(client: TestClient, sid: int, **choices: str) -> dict[str, str]:
    """The trial page's answer form, every comparison answered ``first`` (unless ``choices``
    says otherwise), confirmed."""
    form = forms_of(client.get(f"/sessions/{sid}").text)["answer-form"]
    cmps = {k: "first" for k in form.radios if k.startswith("cmp-")}
    return {**form.fields, **cmps, **choices, "confirmed": "1"}


def comparisons_of(client: TestClient, sid: int) -> list[dict[str, Any]]:
    log = client.get(f"/api/sessions/{sid}/events").json()
    return [e["payload"] for e in log if e["kind"] == "comparison_answered"]


def test_the_same_answer_twice_is_saved_once_and_the_second_post_redirects(
    client: TestClient,
) -> None:
    sid = new_session(client)
    answer_once(client, sid)
    a = gait(client, sid)
    data = answer_form(client, sid, **{f"sug-{a}-step_length": "+small", "note": "steady"})
    first = post(client, sid, data)
    assert first.status_code == 303 and first.headers["location"] == f"/sessions/{sid}?answered=2"
    events = event_count(client, sid)
    for _ in range(2):  # a double click, then the browser's "resubmit"
        again = post(client, sid, data)
        assert again.status_code == 303
        assert again.headers["location"] == f"/sessions/{sid}?answered=2&again=1"
    assert event_count(client, sid) == events
    page = client.get(again.headers["location"])
    assert page.status_code == 200 and SAVED.format(2) in page.text
    assert "Run now: trial 3" in page.text
    log = client.get(f"/api/sessions/{sid}/events").json()
    assert [e["payload"]["trial"] for e in log if e["kind"] == "trial_executed"] == [1, 2]
    assert sum(e["kind"] == "suggestion_given" for e in log) == 1
    assert sum(e["kind"] == "note" for e in log) == 1  # the note is not written twice either


def test_the_review_step_posted_again_after_the_save_redirects_too(client: TestClient) -> None:
    """Back to the review page and "resubmit": the first, unconfirmed post comes again."""
    sid = new_session(client)
    answer_once(client, sid)
    data = answer_form(client, sid)
    review = {k: v for k, v in data.items() if k != "confirmed"}
    assert post(client, sid, review).status_code == 200  # the review step
    assert post(client, sid, data).status_code == 303
    events = event_count(client, sid)
    again = post(client, sid, review)
    assert again.status_code == 303
    assert again.headers["location"] == f"/sessions/{sid}?answered=2&again=1"
    assert event_count(client, sid) == events


def test_a_different_answer_to_the_answered_query_is_409_saying_how_to_change_it(
    client: TestClient,
) -> None:
    sid = new_session(client)
    answer_once(client, sid)
    a = gait(client, sid)
    data = answer_form(client, sid)
    assert post(client, sid, data).status_code == 303
    events = event_count(client, sid)
    cmp = next(k for k in data if k.startswith("cmp-"))
    for changed in (
        {**data, cmp: "second"},  # another choice
        {**data, f"sug-{a}-step_length": "-big"},  # a suggestion added
        {k: v for k, v in {**data, cmp: "none"}.items() if k != "confirmed"},  # at review
    ):
        r = post(client, sid, changed)
        assert r.status_code == 409, r.text
        text = " ".join(r.text.split())
        assert "was already answered, with a different answer than this form&#39;s" in text
        assert "preferred to" in text  # the logged answer, in words
        assert "Undo last answer" in text and "answer trial 2 again" in text
        assert "Nothing was written" in text
        assert event_count(client, sid) == events
    assert [c["outcome"] for c in comparisons_of(client, sid)] == ["first"]


def test_the_same_answer_after_the_next_one_and_after_finishing_still_redirects(
    client: TestClient,
) -> None:
    sid = new_session(client)
    answer_once(client, sid)
    data = answer_form(client, sid)
    assert post(client, sid, data).status_code == 303
    answer_once(client, sid, "second")  # trial 3, by the API
    events = event_count(client, sid)
    again = post(client, sid, data)
    assert again.status_code == 303
    assert SAVED.format(2) in client.get(again.headers["location"]).text
    r = client.post(f"/api/sessions/{sid}/status", json={"status": "finished"})
    assert r.status_code == 200, r.text
    events = event_count(client, sid)
    assert post(client, sid, data).status_code == 303  # finished since: saved all the same
    assert event_count(client, sid) == events


def test_an_undone_answer_posted_again_is_an_answer_as_before(client: TestClient) -> None:
    """After an undo the query is pending again: the same form answers it (as it always did)."""
    sid = new_session(client)
    answer_once(client, sid)
    data = answer_form(client, sid)
    assert post(client, sid, data).status_code == 303
    assert client.post(f"/api/sessions/{sid}/undo").status_code == 200
    r = post(client, sid, data)
    assert r.status_code == 303 and r.headers["location"] == f"/sessions/{sid}?answered=2"


def test_a_stale_query_that_was_never_answered_is_still_the_plain_409(
    client: TestClient,
) -> None:
    sid = new_session(client)
    answer_once(client, sid)
    data = answer_form(client, sid)
    events = event_count(client, sid)
    r = post(client, sid, {**data, "query_id": str(int(data["query_id"]) + 50)})
    assert r.status_code == 409 and "is not the pending query" in r.text
    assert "different answer" not in r.text
    assert event_count(client, sid) == events


def test_ratings_are_part_of_the_answer_compared(client: TestClient) -> None:
    sid = new_session(client, rated_config())
    a = gait(client, sid)
    data = answer_form(client, sid, **{f"rate-{a}": "2"})
    assert post(client, sid, data).status_code == 303
    events = event_count(client, sid)
    same = post(client, sid, data)
    assert same.status_code == 303 and same.headers["location"].endswith("again=1")
    other = post(client, sid, {**data, f"rate-{a}": "3"})
    assert other.status_code == 409 and "rated &#39;bad&#39;" in other.text
    unrated = post(client, sid, {**data, f"rate-{a}": ""})
    assert unrated.status_code == 409 and "different answer" in unrated.text
    assert event_count(client, sid) == events


def test_the_api_still_refuses_any_second_answer_with_409(client: TestClient) -> None:
    sid = new_session(client)
    q = client.get(f"/api/sessions/{sid}/query").json()
    body = {"query_id": q["query_id"], "comparisons": []}
    assert client.post(f"/api/sessions/{sid}/answers", json=body).status_code == 200
    events = event_count(client, sid)
    r = client.post(f"/api/sessions/{sid}/answers", json=body)  # the very same body
    assert r.status_code == 409 and "already answered" in r.json()["detail"]
    assert "different answer" not in r.json()["detail"]
    assert event_count(client, sid) == events
