"""Ratings, unsafe flags and "no safe gait" through the JSON API and the pages (no browser)."""

from __future__ import annotations

import csv
import io
import zipfile
from typing import Any

import httpx
import pytest
from fastapi.testclient import TestClient

from gaitpref.config import parse_config
from gaitpref.loop.safety import near
from tests.console.conftest import event_count, new_session
from tests.console.htmlforms import Form, forms_of

LABELS = ["very bad", "bad", "okay", "good"]


def rated_config(radius: float = 0.1) -> str:
    return f"""
name = "rated-1d"
[space.step_length]
min = 0.08
max = 0.18
num = 15
unit = "m"
[model]
lengthscale = 0.03
signal_variance = 0.005
noise = 0.02
[cospar]
seed = 2
[feedback.rating]
labels = {LABELS!r}
[safety]
avoid = ["very bad"]
lambda = 2.0
unsafe_radius = {radius}
""".replace("'", '"')


def query(client: TestClient, sid: int) -> dict[str, Any]:
    r = client.get(f"/api/sessions/{sid}/query")
    assert r.status_code == 200, r.text
    return dict(r.json())


def answer(client: TestClient, sid: int, feedback: list[dict[str, Any]]) -> httpx.Response:
    q = query(client, sid)
    body = {
        "query_id": q["query_id"],
        "comparisons": [[i, j, "first"] for i, j in q["comparisons"]],
        "feedback": feedback,
    }
    response: httpx.Response = client.post(f"/api/sessions/{sid}/answers", json=body)
    return response


def gait(client: TestClient, sid: int) -> int:
    return int(query(client, sid)["actions"][0]["index"])


# -- ratings in the JSON API -------------------------------------------------------------------
def test_ratings_by_name_and_number_are_logged_listed_and_exported(client: TestClient) -> None:
    sid = new_session(client, rated_config())
    scale = client.get(f"/api/sessions/{sid}").json()["rating"]
    assert scale == {"categories": LABELS, "avoid": 1}
    a1 = gait(client, sid)
    assert answer(client, sid, [{"kind": "rating", "action": a1, "label": "okay"}]).is_success
    a2 = gait(client, sid)
    assert answer(client, sid, [{"kind": "rating", "action": a2, "label": 4}]).is_success
    assert answer(client, sid, []).is_success  # a trial may go unrated
    trials = client.get(f"/api/sessions/{sid}/trials").json()
    assert [t["rating"] for t in trials] == ["okay", "good", None]
    given = [e["payload"] for e in client.get(f"/api/sessions/{sid}/events").json()]
    rated = [p for p in given if "category" in p]
    assert [(p["trial"], p["action"], p["label"]) for p in rated] == [(1, a1, 3), (2, a2, 4)]
    data = client.get(f"/api/sessions/{sid}/export?format=csv").content
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        name = next(n for n in zf.namelist() if n.endswith("ratings.csv"))
        rows = list(csv.DictReader(io.StringIO(zf.read(name).decode())))
    assert [(r["trial"], r["category"]) for r in rows] == [("1", "okay"), ("2", "good")]


@pytest.mark.parametrize(
    ("item", "field", "says"),
    [
        ({"kind": "mood", "action": 0, "label": 1}, "feedback.0", "no feedback kind 'mood'"),
        ({"kind": "rating", "action": 0}, "feedback.0", "missing 'label'"),
        ({"kind": "rating", "action": 0, "label": 1, "x": 2}, "feedback.0", "unknown 'x'"),
        ({"kind": "rating", "action": 0, "label": [1]}, "feedback.0", "number or a text"),
        ({"kind": "rating", "action": "THIS", "label": "great"}, "feedback", "not a category"),
        ({"kind": "rating", "action": 14, "label": 1}, "feedback", "was not executed"),
    ],
)
def test_refused_ratings_name_the_field_and_write_nothing(
    client: TestClient, item: dict[str, Any], field: str, says: str
) -> None:
    sid = new_session(client, rated_config())
    a = gait(client, sid)
    if item.get("action") == "THIS":
        item = {**item, "action": a}
    elif item.get("action") == 14 and a == 14:
        item = {**item, "action": 0}
    before = event_count(client, sid)
    r = answer(client, sid, [item])
    assert r.status_code == 422, r.text
    detail = r.json()["detail"][0]
    assert ".".join(map(str, detail["loc"])) == f"body.{field}"
    assert says in detail["msg"]
    assert event_count(client, sid) == before


