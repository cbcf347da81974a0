"""The console withdraws an open blind validation round: the JSON API
(``POST .../validation/{round}/withdraw``) and the validation page (a reason, the undo of the
answer after which the ``[stop]`` rule opened it, a confirm step); who opened a round is shown."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from gaitpref import Session
from gaitpref.config import load_config, parse_config
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from tests.console.conftest import answer_once, keys_ready, new_session
from tests.console.htmlforms import forms_of
from tests.console.test_pages import post

CONFIG = "exo-1d-step-length"


def _ruled(db_url: str) -> tuple[int, int, list[int]]:
    """A session whose [stop] rule opened round 1 after its last answer: its id, that
    answer's query and trials."""
    config = parse_config(
        load_config(CONFIG).text + "\n[stop]\nmax_trials = 4\n", default_name=CONFIG
    )
    subject = SimulatedSubject(config.space, bump_utility(config.space), seed=1)
    with Session.create(db_url, config, "S01") as s:
        while s.validation_plan is None:
            q = s.next_query()
            s.answer(q.id, *subject.respond(q))
        last = s.trials()[-1].query
        return s.id, last, [t.number for t in s.trials() if t.query == last]


def test_the_api_withdraws_a_round_with_the_answer_that_opened_it(
    client: TestClient, db_url: str
) -> None:
    sid, last, trials = _ruled(db_url)
    [open_round] = client.get(f"/api/sessions/{sid}/validation").json()
    assert open_round["round"] == 1 and open_round["opened_by"] == "rule"
    url = f"/api/sessions/{sid}/validation/1/withdraw"
    assert client.post(url, json={"reason": ""}).status_code == 422
    r = client.post(url, json={"reason": "mis-keyed answer", "undo": True})
    assert r.status_code == 200, r.text
    assert r.json() == {
        "round": 1,
        "undone_query_id": last,
        "trials": trials,
        "pending_query_id": last,
        "next_query_error": None,
    }
    assert client.get(f"/api/sessions/{sid}/validation").json() == []
    r = client.post(url, json={"reason": "twice"})
    assert r.status_code == 409
    assert "round 1 is not open: it was withdrawn" in r.json()["detail"]
    assert client.get(f"/api/sessions/{sid}/query").json()["query_id"] == last  # asked again


def test_an_operators_round_is_withdrawn_alone_and_undo_is_refused(client: TestClient) -> None:
    sid = new_session(client)
    for outcome in ("first", "second", "first"):
        answer_once(client, sid, outcome)
    plan = client.post(f"/api/sessions/{sid}/validation").json()
    assert plan["opened_by"] == "operator"
    url = f"/api/sessions/{sid}/validation/{plan['round']}/withdraw"
    r = client.post(url, json={"reason": "x", "undo": True})
    assert r.status_code == 409 and "opened by the operator" in r.json()["detail"]
    r = client.post(url, json={"reason": "subject tired"})
    assert r.status_code == 200 and r.json()["undone_query_id"] is None
    again = client.post(f"/api/sessions/{sid}/validation").json()
    assert again["round"] == plan["round"] + 1  # the next number
    ranked = client.post(
        f"/api/sessions/{sid}/validation/{again['round']}/ranking",
        json={"ranking": ["A", "B", "C"]},
    ).json()
    assert ranked["opened_by"] == "operator" and ranked["kendall_tau"] is not None


def test_the_validation_page_withdraws_the_round_after_a_confirm_step(
    client: TestClient, db_url: str
) -> None:
    sid, last, trials = _ruled(db_url)
    page = client.get(f"/sessions/{sid}/validation").text
    assert "The [stop] rule opened this round after an answer." in page
    form = forms_of(page)["withdraw-round-form"]
    r = post(client, form.action, {**form.fields, "reason": "  "})
    assert r.status_code == 422 and "<code>reason</code>" in r.text
    asked = {**form.fields, "reason": "mis-keyed answer", "undo": "1"}
    review = post(client, form.action, asked)  # the confirm step (without JavaScript)
    assert review.status_code == 200 and "Withdraw this validation round?" in review.text
    assert f"Undo the answer to trial {', '.join(map(str, trials))}, after which" in review.text
    assert client.get(f"/api/sessions/{sid}/validation").json()[0]["round"] == 1  # not yet
    confirm = forms_of(review.text)["form1"]
    assert confirm.fields["confirmed"] == "1" and confirm.fields["undo"] == "1"
    r = post(client, confirm.action, confirm.fields)
    assert r.status_code == 303 and r.headers["location"] == f"/sessions/{sid}"
    with Session.open(db_url, sid) as s:
        kinds = [e.kind for e in s.events()[-2:]]
        assert kinds == ["validation_withdrawn", "undo"]
        assert s.validation_plan is None and s.pending is not None and s.pending.id == last
    page = client.get(f"/sessions/{sid}/validation").text
    assert "withdraw-round-form" not in page and "Start a blind validation round" in page


