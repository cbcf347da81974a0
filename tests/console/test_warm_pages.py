"""Warm starts and the confidence in the console without a browser: the create form's and the
API's ``prior_from``, the trial page's confidence after every answer, refused items."""

from __future__ import annotations

import re

from fastapi.testclient import TestClient

from tests.console.conftest import answer_once, new_session
from tests.console.htmlforms import forms_of

SENTENCE = re.compile(r'id="confidence"><b>(\d+)% that (G\d+) is within 5% of the best</b>')


def _earlier(client: TestClient, answers: int = 4) -> int:
    sid = new_session(client)
    for _ in range(answers):
        answer_once(client, sid)
    return sid


def _create(client: TestClient, subject: str, prior_from: str) -> tuple[int, str]:
    create = forms_of(client.get("/").text)["create-form"]
    assert "prior_from" in create.fields  # the form has the field, empty
    data = {
        "csrf_token": create.fields["csrf_token"],
        "subject": subject,
        "config": "exo-1d-step-length",
        "prior_from": prior_from,
    }
    r = client.post("/sessions", data=data, follow_redirects=False)
    return r.status_code, r.text if r.status_code != 303 else r.headers["location"]


def test_the_create_form_warm_starts_from_a_subject_code(client: TestClient) -> None:
    earlier = _earlier(client)
    before = client.get(f"/api/sessions/{earlier}/events").json()
    code, where = _create(client, "S02", " S01 ")
    assert code == 303
    sid = int(where.rsplit("/", 1)[1])
    created = client.get(f"/api/sessions/{sid}/events").json()[0]["payload"]
    assert [p["session"] for p in created["prior_from"]] == [earlier]
    assert 0.0 <= created["prior_rho"] <= 1.0
    page = client.get(f"/sessions/{sid}").text
    assert f"Warm-started from session {earlier}." in page
    # a warm start made now starts the subject alone (prior_share_gate): nothing is learnt
    # before their first answer; the share is re-learned after each (tests/sessions)
    assert created["prior_relearn_every"] == 1
    assert not SENTENCE.search(page)
    assert client.get(f"/api/sessions/{earlier}/events").json() == before  # only read


def test_the_trial_page_states_the_confidence_after_every_answer(client: TestClient) -> None:
    sid = new_session(client)
    assert 'id="confidence"' not in client.get(f"/sessions/{sid}").text  # nothing learnt yet
    assert client.get(f"/api/sessions/{sid}/posterior").json()["confidence"] is None
    seen = []
    for _ in range(4):
        answer_once(client, sid)
        page = client.get(f"/sessions/{sid}").text
        m = SENTENCE.search(page)
        if "No preference learned yet" in page:  # the first trial: nothing to compare with
            assert m is None
            continue
        assert m, "no confidence after an answer"
        assert "expected shortfall if you stop now" in page
        seen.append((int(m.group(1)), m.group(2)))
        again = SENTENCE.search(client.get(f"/sessions/{sid}").text)
        assert again and (int(again.group(1)), again.group(2)) == seen[-1]  # same state, same
        api = client.get(f"/api/sessions/{sid}/posterior").json()["confidence"]
        assert api["sentence"] == f"{seen[-1][0]}% that {seen[-1][1]} is within 5% of the best"
        assert 0.0 <= api["probability"] <= 1.0 and api["tolerance"] == 0.05
    assert len(seen) >= 3


def test_refused_prior_from_items_name_the_field(client: TestClient) -> None:
    _earlier(client, answers=1)
    code, text = _create(client, "S02", "S01, J@ne")
    assert code == 422 and "<code>prior_from</code>" in text and "J@ne" in text
    code, text = _create(client, "S02", "S09")
    assert code == 422 and "S09" in text and "has no sessions" in text
    # digits of another script are not a session id (int() read "\u0661" as session 1: the
    # session was created, warm-started from session 1); the API's pattern refuses them too
    for odd in ("\u0661", "\u00b2"):
        code, text = _create(client, "S02", odd)
        assert code == 422 and "neither a session id nor a subject code" in text, text
    assert len(client.get("/api/sessions").json()) == 1


def test_the_api_takes_prior_from(client: TestClient) -> None:
    earlier = _earlier(client, answers=2)
    sid = new_session(client, prior_from=[earlier])
    created = client.get(f"/api/sessions/{sid}/events").json()[0]["payload"]
    assert [p["session"] for p in created["prior_from"]] == [earlier]
    # the session's JSON names them (only the first event did, as the page's words)
    shown = client.get(f"/api/sessions/{sid}").json()
    last = created["prior_from"][0]["last_seq"]
    assert shown["prior_from"] == [{"session": earlier, "subject": "S01", "last_seq": last}]
    assert shown["prior_rho"] == created["prior_rho"]
    cold = client.get(f"/api/sessions/{earlier}").json()
    assert cold["prior_from"] == [] and cold["prior_rho"] is None
    r = client.post(
        "/api/sessions",
        json={"config": "exo-1d-step-length", "subject": "S03", "prior_from": ["no name"]},
    )
    assert r.status_code == 422


def test_a_prior_from_naming_nothing_usable_is_422_at_prior_from(client: TestClient) -> None:
    """An unknown session id (a 404 before), an unknown subject and a session on another grid
    are the body's ``prior_from`` that is wrong, not the session asked for."""
    earlier = _earlier(client, answers=1)
    other = new_session(client, "exo-2d-length-duration")
    cases = [
        ([earlier + 99], "there is no session"),
        (["S77"], "has no sessions"),
        ([other], "another grid"),
    ]
    for prior_from, why in cases:
        r = client.post(
            "/api/sessions",
            json={"config": "exo-1d-step-length", "subject": "S03", "prior_from": prior_from},
        )
        assert r.status_code == 422, r.text
        detail = r.json()["detail"][0]
        assert detail["loc"] == ["body", "prior_from"] and why in detail["msg"]
    code, text = _create(client, "S02", str(earlier + 99))
    assert code == 422 and "<code>prior_from</code>" in text and "there is no session" in text
    too_many = list(range(1, 258))
    r = client.post(
        "/api/sessions",
        json={"config": "exo-1d-step-length", "subject": "S03", "prior_from": too_many},
    )
    assert r.status_code == 413 and "prior_from: at most 256 items" in r.json()["detail"]
    assert len(client.get("/api/sessions").json()) == 2


def test_an_earlier_session_that_cannot_be_rebuilt_is_422_at_prior_from(
    client: TestClient, db_url: str
) -> None:
    """Its row edited (another tool): creating a session warm-started from it answered 500 with
    the earlier session's replay error, as if the console had failed; it is the request's
    ``prior_from`` that names a session no warm start can be made from."""
    import sqlite3

    earlier = _earlier(client, answers=2)
    with sqlite3.connect(db_url.removeprefix("sqlite:///")) as con:
        con.execute("UPDATE sessions SET seed = 12345 WHERE id = ?", (earlier,))
    why = rf"cannot be rebuilt.*session {earlier} \(subject S01\).* does not replay"
    r = client.post(
        "/api/sessions",
        json={"config": "exo-1d-step-length", "subject": "S03", "prior_from": [earlier]},
    )
    assert r.status_code == 422, r.text
    detail = r.json()["detail"][0]
    assert detail["loc"] == ["body", "prior_from"] and re.search(why, detail["msg"]), detail
    code, text = _create(client, "S02", f"S01, {earlier}")
    assert code == 422 and "<code>prior_from</code>" in text, text
    assert re.search(why, " ".join(text.split())) and "Nothing was written." in text
    assert len(client.get("/api/sessions").json()) == 1