def test_a_config_without_ratings_refuses_them(client: TestClient) -> None:
    sid = new_session(client)
    assert client.get(f"/api/sessions/{sid}").json()["rating"] is None
    r = answer(client, sid, [{"kind": "rating", "action": gait(client, sid), "label": 1}])
    assert r.status_code == 422 and "takes no ratings" in r.text


def test_more_than_256_feedback_items_is_413(client: TestClient) -> None:
    sid = new_session(client, rated_config())
    items = [{"kind": "rating", "action": 0, "label": 1}] * 257
    r = answer(client, sid, items)
    assert r.status_code == 413 and "feedback" in r.json()["detail"]


# -- unsafe flags and no safe gait -------------------------------------------------------------
def test_flag_and_withdraw_through_the_api(client: TestClient) -> None:
    sid = new_session(client, rated_config(0.2))
    for _ in range(3):
        answer(client, sid, [])
    flagged = int(client.get(f"/api/sessions/{sid}/trials").json()[2]["gait"]["index"])
    pending = query(client, sid)  # issued and logged before the flag
    space = parse_config(rated_config(0.2)).space
    banned = near(space, [flagged], 0.2)
    assert 1 < banned.sum() < len(space)
    assert banned[pending["actions"][0]["index"]]  # (seed 2) the pending gait is near trial 3's
    r = client.post(f"/api/sessions/{sid}/trials/3/unsafe", json={"reason": "knee buckled"})
    assert r.status_code == 200, r.text
    assert [t["unsafe"] for t in r.json()] == [None, None, "knee buckled"]
    assert client.get(f"/api/sessions/{sid}").json()["unsafe"] == {"3": "knee buckled"}
    q = query(client, sid)  # the pending query was withdrawn: a new one, away from the flag
    assert q["query_id"] != pending["query_id"]
    assert not any(banned[g["index"]] for g in q["actions"])
    before = event_count(client, sid)
    again = client.post(f"/api/sessions/{sid}/trials/3/unsafe", json={"reason": "twice"})
    assert again.status_code == 409 and "already flagged" in again.text
    blank = client.post(f"/api/sessions/{sid}/trials/1/unsafe", json={"reason": "   "})
    assert blank.status_code == 422 and blank.json()["detail"][0]["loc"] == ["body", "reason"]
    missing = client.post(f"/api/sessions/{sid}/trials/1/unsafe", json={})
    assert missing.status_code == 422
    unanswered = client.post(f"/api/sessions/{sid}/trials/9/unsafe", json={"reason": "x"})
    assert unanswered.status_code == 409 and "no trial 9" in unanswered.text
    assert event_count(client, sid) == before
    w = client.post(f"/api/sessions/{sid}/trials/3/unsafe/withdraw")
    assert w.status_code == 200 and w.json()[2]["unsafe"] is None
    assert client.post(f"/api/sessions/{sid}/trials/3/unsafe/withdraw").status_code == 409


