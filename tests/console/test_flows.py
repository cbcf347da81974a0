"""Operator flows end to end (no browser): what a second tab, a long export or a failed step
does to the other requests of the same session."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import httpx
import pytest
from fastapi.testclient import TestClient

import gaitpref.sessions.export as export_module
from tests.console.conftest import answer_once, event_count, new_session
from tests.console.htmlforms import forms_of


def test_an_export_does_not_hold_up_the_answers_of_its_session(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The export was made under the shared session's lock: on a 150-trial session the
    operator's next answer waited for it (about a minute on this machine)."""
    sid = new_session(client)
    answer_once(client, sid)
    real = export_module.export_session
    during: list[httpx.Response] = []
    q = client.get(f"/api/sessions/{sid}/query").json()
    body = {"query_id": q["query_id"], "comparisons": [[*q["comparisons"][0], "first"]]}

    def slow_export(session: Any, out: Path, fmt: Any = "csv") -> Path:
        answering = threading.Thread(
            target=lambda: during.append(client.post(f"/api/sessions/{sid}/answers", json=body)),
            daemon=True,
        )
        answering.start()
        answering.join(timeout=30)  # blocked until the export ended, before
        assert not answering.is_alive(), "the answer waited for the export"
        return real(session, out, fmt)

    monkeypatch.setattr(export_module, "export_session", slow_export)
    r = client.get(f"/sessions/{sid}/export.zip")
    assert r.status_code == 200
    assert [a.status_code for a in during] == [200]
    assert client.get(f"/api/sessions/{sid}").json()["trials"] == 2


def test_the_sessions_page_says_its_times_are_utc(client: TestClient) -> None:
    """The table's 'updated' times were UTC without saying so (an hour or more off the lab's
    clock in most of Europe)."""
    sid = new_session(client)
    updated = client.get("/api/sessions").json()[0]["updated_at"]
    assert updated.endswith("+00:00")
    html = client.get("/").text
    row = html[html.index(f'data-session="{sid}"') :]
    shown = f"{updated[:10]} {updated[11:16]} UTC"
    assert f'<time datetime="{updated}">{shown}</time>' in row


def test_a_reloaded_page_does_not_say_what_another_tab_took_back(client: TestClient) -> None:
    """Reloading ``?answered=2`` after another tab undid trial 2 said "Saved: trial 2." above
    trial 2 asked again; and any text after ``answered=`` was shown as saved."""
    sid = new_session(client)
    answer_once(client, sid)
    answer_once(client, sid)
    assert "Saved: trial 2." in client.get(f"/sessions/{sid}?answered=2").text
    assert client.post(f"/api/sessions/{sid}/undo").status_code == 200  # the other tab
    page = client.get(f"/sessions/{sid}?answered=2").text
    assert "Saved: trial 2." not in page and "Run now: trial 2" in page
    assert "Undone: the answer to trial 2" in client.get(f"/sessions/{sid}?undone=2").text
    answer_once(client, sid)
    assert "Undone" not in client.get(f"/sessions/{sid}?undone=2").text  # answered again since
    assert 'id="flash"' not in client.get(f"/sessions/{sid}?answered=9").text
    assert 'id="flash"' not in client.get(f"/sessions/{sid}?answered=all%20done").text
    flag = f"/api/sessions/{sid}/trials/2/unsafe"
    assert client.post(flag, json={"reason": "slipped"}).status_code == 200
    assert "Trial 2 flagged unsafe" in client.get(f"/sessions/{sid}?flagged=2").text
    assert client.post(f"{flag}/withdraw").status_code == 200  # the other tab
    assert "flagged unsafe" not in client.get(f"/sessions/{sid}?flagged=2").text
    assert "flag of trial 2 was withdrawn" in client.get(f"/sessions/{sid}?withdrawn=2").text


