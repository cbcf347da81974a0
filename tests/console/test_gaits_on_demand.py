"""A console session whose config names a gait generator: gait ids as with a library, and the
gaits that could not be made listed on the trial page, never offered as a trial."""

from __future__ import annotations

import numpy as np
import pytest
from fastapi.testclient import TestClient

from gaitpref.errors import GaitGeneratorError, SimulationError
from tests.console.conftest import event_count, new_session
from tests.console.htmlforms import forms_of
from tests.sessions.gaitkit import CONFIG, FakeSteps


def test_the_console_runs_a_session_with_gaits_made_on_demand(client: TestClient) -> None:
    sid = new_session(client, CONFIG, seed=4)
    shown = []
    for _ in range(12):
        q = client.get(f"/api/sessions/{sid}/query").json()
        shown += q["actions"]
        gaits = {g["index"]: g for g in q["actions"] + q["buffer"]}
        comparisons = []
        for i, j in q["comparisons"]:  # the subject prefers short steps
            first = gaits[i]["values"]["step_length"] <= gaits[j]["values"]["step_length"]
            comparisons.append([i, j, "first" if first else "second"])
        body = {"query_id": q["query_id"], "comparisons": comparisons}
        assert client.post(f"/api/sessions/{sid}/answers", json=body).status_code == 200
    assert all(g["values"]["step_length"] >= FakeSteps.below for g in shown)
    assert all(g["gait_id"].startswith("S") for g in shown)  # the generator's ids
    kinds = [e["kind"] for e in client.get(f"/api/sessions/{sid}/events").json()]
    assert "gait_made" in kinds and "gait_infeasible" in kinds
    page = client.get(f"/sessions/{sid}").text
    assert "Gaits that could not be made" in page
    assert "too short" in page


@pytest.mark.parametrize("error", [GaitGeneratorError("solver crashed"), SimulationError("fell")])
def test_a_generator_that_fails_leaves_the_trial_page_usable_and_writes_nothing(
    client: TestClient, monkeypatch: pytest.MonkeyPatch, error: Exception
) -> None:
    """A generator that raises (not an infeasible gait: an error) was a 422 "refused input"
    page for GaitGeneratorError and a bare 500 for SimulationError, on a GET."""
    sid = new_session(client, CONFIG, seed=4)

    def fails(self: FakeSteps, vector: object, warm_start: object = None) -> None:
        raise error

    monkeypatch.setattr(FakeSteps, "make", fails)
    before = event_count(client, sid)
    page = client.get(f"/sessions/{sid}")
    assert page.status_code == 200
    assert "The next gait could not be made" in page.text and str(error) in page.text
    assert 'id="answer-form"' not in page.text
    assert 'value="finished"' in page.text  # the session can still be finished
    r = client.get(f"/api/sessions/{sid}/query")
    assert r.status_code == 503 and str(error) in r.json()["detail"]
    assert event_count(client, sid) == before
    monkeypatch.undo()
    assert client.get(f"/api/sessions/{sid}/query").status_code == 200


def test_an_ask_that_stops_at_max_infeasible_says_so_and_only_an_explicit_ask_goes_on(
    client: TestClient,
) -> None:
    """Each reload of the page (and each poll of GET .../query) asked again, so a session whose
    asks keep stopping made up to max_infeasible more gaits per request, without end on a
    continuous space with avoid_radius 0.  A read now says the stop again; asking again is the
    page's "Ask again" (or POST .../query)."""
    FakeSteps.below = 0.95  # most step lengths have no gait
    config = CONFIG.replace("avoid_radius = 0.1\n", "avoid_radius = 0.1\nmax_infeasible = 2\n")
    sid = new_session(client, config, seed=4)
    page = client.get(f"/sessions/{sid}")
    assert page.status_code == 200
    assert "No gait could be made for this ask" in page.text
    assert "2 gaits that cannot be made" in page.text and "max_infeasible" in page.text
    assert "Gaits that could not be made" in page.text  # the stopped ask's, listed
    assert 'id="answer-form"' not in page.text
    kinds = [e["kind"] for e in client.get(f"/api/sessions/{sid}/events").json()]
    assert kinds == ["created", "gait_infeasible", "gait_infeasible", "query_stopped"]
    made = len(FakeSteps.calls)
    for _ in range(5):  # reloads and polls: the same stop, no gait made, nothing written
        assert "2 gaits that cannot be made" in client.get(f"/sessions/{sid}").text
        r = client.get(f"/api/sessions/{sid}/query")
        assert r.status_code == 409 and "2 gaits that cannot be made" in r.json()["detail"]
    assert event_count(client, sid) == len(kinds) and len(FakeSteps.calls) == made
    for _ in range(30):  # each "Ask again" goes on from the gaits avoided so far
        page = client.get(f"/sessions/{sid}")
        if 'id="answer-form"' in page.text:
            break
        ask = forms_of(page.text)["ask-form"]
        r = client.post(ask.action, data=ask.fields, follow_redirects=False)
        assert r.status_code == 303
    else:
        raise AssertionError("no query after 30 asks")
    q = client.get(f"/api/sessions/{sid}/query").json()
    assert all(g["values"]["step_length"] >= FakeSteps.below for g in q["actions"])


