"""The pages without a browser: forms, the server-side confirm step, 409/422 pages."""

from __future__ import annotations

import json
import logging
import re

import httpx
import pytest
from fastapi.testclient import TestClient

from tests.console.conftest import answer_once, event_count, new_session
from tests.console.htmlforms import Form, forms_of


def trial_form(client: TestClient, sid: int) -> Form:
    page = client.get(f"/sessions/{sid}")
    assert page.status_code == 200
    return forms_of(page.text)["answer-form"]


def post(client: TestClient, url: str, data: dict[str, str]) -> httpx.Response:
    response: httpx.Response = client.post(url, data=data, follow_redirects=False)
    return response


def test_create_from_the_sessions_page_then_answer_with_a_confirm_step(client: TestClient) -> None:
    page = client.get("/")
    create = forms_of(page.text)["create-form"]
    assert "exo-2d-length-duration" in create.selects["config"]
    r = client.post(
        "/sessions",
        data={**create.fields, "subject": "S07", "config": "exo-2d-length-duration", "seed": "3"},
        files={"config_file": ("", b"")},
        follow_redirects=False,
    )
    assert r.status_code == 303
    sid = int(r.headers["location"].rsplit("/", 1)[1])
    assert client.get(f"/api/sessions/{sid}").json()["seed"] == 3
    html = client.get(f"/sessions/{sid}").text
    assert "Run now: trial 1" in html and "step duration" in html and ">s<" not in html
    assert "slightly slower" in html and "quicker" in html  # the features' own words
    assert "No preference learned yet" in html
    form = forms_of(html)["answer-form"]
    gait = client.get(f"/api/sessions/{sid}/query").json()["actions"][0]["index"]
    assert form.radios[f"sug-{gait}-step_length"] == ["+big", "+small", "", "-small", "-big"]
    data = {**form.fields, f"sug-{gait}-step_length": "+small", "note": "first steps"}
    confirm = post(client, f"/sessions/{sid}/answer", data)
    assert confirm.status_code == 200
    assert "Save this answer?" in confirm.text and "step length slightly longer" in confirm.text
    assert client.get(f"/api/sessions/{sid}").json()["trials"] == 0  # not yet
    again = forms_of(confirm.text)["form1"]
    assert again.fields["confirmed"] == "1"
    done = post(client, f"/sessions/{sid}/answer", again.fields)
    assert done.status_code == 303
    assert done.headers["location"] == f"/sessions/{sid}?answered=1"
    shown = client.get(done.headers["location"]).text
    assert (
        "Saved: trial 1." in shown
        and "Run now: trial 2" in shown
        and "Compare with: trial 1" in shown
    )
    assert "step length: slightly longer" in shown  # the chronology
    assert "trial 1: first steps" in shown  # the note
    assert "Best so far" in shown and "No preference learned yet" not in shown


def test_a_second_post_of_the_same_answer_redirects_saying_so_and_writes_nothing(
    client: TestClient,
) -> None:
    """A double click (or a re-sent form) without JavaScript: the answer is saved once, and the
    second post is not an error page (tests/console/test_repost.py has the other cases)."""
    sid = new_session(client)
    answer_once(client, sid)
    form = trial_form(client, sid)
    cmp = next(k for k in form.radios if k.startswith("cmp-"))
    data = {**form.fields, cmp: "first", "confirmed": "1"}
    assert post(client, f"/sessions/{sid}/answer", data).status_code == 303
    events = event_count(client, sid)
    r = post(client, f"/sessions/{sid}/answer", data)
    assert r.status_code == 303
    assert r.headers["location"] == f"/sessions/{sid}?answered=2&again=1"
    assert event_count(client, sid) == events  # (showing the page then logs trial 3's query)
    shown = client.get(r.headers["location"]).text
    assert "That answer was already saved (trial 2); nothing was stored twice." in shown
    assert "Saved: trial" not in shown and "Run now: trial 3" in shown


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"cmp-1-2": "maybe"}, "cmp-1-2"),
        ({"colour": "red"}, "colour"),
        ({"query_id": "abc"}, "query_id"),
        ({"sug-3-step_length": "+huge"}, "sug-3-step_length"),
    ],
)
def test_malformed_answer_forms_are_422_naming_the_field(
    client: TestClient, change: dict[str, str], field: str
) -> None:
    sid = new_session(client)
    form = trial_form(client, sid)
    events = event_count(client, sid)
    r = post(client, f"/sessions/{sid}/answer", {**form.fields, **change, "confirmed": "1"})
    assert r.status_code == 422
    assert f"<code>{field}</code>" in r.text
    assert event_count(client, sid) == events