def test_no_safe_gait_is_409_with_its_reason_and_a_plain_page(client: TestClient) -> None:
    sid = new_session(client, rated_config(1.0))  # a radius of the whole range
    answer(client, sid, [])
    assert client.post(f"/api/sessions/{sid}/trials/1/unsafe", json={"reason": "fell"}).is_success
    before = event_count(client, sid)
    r = client.get(f"/api/sessions/{sid}/query")
    assert r.status_code == 409
    assert "no gait may be proposed" in r.json()["detail"]
    page = client.get(f"/sessions/{sid}")
    assert page.status_code == 200
    assert "No safe gait left to propose" in page.text and "no gait may be proposed" in page.text
    assert "could not be made" not in page.text  # a grid session makes no gaits on demand
    assert 'id="answer-form"' not in page.text
    assert event_count(client, sid) == before  # nothing written by either
    client.post(f"/api/sessions/{sid}/trials/1/unsafe/withdraw")
    assert client.get(f"/api/sessions/{sid}/query").status_code == 200


# -- the pages ---------------------------------------------------------------------------------
def post(client: TestClient, url: str, data: dict[str, str]) -> httpx.Response:
    response: httpx.Response = client.post(url, data=data, follow_redirects=False)
    return response


def form_to(html: str, action: str) -> Form:
    return next(f for f in forms_of(html).values() if f.action == action)


def test_the_trial_page_rates_with_the_configs_words(client: TestClient) -> None:
    sid = new_session(client, rated_config())
    a = gait(client, sid)
    html = client.get(f"/sessions/{sid}").text
    for k, word in enumerate(LABELS, start=1):
        assert f"{word} <kbd>{k}</kbd>" in html
    form = forms_of(html)["answer-form"]
    assert form.radios[f"rate-{a}"] == ["1", "2", "3", "4", ""]
    assert form.fields[f"rate-{a}"] == ""  # skippable: "no rating" is chosen
    confirm = post(client, f"/sessions/{sid}/answer", {**form.fields, f"rate-{a}": "2"})
    assert confirm.status_code == 200 and "rated &#39;bad&#39;" in confirm.text
    done = post(client, f"/sessions/{sid}/answer", forms_of(confirm.text)["form1"].fields)
    assert done.status_code == 303
    assert client.get(f"/api/sessions/{sid}/trials").json()[0]["rating"] == "bad"
    assert '<td class="rated">bad</td>' in client.get(f"/sessions/{sid}").text
    bad = post(client, f"/sessions/{sid}/answer", {**form.fields, f"rate-{a}": "7"})
    assert bad.status_code == 422 and f"rate-{a}" in bad.text


def test_no_rating_buttons_without_a_rating_scale(client: TestClient) -> None:
    sid = new_session(client)
    html = client.get(f"/sessions/{sid}").text
    assert 'data-kind="rating"' not in html and "rate the gait" not in html


def test_flag_from_the_page_needs_a_reason_and_a_confirmation(client: TestClient) -> None:
    sid = new_session(client, rated_config())
    answer(client, sid, [])
    html = client.get(f"/sessions/{sid}").text
    assert 'id="unsafe-last"' in html
    flag = form_to(html, f"/sessions/{sid}/trials/1/unsafe")
    empty = post(client, flag.action, {**flag.fields, "reason": " "})
    assert empty.status_code == 422 and "reason" in empty.text
    ask = post(client, flag.action, {**flag.fields, "reason": "hip pain"})
    assert ask.status_code == 200 and "Flag this trial unsafe?" in ask.text
    assert client.get(f"/api/sessions/{sid}").json()["unsafe"] == {}  # not yet
    done = post(client, flag.action, forms_of(ask.text)["form1"].fields)
    assert done.status_code == 303 and done.headers["location"].endswith("?flagged=1&replaced=0")
    shown = client.get(done.headers["location"]).text
    assert "Trial 1 flagged unsafe" in shown and "unsafe: hip pain" in shown
    assert 'id="unsafe-last"' not in shown
    withdraw = form_to(shown, f"/sessions/{sid}/trials/1/unsafe/withdraw")
    ask = post(client, withdraw.action, withdraw.fields)
    assert "Withdraw the unsafe flag?" in ask.text
    done = post(client, withdraw.action, forms_of(ask.text)["form1"].fields)
    assert done.headers["location"].endswith("?withdrawn=1")
    assert client.get(f"/api/sessions/{sid}").json()["unsafe"] == {}