def test_the_api_asks_again_only_when_posted(client: TestClient) -> None:
    FakeSteps.below = 0.95
    config = CONFIG.replace("avoid_radius = 0.1\n", "avoid_radius = 0.1\nmax_infeasible = 2\n")
    sid = new_session(client, config, seed=4)
    assert client.get(f"/api/sessions/{sid}/query").status_code == 409  # the first ask stops
    count = event_count(client, sid)
    assert client.get(f"/api/sessions/{sid}/query").status_code == 409
    assert event_count(client, sid) == count
    for _ in range(30):
        r = client.post(f"/api/sessions/{sid}/query")
        if r.status_code == 200:
            break
        assert r.status_code == 409 and "max_infeasible" in r.json()["detail"]
        assert event_count(client, sid) > count  # this ask went on, and logged its stop
        count = event_count(client, sid)
    else:
        raise AssertionError("no query after 30 asks")
    assert client.get(f"/api/sessions/{sid}/query").json()["query_id"] == r.json()["query_id"]


def _withdrawn_on_undo(client: TestClient) -> int:
    """A session whose last answer's query proposes a gait flagged unsafe since: undoing it
    withdraws that query and proposes a new one in its place (made on demand)."""
    sid = new_session(client, CONFIG + "[safety]\nunsafe_radius = 0.3\n", seed=1)
    for _ in range(2):
        q = client.get(f"/api/sessions/{sid}/query").json()
        body = {"query_id": q["query_id"], "comparisons": [[*c, "first"] for c in q["comparisons"]]}
        assert client.post(f"/api/sessions/{sid}/answers", json=body).status_code == 200
    r = client.post(f"/api/sessions/{sid}/trials/1/unsafe", json={"reason": "hip"})
    assert r.status_code == 200
    assert r.json()[1]["gait"]["values"]["step_length"] == 0.65  # near trial 1's 0.4
    return sid


def _generator_fails(monkeypatch: pytest.MonkeyPatch) -> None:
    def fails(self: FakeSteps, vector: object, warm_start: object = None) -> None:
        raise GaitGeneratorError("solver crashed")

    monkeypatch.setattr(FakeSteps, "make", fails)


def test_an_undo_whose_new_query_cannot_be_made_says_it_was_undone(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The undo was written, then the gait of the query proposed in the withdrawn one's place
    could not be made: the API answered 503 with the generator's error alone, as if nothing had
    happened (a client would undo again and take back another answer)."""
    sid = _withdrawn_on_undo(client)
    _generator_fails(monkeypatch)
    before = client.get(f"/api/sessions/{sid}/events").json()
    r = client.post(f"/api/sessions/{sid}/undo", json={})
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["trials"] == [2] and body["withdrawn"] is True
    assert body["pending_query_id"] is None and "solver crashed" in body["next_query_error"]
    after = client.get(f"/api/sessions/{sid}/events").json()
    assert after[: len(before)] == before and [e["kind"] for e in after[len(before) :]] == ["undo"]
    assert client.get(f"/api/sessions/{sid}").json()["trials"] == 1
    r = client.get(f"/api/sessions/{sid}/query")
    assert r.status_code == 503 and "solver crashed" in r.json()["detail"]
    monkeypatch.undo()
    q = client.get(f"/api/sessions/{sid}/query").json()
    assert q["query_id"] != body["undone_query_id"]
    # an undo whose query is asked again, or made, says nothing of the kind
    answered = client.post(
        f"/api/sessions/{sid}/answers",
        json={"query_id": q["query_id"], "comparisons": [[*c, "first"] for c in q["comparisons"]]},
    )
    assert answered.status_code == 200
    again = client.post(f"/api/sessions/{sid}/undo", json={}).json()
    assert again["withdrawn"] is False and again["next_query_error"] is None


def test_an_undo_from_the_page_whose_new_query_cannot_be_made_says_it_was_undone(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The page answered a 503 'Gait not made' page for an undo that was written."""
    sid = _withdrawn_on_undo(client)
    undo = forms_of(client.get(f"/sessions/{sid}").text)["undo-form"]
    _generator_fails(monkeypatch)
    before = event_count(client, sid)
    r = client.post(
        f"/sessions/{sid}/undo", data={**undo.fields, "confirmed": "1"}, follow_redirects=False
    )
    assert r.status_code == 303, r.text
    assert event_count(client, sid) == before + 1  # the undo, once
    page = client.get(r.headers["location"])
    assert page.status_code == 200
    text = " ".join(page.text.split())
    assert "Undone: the answer to trial 2 was taken back" in text
    assert "no new query could be proposed in its place" in text
    assert "a new query is proposed in its place" not in text
    assert "The next gait could not be made" in text and "solver crashed" in text
    assert event_count(client, sid) == before + 1


@pytest.mark.parametrize(
    "error", [RuntimeError("boom"), np.linalg.LinAlgError("Singular matrix")], ids=type
)
def test_a_generator_fault_is_a_gait_not_made_and_writes_nothing(
    client: TestClient, monkeypatch: pytest.MonkeyPatch, error: Exception
) -> None:
    """A generator that raises an error not of gaitpref's own (a bug, numpy's LinAlgError) was
    a bare 500 (RuntimeError) or a 422 "refused input" (LinAlgError is a ValueError); it is a
    gait not made, as a GaitError, naming the generator, the gait and the error."""
    sid = new_session(client, CONFIG, seed=4)

    def fails(self: FakeSteps, vector: object, warm_start: object = None) -> None:
        raise error

    monkeypatch.setattr(FakeSteps, "make", fails)
    before = event_count(client, sid)
    page = client.get(f"/sessions/{sid}")
    assert page.status_code == 200 and "The next gait could not be made" in page.text
    r = client.get(f"/api/sessions/{sid}/query")
    detail = r.json()["detail"]
    assert r.status_code == 503 and f"{type(error).__name__}: {error}" in detail
    assert "the gait generator 'test-steps' failed making gait" in detail
    assert "Nothing is logged" in detail
    assert event_count(client, sid) == before
    monkeypatch.undo()
    assert client.get(f"/api/sessions/{sid}/query").status_code == 200