def test_undo_from_the_page_goes_through_a_confirm_step(client: TestClient) -> None:
    sid = new_session(client)
    answer_once(client, sid)
    html = client.get(f"/sessions/{sid}").text
    undo = forms_of(html)["undo-form"]
    confirm = post(client, f"/sessions/{sid}/undo", undo.fields)
    assert confirm.status_code == 200 and "Undo the last answer?" in confirm.text
    assert "trial 1" in confirm.text
    r = post(client, f"/sessions/{sid}/undo", {**undo.fields, "confirmed": "1"})
    assert r.status_code == 303 and r.headers["location"].endswith("?undone=1")
    assert client.get(f"/api/sessions/{sid}").json()["trials"] == 0
    r = post(client, f"/sessions/{sid}/undo", {**undo.fields, "confirmed": "1"})
    assert r.status_code == 409 and "nothing was undone" in r.text


def test_notes_exclusion_pause_resume_finish_from_the_page(client: TestClient) -> None:
    sid = new_session(client)
    answer_once(client, sid)
    answer_once(client, sid)
    forms = forms_of(client.get(f"/sessions/{sid}").text)
    csrf = forms["answer-form"].fields["csrf_token"]
    assert (
        post(
            client, f"/sessions/{sid}/note", {"csrf_token": csrf, "text": "strap loose"}
        ).status_code
        == 303
    )
    assert (
        post(client, f"/sessions/{sid}/note", {"csrf_token": csrf, "text": " "}).status_code == 422
    )
    long = post(  # refused as the API refuses it, never cut short
        client,
        f"/sessions/{sid}/trials/1/exclude",
        {"csrf_token": csrf, "reason": "device_fault", "detail": "m" * 501},
    )
    assert long.status_code == 422 and "at most 500 characters" in long.text
    exclude = {"csrf_token": csrf, "reason": "device_fault", "detail": "motor"}
    before = event_count(client, sid)
    r = post(client, f"/sessions/{sid}/trials/1/exclude", exclude)  # an exclusion is for good:
    assert r.status_code == 200 and "Exclude this trial?" in r.text  # confirmed first
    assert "device fault (motor)" in r.text and "cannot be taken back" in r.text
    assert event_count(client, sid) == before  # nothing written yet
    r = post(client, f"/sessions/{sid}/trials/1/exclude", forms_of(r.text)["form1"].fields)
    assert r.status_code == 303
    again = post(client, f"/sessions/{sid}/trials/1/exclude", exclude)  # a stale review: 409
    assert again.status_code == 409 and "already excluded" in again.text
    html = client.get(f"/sessions/{sid}").text
    assert "strap loose" in html and "excluded: device fault" in html
    assert (
        post(
            client, f"/sessions/{sid}/status", {"csrf_token": csrf, "status": "paused"}
        ).status_code
        == 303
    )
    html = client.get(f"/sessions/{sid}").text
    assert "Paused" in html and "answer-form" not in html
    assert (
        post(
            client, f"/sessions/{sid}/status", {"csrf_token": csrf, "status": "active"}
        ).status_code
        == 303
    )
    assert (
        post(
            client, f"/sessions/{sid}/status", {"csrf_token": csrf, "status": "finished"}
        ).status_code
        == 200  # the confirm step (without JavaScript)
    )
    assert "Paused" not in client.get(f"/sessions/{sid}").text
    finish = {"csrf_token": csrf, "status": "finished", "confirmed": "1"}
    assert post(client, f"/sessions/{sid}/status", finish).status_code == 303
    html = client.get(f"/sessions/{sid}").text
    assert "Finished" in html and "answer-form" not in html and "Export CSV" in html


def test_a_query_of_two_new_gaits_asks_to_compare_them(client: TestClient) -> None:
    sid = new_session(client, "compass-gait")
    html = client.get(f"/sessions/{sid}").text
    q = client.get(f"/api/sessions/{sid}/query").json()
    a, b = (g["index"] for g in q["actions"])
    form = forms_of(html)["answer-form"]
    assert form.radios[f"cmp-{a}-{b}"] == ["first", "second", "none"]
    assert "Run now: trial 1" in html and "Run now: trial 2" in html
    assert len([k for k in form.radios if k.startswith("sug-")]) == 2  # one per executed gait


