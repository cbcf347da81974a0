"""A console session whose config names a gait generator: gait ids as with a library, and the
gaits that could not be made listed on the trial page, never offered as a trial."""

from __future__ import annotations

from fastapi.testclient import TestClient

from tests.console.conftest import new_session
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