def test_the_posterior_figure_draws_with_flags(client: TestClient) -> None:
    sid = new_session(client, rated_config())
    answer(client, sid, [])
    client.post(f"/api/sessions/{sid}/trials/1/unsafe", json={"reason": "fell"})
    png = client.get(f"/sessions/{sid}/posterior.png")
    assert png.status_code == 200 and png.content[:4] == b"\x89PNG"


def test_an_undo_whose_query_proposes_a_gait_flagged_since_proposes_anew(
    client: TestClient,
) -> None:
    from tests.sessions.test_unsafe import CONFIG  # seed 1 runs gaits 6, then 8 near it

    sid = new_session(client, CONFIG)
    answer(client, sid, [])
    answer(client, sid, [])
    first, second = (t["gait"]["index"] for t in client.get(f"/api/sessions/{sid}/trials").json())
    banned = near(parse_config(CONFIG).space, [first], 0.15)
    assert banned[second]
    pending = query(client, sid)
    assert client.post(f"/api/sessions/{sid}/trials/1/unsafe", json={"reason": "hip"}).is_success
    undone = client.post(f"/api/sessions/{sid}/undo", json={})
    assert undone.status_code == 200, undone.text
    body = undone.json()
    assert body["withdrawn"] is True and body["trials"] == [2]
    assert body["pending_query_id"] != body["undone_query_id"]
    q = query(client, sid)
    assert q["query_id"] == body["pending_query_id"] and q["query_id"] != pending["query_id"]
    assert not any(banned[g["index"]] for g in q["actions"])
    again = client.post(
        f"/api/sessions/{sid}/answers",
        json={"query_id": body["undone_query_id"], "comparisons": []},
    )
    assert again.status_code == 409  # the withdrawn query takes no answer


def test_an_undo_after_which_no_gait_is_safe_says_it_was_undone(client: TestClient) -> None:
    """The undo was written, then no gait was left to propose in the withdrawn query's place:
    the API answered 409, which docs/console.md says writes nothing.  (The page offers no undo
    then: with no gait safe there is no query, and a form loaded before the flag names a query
    the flag withdrew, refused as stale.)"""
    sid = new_session(client, rated_config(1.0))  # a radius of the whole range
    answer(client, sid, [])
    answer(client, sid, [])
    assert client.post(f"/api/sessions/{sid}/trials/1/unsafe", json={"reason": "hip"})
    before = event_count(client, sid)
    r = client.post(f"/api/sessions/{sid}/undo", json={})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["trials"] == [2] and body["withdrawn"] is True
    assert body["pending_query_id"] is None
    assert "no gait may be proposed" in body["next_query_error"]
    assert event_count(client, sid) == before + 1  # the undo, once
    assert client.get(f"/api/sessions/{sid}").json()["trials"] == 1
    assert client.get(f"/api/sessions/{sid}/query").status_code == 409