def test_validation_pages(client: TestClient) -> None:
    sid = new_session(client)
    for outcome in ("first", "second", "first"):
        answer_once(client, sid, outcome)
    page = client.get(f"/sessions/{sid}/validation").text
    start = forms_of(page)["form1"]
    assert post(client, f"/sessions/{sid}/validation", start.fields).status_code == 303
    page = client.get(f"/sessions/{sid}/validation").text
    assert re.findall(r'data-label="([ABC])"', page) == ["A", "B", "C"]
    trial_page = client.get(f"/sessions/{sid}").text
    assert "A blind validation round is open" in trial_page
    assert "or withdraw the round there, unanswered" in trial_page  # not the ranking alone
    rank = forms_of(page)["ranking-form"]
    assert rank.selects["rank1"] == ["", "A", "B", "C"]
    r = post(client, rank.action, {**rank.fields, "rank1": "C", "rank2": "", "rank3": "A"})
    assert r.status_code == 422 and "<code>rank2</code>" in r.text
    ranked = {**rank.fields, "rank1": "C", "rank2": "B", "rank3": "A"}
    review = post(client, rank.action, ranked)  # the confirm step (without JavaScript)
    assert review.status_code == 200 and "Record this ranking?" in review.text
    assert "best first: 1. C, 2. B, 3. A" in review.text
    assert client.get(f"/api/sessions/{sid}/validation").json()[-1]["ranking"] is None
    confirm = forms_of(review.text)["form1"]
    assert confirm.fields["confirmed"] == "1" and confirm.fields["rank1"] == "C"
    r = post(client, confirm.action, confirm.fields)
    assert r.status_code == 303
    page = client.get(f"/sessions/{sid}/validation").text
    assert "Kendall" in page and 'id="round-1"' in page
    assert "Start a blind validation round" in page


def test_posterior_figure_and_export_links(client: TestClient) -> None:
    sid = new_session(client, "exo-2d-length-width")
    answer_once(client, sid)
    html = client.get(f"/sessions/{sid}").text
    src = re.search(r'<img src="([^"]+)"', html)
    assert src is not None
    png = client.get(src.group(1))
    assert png.status_code == 200 and png.content[:8] == b"\x89PNG\r\n\x1a\n"
    assert client.get(src.group(1)).content == png.content  # cached, same picture
    paper = client.get(f"/sessions/{sid}/figure.png")
    assert paper.status_code == 200 and paper.content[:4] == b"\x89PNG"
    assert paper.content != png.content
    for fmt in ("csv", "json"):
        r = client.get(f"/sessions/{sid}/export.zip", params={"format": fmt})
        assert r.status_code == 200 and r.content[:2] == b"PK"


def test_unknown_sessions_get_an_html_404(client: TestClient) -> None:
    r = client.get("/sessions/42")
    assert r.status_code == 404 and "text/html" in r.headers["content-type"]
    assert "no session 42" in r.text
    assert client.get("/sessions/0").status_code == 422


def test_an_uploaded_config_and_a_refused_one(client: TestClient) -> None:
    from tests.console.test_api import SMALL_TOML

    csrf = forms_of(client.get("/").text)["create-form"].fields["csrf_token"]
    files = {"config_file": ("tiny-speed.toml", SMALL_TOML.replace('name = "tiny"\n', "").encode())}
    r = client.post(
        "/sessions",
        data={"csrf_token": csrf, "subject": "S2", "config": "exo-1d-step-length"},
        files=files,
        follow_redirects=False,
    )
    assert r.status_code == 303
    assert client.get("/api/sessions").json()[0]["config"] == "tiny-speed"
    files = {"config_file": ("bad.toml", b"[model]\nnoise = -1\n")}
    r = client.post(
        "/sessions", data={"csrf_token": csrf, "subject": "S2"}, files=files, follow_redirects=False
    )
    assert r.status_code == 422 and "<code>config</code>" in r.text
    assert len(client.get("/api/sessions").json()) == 1


def test_a_name_is_refused_as_a_subject_code(client: TestClient) -> None:
    csrf = forms_of(client.get("/").text)["create-form"].fields["csrf_token"]
    form = {"csrf_token": csrf, "subject": "Jane Doe", "config": "exo-1d-step-length"}
    r = post(client, "/sessions", form)
    assert r.status_code == 422 and "<code>subject</code>" in r.text and "never a name" in r.text
    assert client.get("/api/sessions").json() == []


