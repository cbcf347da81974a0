"""A console session whose config names a gait generator: gait ids as with a library, and the
gaits that could not be made listed on the trial page, never offered as a trial."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient

from gaitpref.errors import GaitGeneratorError, SimulationError
from tests.console.conftest import event_count, new_session
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


def test_an_ask_that_stops_at_max_infeasible_says_so_and_a_reload_goes_on(
    client: TestClient,
) -> None:
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
    r = client.get(f"/api/sessions/{sid}/query")
    assert r.status_code == 409 and "max_infeasible" in r.json()["detail"]
    for _ in range(30):  # each reload goes on from the gaits avoided so far
        if 'id="answer-form"' in client.get(f"/sessions/{sid}").text:
            break
    else:
        raise AssertionError("no query after 30 reloads")
    q = client.get(f"/api/sessions/{sid}/query").json()
    assert all(g["values"]["step_length"] >= FakeSteps.below for g in q["actions"])