def test_a_gait_run_twice_in_one_query_has_one_rating_and_suggestion_group(
    client: TestClient, db_url: str
) -> None:
    """n = 2, one gait for trials 3 and 4: the page showed a rating row per trial, both one
    radio group ``rate-<a>`` (rating trial 4 cleared trial 3's); one row now names both.  The
    gait is not compared with itself (the page asked it, 'kept, not modelled'; the terminal
    never did): the page says why, and the API lists no pair."""
    from pathlib import Path

    from gaitpref import Session

    shipped = Path(__file__).parents[2] / "src/gaitpref/config/shipped/exo-2d-rated.toml"
    text = shipped.read_text(encoding="utf-8").replace("n = 1\nbuffer = 1", "n = 2\nbuffer = 0")
    session = Session.create(db_url, parse_config(text), "S01", seed=0)
    for _ in range(40):
        q = session.next_query()
        if q.actions[0] == q.actions[1]:
            break
        session.answer(q.id, [(q.actions[0], q.actions[1], "first")], [])
    else:
        raise AssertionError("no query proposed a gait twice")
    session.close()
    (t3, t4), a = q.trials, q.actions[0]
    html = client.get(f"/sessions/{session.id}").text
    assert html.count('data-kind="rating"') == 1
    assert f"How did the subject rate trials {t3}, {t4} (G{a})?" in html
    assert html.count(f"trials {t3}, {t4} (G{a}): step length") == 1
    assert 'data-kind="comparison"' not in html
    assert (
        f"Not asked: trial {t3} (G{a}) and trial {t4} (G{a}) are the same gait: nothing to "
        "compare" in html
    )
    assert client.get(f"/api/sessions/{session.id}/query").json()["comparisons"] == []
    form = forms_of(html)["answer-form"]
    assert not [k for k in form.radios if k.startswith("cmp-")]
    data = {**form.fields, f"rate-{a}": "4", f"sug-{a}-step_width": "-small"}
    confirm = post(client, f"/sessions/{session.id}/answer", data)
    assert confirm.status_code == 200, confirm.text
    assert f"trial {t3} (G{a}) rated &#39;good&#39;" in confirm.text
    assert "Not answered" not in confirm.text
    done = post(client, f"/sessions/{session.id}/answer", forms_of(confirm.text)["form1"].fields)
    assert done.status_code == 303
    rated = [t["rating"] for t in client.get(f"/api/sessions/{session.id}/trials").json()]
    assert rated[t3 - 1] == "good"


def test_the_undo_of_a_query_of_two_trials_names_both(client: TestClient) -> None:
    """n = 2: the undo takes back both trials of the last query; its button and confirm step
    said 'Take back the answer to trial 2', the last trial alone."""
    text = rated_config().replace("[cospar]\n", "[cospar]\nn = 2\nbuffer = 0\n", 1)
    sid = new_session(client, text)
    q = query(client, sid)
    (a, b), = q["comparisons"]  # fmt: skip
    answered = client.post(
        f"/api/sessions/{sid}/answers",
        json={"query_id": q["query_id"], "comparisons": [[a, b, "first"]]},
    )
    assert answered.status_code == 200, answered.text
    html = client.get(f"/sessions/{sid}").text
    assert 'data-say="Take back the answer to trials 1, 2, one query"' in html
    form = form_to(html, f"/sessions/{sid}/undo")
    confirm = post(client, form.action, form.fields)
    assert confirm.status_code == 200, confirm.text
    assert "Take back the answer to trials 1, 2, one query:" in confirm.text
    assert (
        "<li>trial 1 (step_length=" in confirm.text and "<li>trial 2 (step_length=" in confirm.text
    )


def test_the_confirm_step_names_the_pairs_a_form_leaves_unanswered(client: TestClient) -> None:
    """n = 2, b = 1: three pairs.  Posted without the page's script (which asks every pair
    first) with one answered, the confirm step listed that one alone and saved it: two pairs
    went missing unsaid."""
    text = rated_config().replace("[cospar]\n", "[cospar]\nn = 2\nbuffer = 1\n", 1)
    sid = new_session(client, text)
    q = query(client, sid)
    (a, b), = q["comparisons"]  # fmt: skip
    body = {"query_id": q["query_id"], "comparisons": [[a, b, "first"]]}
    assert client.post(f"/api/sessions/{sid}/answers", json=body).status_code == 200
    form = forms_of(client.get(f"/sessions/{sid}").text)["answer-form"]
    pairs = sorted(k for k in form.radios if k.startswith("cmp-"))
    assert len(pairs) == 3
    confirm = post(client, f"/sessions/{sid}/answer", {**form.fields, pairs[0]: "first"})
    assert confirm.status_code == 200, confirm.text
    assert confirm.text.count("Not answered, not saved: trial ") == 2
    every = {**form.fields, **dict.fromkeys(pairs, "none")}
    confirm = post(client, f"/sessions/{sid}/answer", every)
    assert "Not answered" not in confirm.text