def test_a_ranking_forms_shown_field_is_read_within_bounds(client: TestClient) -> None:
    """'shown' (the gaits the validation page showed, a JSON list) deeply nested was a 500
    (json's RecursionError); a long one was parsed whole, then refused as 409 'drawn again':
    both are 422 at ``shown`` (at most 8 names, its text measured first), nothing written."""
    sid = new_session(client)
    for outcome in ("first", "second", "first"):
        answer_once(client, sid, outcome)
    assert client.post(f"/api/sessions/{sid}/validation").status_code == 200
    rank = forms_of(client.get(f"/sessions/{sid}/validation").text)["ranking-form"]
    ranked = {**rank.fields, "rank1": "C", "rank2": "B", "rank3": "A"}
    before = event_count(client, sid)
    for shown in ("[" * 100_000, "[" * 5_000, json.dumps(["G1"] * 30_000), json.dumps(["G1"] * 9)):
        r = post(client, rank.action, {**ranked, "shown": shown})
        assert r.status_code == 422 and "<code>shown</code>" in r.text, r.text[:300]
    assert event_count(client, sid) == before
    assert post(client, rank.action, ranked | {"confirmed": "1"}).status_code == 303


def test_a_ranking_label_past_four_characters_is_refused_naming_its_place(
    client: TestClient,
) -> None:
    """The page's ranking labels were not bounded (the JSON API's are: 4 characters): a long
    one reached the session and was refused there as a stale round (409), quoted whole."""
    sid = new_session(client)
    for outcome in ("first", "second", "first"):
        answer_once(client, sid, outcome)
    assert client.post(f"/api/sessions/{sid}/validation").status_code == 200
    rank = forms_of(client.get(f"/sessions/{sid}/validation").text)["ranking-form"]
    before = event_count(client, sid)
    for label in ("ABCDE", "A" * 100_000):
        r = post(client, rank.action, {**rank.fields, "rank1": "C", "rank2": label, "rank3": "A"})
        assert r.status_code == 422 and "<code>rank2</code>" in r.text, r.text[:300]
        assert "at most 4 characters" in r.text and "A" * 61 not in r.text
    assert event_count(client, sid) == before


def test_the_sessions_page_counts_each_subjects_sessions(client: TestClient) -> None:
    for subject in ("S01", "S02", "S01"):
        new_session(client, subject=subject)
    html = client.get("/").text
    pills = re.findall(r'<span class="pill">([^<]*)</span>', html)
    assert "S01: 2 sessions" in pills and "S02: 1 session" in pills


def test_the_answer_form_of_a_query_of_45_gaits_is_taken(client: TestClient) -> None:
    """Up to 990 comparisons and 90 suggestions: more fields than Starlette's default 1,000,
    which refused the form (413) whatever the operator chose."""
    config = "".join(f"[space.{name}]\nmin = 0.0\nmax = 1.0\nnum = 40\n" for name in ("x", "y")) + (
        "[model]\nlengthscale = 0.2\nsignal_variance = 1.0\nnoise = 0.05\n"
        '[cospar]\nn = 45\nbuffer = 0\nstrategy = "self-sparring"\n'
    )
    r = client.post("/api/sessions", json={"config": config, "subject": "S01"})
    assert r.status_code == 201, r.text
    sid = r.json()["id"]
    form = trial_form(client, sid)
    chosen = {name: "first" for name in form.radios if name.startswith("cmp-")}
    assert len({**form.fields, **chosen}) > 1000  # 900-odd pairs (a gait may be drawn twice)
    confirm = post(client, f"/sessions/{sid}/answer", {**form.fields, **chosen})
    assert confirm.status_code == 200, confirm.text[:300]
    done = post(client, f"/sessions/{sid}/answer", forms_of(confirm.text)["form1"].fields)
    assert done.status_code == 303
    assert client.get(f"/api/sessions/{sid}").json()["trials"] == 45