def test_a_ranking_of_a_round_drawn_again_since_the_page_loaded_is_refused(
    client: TestClient,
) -> None:
    """A flag on a gait the open round shows draws the round again with the same number; a
    validation page loaded before (another tab, the operator's tablet) posted its ranking of
    the gaits it showed, and it was booked against the new round's gaits."""
    from tests.console.test_ratings_safety import rated_config

    sid = new_session(client, rated_config(0.05))
    for _ in range(3):
        answer_once(client, sid)
    for _ in range(12):  # until a round shows a gait a trial walked
        answer_once(client, sid)
        r = client.post(f"/api/sessions/{sid}/validation")
        assert r.status_code == 200, r.text
        plan = r.json()
        shown = {g["gait"]["index"] for g in plan["gaits"]}
        trials = client.get(f"/api/sessions/{sid}/trials").json()
        walked = [t for t in trials if t["gait"]["index"] in shown]
        if walked:
            break
        ranking = {"ranking": ["A", "B", "C"]}
        client.post(f"/api/sessions/{sid}/validation/{plan['round']}/ranking", json=ranking)
    assert walked, "no round showed a walked gait"
    stale = forms_of(client.get(f"/sessions/{sid}/validation").text)["ranking-form"]
    flag = f"/api/sessions/{sid}/trials/{walked[0]['trial']}/unsafe"
    assert client.post(flag, json={"reason": "knee gave way"}).status_code == 200
    again = client.get(f"/api/sessions/{sid}/validation").json()[-1]
    assert again["round"] == plan["round"] and again["gaits"] != plan["gaits"]
    before = event_count(client, sid)
    data = {**stale.fields, "rank1": "A", "rank2": "B", "rank3": "C"}
    for confirmed in ("", "1"):  # refused at the confirm step already
        r = client.post(stale.action, data=data | {"confirmed": confirmed}, follow_redirects=False)
        assert r.status_code == 409 and "was drawn again since its gaits were shown" in r.text
    assert event_count(client, sid) == before
    old_ids = [g["gait"]["gait_id"] for g in plan["gaits"]]
    rank_url = f"/api/sessions/{sid}/validation/{plan['round']}/ranking"
    r = client.post(rank_url, json={"ranking": ["A", "B", "C"], "shown": old_ids})
    assert r.status_code == 409 and "drawn again" in r.json()["detail"]
    assert event_count(client, sid) == before
    fresh = forms_of(client.get(f"/sessions/{sid}/validation").text)["ranking-form"]
    ranked = {**fresh.fields, "rank1": "A", "rank2": "B", "rank3": "C", "confirmed": "1"}
    r = client.post(fresh.action, data=ranked)
    assert r.status_code == 200 and f'id="round-{plan["round"]}"' in r.text


@pytest.mark.parametrize("spoil", ["exclude", "unsafe"])
def test_no_undo_is_offered_that_the_session_refuses(client: TestClient, spoil: str) -> None:
    """An excluded or flagged last trial kept its 'Undo last answer' button, whose confirm step
    ended in a 409 page (the session refuses to undo such an answer)."""
    sid = new_session(client)
    answer_once(client, sid)
    answer_once(client, sid)
    assert 'id="undo-form"' in client.get(f"/sessions/{sid}").text
    body = {"reason": "stumble"} if spoil == "exclude" else {"reason": "knee gave way"}
    assert client.post(f"/api/sessions/{sid}/trials/2/{spoil}", json=body).status_code == 200
    assert client.post(f"/api/sessions/{sid}/undo").status_code == 409
    assert 'id="undo-form"' not in client.get(f"/sessions/{sid}").text
    if spoil == "unsafe":
        client.post(f"/api/sessions/{sid}/trials/2/unsafe/withdraw")
        assert 'id="undo-form"' in client.get(f"/sessions/{sid}").text


def test_a_finished_sessions_open_round_offers_no_ranking(client: TestClient) -> None:
    """A session finished with a validation round open showed the round's ranking form, whose
    every post was a 409 (a finished session takes no ranking)."""
    sid = new_session(client)
    for _ in range(4):
        answer_once(client, sid)
    assert client.post(f"/api/sessions/{sid}/validation").status_code == 200
    assert client.post(f"/api/sessions/{sid}/status", json={"status": "finished"}).is_success
    page = client.get(f"/sessions/{sid}/validation").text
    assert "ranking-form" not in forms_of(page)
    assert "finished with this round open" in page


def test_the_console_says_why_the_stop_rule_cannot_open_validation(client: TestClient) -> None:
    from gaitpref import load_config

    config = load_config("exo-1d-step-length").text + "\n[stop]\nmax_trials = 1\n"
    sid = new_session(client, config)
    assert client.get(f"/api/sessions/{sid}").json()["stop_blocked"] is None
    answer_once(client, sid)  # the first query compares nothing: nothing learnt
    blocked = client.get(f"/api/sessions/{sid}").json()["stop_blocked"]
    assert "max_trials = 1" in blocked and "the posterior mean is flat" in blocked
    page = client.get(f"/sessions/{sid}").text
    assert 'id="stop-blocked"' in page and "cannot open blind validation" in page


def test_the_console_says_why_the_stop_rule_opened_validation(client: TestClient) -> None:
    """When the rule opened blind validation after an answer, the answer's response and the
    page with the open round said nothing of the rule: the round just appeared."""
    from gaitpref import load_config

    config = load_config("exo-1d-step-length").text + "\n[stop]\nmax_trials = 2\n"
    sid = new_session(client, config)
    said = []
    for _ in range(2):
        q = client.get(f"/api/sessions/{sid}/query").json()
        action = q["actions"][0]["index"]
        body = {
            "query_id": q["query_id"],
            "comparisons": [[i, j, "first"] for i, j in q["comparisons"]],
            "suggestions": [[action, "step_length", "+small" if action < 14 else "-small"]],
        }
        r = client.post(f"/api/sessions/{sid}/answers", json=body)
        assert r.status_code == 200, r.text
        said.append(r.json()["stopped"])
    assert said == [None, "2 trials reached max_trials = 2"]
    page = client.get(f"/sessions/{sid}").text
    assert "A blind validation round is open" in page
    assert (
        '<p id="stop-reason" role="status">The [stop] rule says stop: 2 trials reached '
        "max_trials = 2.</p>" in page
    )