@pytest.mark.browser
def test_the_validation_page_withdraws_the_round_in_a_browser(
    chromium: Any, live: str, tmp_path: Path
) -> None:
    """Typing the reason does not rank the gaits (A, B, C are the page's keys), and the round
    is withdrawn with its answer after the confirm page."""
    sid, last, trials = _ruled(f"sqlite:///{tmp_path / 'live.db'}")
    page = chromium.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.goto(f"{live}/sessions/{sid}/validation")
    page.fill("#withdraw-round-form input[name=reason]", "abc: a mis-keyed answer")
    page.type("#withdraw-round-form input[name=reason]", " cab")
    assert page.input_value("#rank1") == ""  # typed, not picked
    page.check("#withdraw-undo")
    page.click("#withdraw-round")
    page.wait_for_selector("text=Withdraw this validation round?")
    page.click("text=Confirm")
    page.wait_for_url(f"{live}/sessions/{sid}")
    page.wait_for_selector(f"text=Run now: trial {trials[0]}")
    with Session.open(f"sqlite:///{tmp_path / 'live.db'}", sid) as s:
        assert s.validation_rounds()[0].withdrawn == "abc: a mis-keyed answer cab"
        assert s.pending is not None and s.pending.id == last
    assert errors == []


@pytest.mark.browser
def test_enter_on_the_withdraw_forms_controls_never_records_a_ranking(
    chromium: Any, live: str, tmp_path: Path
) -> None:
    """The ranking is picked (the ranking form would submit on Enter), then Enter is pressed on
    the withdraw form's "also undo" checkbox: the page's Enter shortcut treated the checkbox as
    not typing and opened "Record this ranking?", a second Enter recording it.  Enter there is
    the withdraw form's own now: nothing is ranked; Enter on its button withdraws, after the
    confirm page."""
    url = f"sqlite:///{tmp_path / 'live.db'}"
    sid, last, _ = _ruled(url)
    page = chromium.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.goto(f"{live}/sessions/{sid}/validation")
    keys_ready(page)
    for key in "ABC":
        page.keyboard.press(key)
    assert [page.input_value(f"#rank{k}") for k in (1, 2, 3)] == ["A", "B", "C"]
    page.fill("#withdraw-round-form input[name=reason]", "mis-keyed")
    page.focus("#withdraw-undo")
    page.keyboard.press("Enter")
    page.keyboard.press("Enter")
    page.wait_for_timeout(500)  # what the keys set off (a dialog, a post) has happened by now
    assert not page.locator("#confirm-dialog[open]").count()
    with Session.open(url, sid) as s:
        assert s.validations() == [] and s.validation_plan is not None  # nothing ranked
    page.goto(f"{live}/sessions/{sid}/validation")
    page.fill("#withdraw-round-form input[name=reason]", "mis-keyed")
    page.check("#withdraw-undo")
    page.focus("#withdraw-round")
    keys_ready(page)
    page.keyboard.press("Enter")  # the button's own form: withdraw, after its confirm page
    page.wait_for_selector("text=Withdraw this validation round?")
    with Session.open(url, sid) as s:
        assert s.validations() == [] and s.validation_plan is not None
    page.click("text=Confirm")
    page.wait_for_url(f"{live}/sessions/{sid}")
    with Session.open(url, sid) as s:
        assert s.validations() == [] and s.validation_rounds()[0].withdrawn == "mis-keyed"
        assert s.pending is not None and s.pending.id == last
    assert errors == []