def test_an_answer_whose_stop_check_fails_is_saved_and_says_so(
    client: TestClient, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """The [stop] rule raising after the answer is stored: the answer is not a 500 (which an
    operator would post again), the page says it is saved and that the rule was not checked,
    and the API's response carries why; the console's log says why each time (a
    ``StopCheckWarning`` alone is shown once per place per process by Python's default
    filter)."""
    caplog.set_level(logging.WARNING, logger="gaitpref.console")
    from gaitpref.sessions import Session, StopCheckWarning

    def fails(self: Session) -> None:
        raise FloatingPointError("the confidence's samples are not finite")

    monkeypatch.setattr(Session, "_stop_if_sure", fails)
    sid = new_session(client)
    with pytest.warns(StopCheckWarning):
        body = answer_once(client, sid)
    assert body["trials"] == [1] and "FloatingPointError" in body["stop_warning"]
    form = trial_form(client, sid)
    cmp = next(k for k in form.radios if k.startswith("cmp-"))
    with pytest.warns(StopCheckWarning):
        done = post(
            client, f"/sessions/{sid}/answer", {**form.fields, cmp: "first", "confirmed": "1"}
        )
    assert done.status_code == 303
    assert done.headers["location"] == f"/sessions/{sid}?answered=2&stop_unchecked=1"
    shown = client.get(done.headers["location"]).text
    assert "Saved: trial 2." in shown and "The [stop] rule could not be checked" in shown
    assert client.get(f"/api/sessions/{sid}").json()["trials"] == 2  # each stored once
    logged = [r.getMessage() for r in caplog.records if r.name == "gaitpref.console"]
    assert len(logged) == 2  # both failures, not the first alone
    assert all(
        m.startswith(f"session {sid}: ") and "FloatingPointError" in m and "[stop] rule" in m
        for m in logged
    )
    monkeypatch.undo()
    assert answer_once(client, sid)["stop_warning"] is None


def test_a_suggestion_past_the_edge_is_said_in_the_answer_and_the_chronology(
    client: TestClient,
) -> None:
    """A move clipped at the edge of its range: the API's answer says so (``clipped``) and the
    trial page's chronology marks it (before, only a move back to the same gait was marked)."""
    from gaitpref.config import load_config

    wide = load_config("exo-1d-step-length").text.replace(
        "coactive = [0.1, 0.2]", "coactive = [0.5, 1.0]"
    )
    assert "coactive = [0.5, 1.0]" in wide
    sid = new_session(client, config=wide)
    q = client.get(f"/api/sessions/{sid}/query").json()
    gait = q["actions"][0]
    value, lo, hi = gait["values"]["step_length"], 0.08, 0.18
    if value in (lo, hi):  # at an edge: a move outwards goes back to the same gait
        move, mark = ("-big" if value == lo else "+small"), "(already at the edge of its range)"
    else:  # "longer" moves the whole range: clipped to the longest step
        move, mark = "+big", "(clipped at the edge of its range)"
    body = {
        "query_id": q["query_id"],
        "comparisons": [],
        "suggestions": [[gait["index"], "step_length", move]],
    }
    r = client.post(f"/api/sessions/{sid}/answers", json=body)
    assert r.status_code == 200, r.text
    (note,) = r.json()["clipped"]
    assert note.startswith("trial 1: step_length ") and "past the edge" in note
    assert mark.replace("'", "&#39;") in client.get(f"/sessions/{sid}").text  # HTML-escaped


def test_best_so_far_is_never_a_gait_flagged_unsafe(client: TestClient) -> None:
    """The trial page's "Best so far" and the API's ``recommended`` are the highest posterior
    mean among the gaits that may be proposed (the gait the confidence names); ``argmax`` stays
    the unrestricted highest, here the gait flagged unsafe."""
    from gaitpref.config import load_config

    text = load_config("exo-1d-step-length").text + "\n[safety]\nunsafe_radius = 0.1\n"
    sid = new_session(client, config=text)
    walked: dict[int, int] = {}
    for _ in range(12):  # the subject prefers the longer step
        q = client.get(f"/api/sessions/{sid}/query").json()
        body = {
            "query_id": q["query_id"],
            "comparisons": [[i, j, "first" if i > j else "second"] for i, j in q["comparisons"]],
        }
        assert client.post(f"/api/sessions/{sid}/answers", json=body).status_code == 200
        trials = client.get(f"/api/sessions/{sid}/trials").json()
        walked = {t["gait"]["index"]: t["trial"] for t in trials}
        best = client.get(f"/api/sessions/{sid}/posterior").json()["argmax"]["index"]
        if best in walked:
            break
    assert best in walked, "the posterior's argmax was never a walked gait"
    post = client.get(f"/api/sessions/{sid}/posterior").json()
    assert post["recommended"]["index"] == best  # nothing flagged yet
    r = client.post(f"/api/sessions/{sid}/trials/{walked[best]}/unsafe", json={"reason": "knee"})
    assert r.status_code == 200, r.text
    post = client.get(f"/api/sessions/{sid}/posterior").json()
    rec = post["recommended"]
    assert post["argmax"]["index"] == best and rec is not None and rec["index"] != best
    mean = post["mean"]
    assert mean[rec["index"]] < mean[best]
    html = client.get(f"/sessions/{sid}").text
    assert f'<b id="best">{rec["gait_id"]}</b>' in html
    assert f'<b id="best">G{best}</b>' not in html
    assert post["confidence"] is None or rec["gait_id"] in post["confidence"]["sentence"]
