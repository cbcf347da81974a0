"""The JSON API: every endpoint, and the errors each one gives (404, 409, 422), with nothing
written by a refused request."""

from __future__ import annotations

import io
import json
import zipfile
from concurrent.futures import ThreadPoolExecutor

import pytest
from fastapi.testclient import TestClient

from gaitpref.config import load_config
from gaitpref.console import create_app
from tests.console.conftest import answer_once, event_count, new_session

SMALL_TOML = """
name = "tiny"
[space.speed]
values = [0.2, 0.3, 0.4, 0.5]
unit = "m/s"
words = ["faster", "slower"]
[model]
lengthscale = 0.1
signal_variance = 0.005
noise = 0.02
[cospar]
n = 2
buffer = 0
"""


def loc_of(response: object) -> list[object]:
    detail = response.json()["detail"]  # type: ignore[attr-defined]
    assert isinstance(detail, list), detail
    return list(detail[0]["loc"])


# -- configs and sessions ----------------------------------------------------------------------
def test_configs_lists_the_shipped_configs(client: TestClient) -> None:
    names = {c["name"]: c for c in client.get("/api/configs").json()}
    assert names["exo-2d-length-duration"]["grid"] == [15, 10]
    assert names["exo-1d-step-length"]["n"] == 1 and names["exo-1d-step-length"]["buffer"] == 1


def test_create_from_a_shipped_name_and_from_toml_text(client: TestClient) -> None:
    a = new_session(client)
    b = new_session(client, SMALL_TOML, seed=7)
    assert b == a + 1
    listed = {s["id"]: s for s in client.get("/api/sessions").json()}
    assert listed[a]["config"] == "exo-1d-step-length"
    assert listed[b]["config"] == "tiny"
    info = client.get(f"/api/sessions/{b}").json()
    assert info["seed"] == 7 and info["trials"] == 0 and info["status"] == "active"
    assert info["features"][0]["moves"]["+small"] == "slightly faster"


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ({"config": "no-such-config", "subject": "S01"}, "config"),
        ({"config": "[space\nbroken", "subject": "S01"}, "config"),
        ({"config": "/etc/passwd", "subject": "S01"}, "config"),
        ({"config": "exo-1d-step-length", "subject": "Jane Doe"}, "subject"),
        ({"config": "exo-1d-step-length"}, "subject"),
        ({"config": "exo-1d-step-length", "subject": "S01", "seed": -1}, "seed"),
        ({"config": "exo-1d-step-length", "subject": "S01", "seed": "1"}, "seed"),
        ({"config": "exo-1d-step-length", "subject": "S01", "colour": "red"}, "colour"),
        ({"config": 3, "subject": "S01"}, "config"),
    ],
)
def test_create_refuses_bad_bodies_naming_the_field(
    client: TestClient, body: dict[str, object], field: str
) -> None:
    r = client.post("/api/sessions", json=body)
    assert r.status_code == 422
    assert field in loc_of(r)
    assert "root:" not in r.text  # a path is never read
    assert client.get("/api/sessions").json() == []


def test_create_refuses_a_config_the_model_cannot_use(client: TestClient) -> None:
    r = client.post(
        "/api/sessions", json={"config": SMALL_TOML.replace("n = 2", "n = 0"), "subject": "S1"}
    )
    assert r.status_code == 422 and loc_of(r) == ["body", "config"]
    assert "n" in r.json()["detail"][0]["msg"]


@pytest.mark.parametrize(
    "config", ["b = " + "[" * 500 + "]" * 500, SMALL_TOML.replace("n = 2", "n = " + "2" * 5000)]
)
def test_toml_python_cannot_read_is_a_422_naming_the_config(
    client: TestClient, config: str
) -> None:
    """Nesting past the recursion limit and integers past 4300 digits: tomllib raises
    RecursionError and ValueError, not TOMLDecodeError (a 500 and a 422 without a field)."""
    r = client.post("/api/sessions", json={"config": config, "subject": "S1"})
    assert r.status_code == 422 and loc_of(r) == ["body", "config"], r.text
    assert "config is not valid TOML" in r.json()["detail"][0]["msg"]
    assert client.get("/api/sessions").json() == []


def test_a_non_json_body_is_refused(client: TestClient) -> None:
    r = client.post(
        "/api/sessions",
        content="config=exo-1d-step-length&subject=S01",
        headers={"content-type": "application/x-www-form-urlencoded"},
    )
    assert r.status_code == 422
    assert client.get("/api/sessions").json() == []


@pytest.mark.parametrize(
    "path",
    [
        "/api/sessions/99",
        "/api/sessions/99/query",
        "/api/sessions/99/posterior",
        "/api/sessions/99/trials",
        "/api/sessions/99/events",
        "/api/sessions/99/validation",
    ],
)
def test_unknown_sessions_are_404(client: TestClient, path: str) -> None:
    r = client.get(path)
    assert r.status_code == 404
    assert "99" in r.json()["detail"]


@pytest.mark.parametrize("sid", ["0", "-3", "abc", str(2**64)])
def test_bad_session_ids_are_422(client: TestClient, sid: str) -> None:
    r = client.get(f"/api/sessions/{sid}/query")
    assert r.status_code == 422
    assert "session_id" in loc_of(r)


# -- the query, as a device controller reads it ------------------------------------------------
def test_the_same_query_until_answered_in_physical_units(client: TestClient) -> None:
    sid = new_session(client, "exo-2d-length-duration")
    first = client.get(f"/api/sessions/{sid}/query").json()
    events = event_count(client, sid)
    again = client.get(f"/api/sessions/{sid}/query").json()
    assert again == first
    assert event_count(client, sid) == events  # reading again writes nothing
    gait = first["actions"][0]
    space = load_config("exo-2d-length-duration").space
    assert gait["values"] == pytest.approx(space.values_of(gait["index"]))
    assert gait["units"] == {"step_length": "m", "step_duration": "s"}
    assert gait["trial"] == 1 and first["buffer"] == [] and first["comparisons"] == []
    answer_once(client, sid)
    second = client.get(f"/api/sessions/{sid}/query").json()
    assert second["query_id"] != first["query_id"]
    assert second["buffer"][0]["index"] == gait["index"] and second["buffer"][0]["trial"] == 1
    assert second["comparisons"] == [[second["actions"][0]["index"], gait["index"]]]


def test_acknowledge_is_logged_once_and_refused_for_other_queries(client: TestClient) -> None:
    sid = new_session(client)
    q = client.get(f"/api/sessions/{sid}/query").json()
    r = client.post(f"/api/sessions/{sid}/query/{q['query_id']}/ack")
    assert r.status_code == 200 and r.json() == {"query_id": q["query_id"], "acknowledged": True}
    events = event_count(client, sid)
    r = client.post(f"/api/sessions/{sid}/query/{q['query_id']}/ack")
    assert r.json()["acknowledged"] is False
    assert event_count(client, sid) == events
    r = client.post(f"/api/sessions/{sid}/query/{q['query_id'] + 50}/ack")
    assert r.status_code == 409 and "not the pending query" in r.json()["detail"]
    assert event_count(client, sid) == events
    kinds = [e["kind"] for e in client.get(f"/api/sessions/{sid}/events").json()]
    assert kinds.count("note") == 1


# -- answers -----------------------------------------------------------------------------------
def test_answer_then_a_second_answer_to_the_same_query_is_409_and_writes_nothing(
    client: TestClient,
) -> None:
    sid = new_session(client)
    answer_once(client, sid)
    q = client.get(f"/api/sessions/{sid}/query").json()
    i, j = q["comparisons"][0]
    body = {
        "query_id": q["query_id"],
        "comparisons": [[i, j, "second"]],
        "suggestions": [[i, "step_length", "-big"]],
        "note": "felt short",
    }
    r = client.post(f"/api/sessions/{sid}/answers", json=body)
    assert r.status_code == 200
    assert r.json()["query_id"] == q["query_id"] and r.json()["trials"] == [2]
    events = event_count(client, sid)
    r = client.post(f"/api/sessions/{sid}/answers", json=body)
    assert r.status_code == 409
    assert "already answered" in r.json()["detail"] and "nothing was written" in r.json()["detail"]
    assert event_count(client, sid) == events
    log = client.get(f"/api/sessions/{sid}/events").json()
    assert any(e["kind"] == "note" and "felt short" in e["payload"]["text"] for e in log)
    assert [e["payload"]["outcome"] for e in log if e["kind"] == "comparison_answered"] == [
        "second"
    ]


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ({"query_id": "2"}, "query_id"),
        ({"query_id": True}, "query_id"),
        ({"query_id": 0}, "query_id"),
        ({"comparisons": []}, "query_id"),
        ({"query_id": 2, "comparisons": [[1, 2]]}, "comparisons"),
        ({"query_id": 2, "comparisons": [[1, 2, "better"]]}, "comparisons"),
        ({"query_id": 2, "comparisons": [[1.5, 2, "first"]]}, "comparisons"),
        ({"query_id": 2, "comparisons": "all"}, "comparisons"),
        ({"query_id": 2, "suggestions": [[1, "step_length", "+huge"]]}, "suggestions"),
        ({"query_id": 2, "suggestions": [[1, 5, "+big"]]}, "suggestions"),
        ({"query_id": 2, "extra": 1}, "extra"),
        ({"query_id": 2, "note": "x" * 2001}, "note"),
    ],
)
def test_malformed_answers_are_422_naming_the_field(
    client: TestClient, body: dict[str, object], field: str
) -> None:
    sid = new_session(client)
    client.get(f"/api/sessions/{sid}/query")
    events = event_count(client, sid)
    r = client.post(f"/api/sessions/{sid}/answers", json=body)
    assert r.status_code == 422, r.text
    assert field in loc_of(r)
    assert event_count(client, sid) == events


def test_answers_the_model_refuses_are_422_naming_the_field(client: TestClient) -> None:
    sid = new_session(client)
    answer_once(client, sid)
    q = client.get(f"/api/sessions/{sid}/query").json()
    events = event_count(client, sid)
    a = q["actions"][0]["index"]
    off_query = next(k for k in range(15) if k not in (a, q["buffer"][0]["index"]))
    cases = [
        ({"comparisons": [[a, off_query, "first"]]}, "comparisons", "not in this query"),
        ({"comparisons": [[a, 10_000, "first"]]}, "comparisons", "off the grid"),
        ({"suggestions": [[a, "step_width", "+big"]]}, "suggestions", "unknown feature"),
        (
            {"suggestions": [[q["buffer"][0]["index"], "step_length", "+big"]]},
            "suggestions",
            "not executed",
        ),
    ]
    for extra, field, words in cases:
        r = client.post(f"/api/sessions/{sid}/answers", json={"query_id": q["query_id"], **extra})
        assert r.status_code == 422, (extra, r.text)
        assert loc_of(r) == ["body", field]
        assert words in r.json()["detail"][0]["msg"]
    assert event_count(client, sid) == events


def test_a_stale_query_id_is_409(client: TestClient) -> None:
    sid = new_session(client)
    q = client.get(f"/api/sessions/{sid}/query").json()
    r = client.post(f"/api/sessions/{sid}/answers", json={"query_id": q["query_id"] + 1})
    assert r.status_code == 409 and "stale or unknown" in r.json()["detail"]


def test_two_clients_answering_the_same_query_at_once_keep_one_answer(db_url: str) -> None:
    app = create_app(db_url)
    clients = [TestClient(app) for _ in range(4)]
    sid = new_session(clients[0])
    q = clients[0].get(f"/api/sessions/{sid}/query").json()
    body = {
        "query_id": q["query_id"],
        "suggestions": [[q["actions"][0]["index"], "step_length", "+big"]],
    }
    with ThreadPoolExecutor(4) as pool:
        codes = sorted(
            pool.map(
                lambda c: c.post(f"/api/sessions/{sid}/answers", json=body).status_code, clients
            )
        )
    assert codes == [200, 409, 409, 409]
    log = clients[0].get(f"/api/sessions/{sid}/events").json()
    assert sum(e["kind"] == "suggestion_given" for e in log) == 1


def test_two_consoles_on_one_database_cannot_double_count(db_url: str) -> None:
    one, two = TestClient(create_app(db_url)), TestClient(create_app(db_url))
    sid = new_session(one)
    q = one.get(f"/api/sessions/{sid}/query").json()
    assert two.get(f"/api/sessions/{sid}/query").json() == q  # the second console sees the same
    body = {"query_id": q["query_id"]}
    assert one.post(f"/api/sessions/{sid}/answers", json=body).status_code == 200
    events = event_count(one, sid)
    r = two.post(f"/api/sessions/{sid}/answers", json=body)
    assert r.status_code == 409
    assert event_count(one, sid) == events
    assert two.get(f"/api/sessions/{sid}").json()["trials"] == 1  # and it caught up


# -- undo --------------------------------------------------------------------------------------
def test_undo_makes_the_answered_query_pending_again(client: TestClient) -> None:
    sid = new_session(client)
    r = client.post(f"/api/sessions/{sid}/undo")
    assert r.status_code == 409 and "nothing to undo" in r.json()["detail"]
    first = answer_once(client, sid)
    q2 = client.get(f"/api/sessions/{sid}/query").json()
    r = client.post(f"/api/sessions/{sid}/undo", json={"query_id": q2["query_id"]})
    assert r.status_code == 200
    assert r.json() == {
        "pending_query_id": first["query_id"],
        "trials": [1],
        "discarded_query_id": q2["query_id"],
        "undone_query_id": first["query_id"],
        "withdrawn": False,
        "next_query_error": None,
    }
    again = client.get(f"/api/sessions/{sid}/query").json()
    assert again["query_id"] == first["query_id"]
    assert client.get(f"/api/sessions/{sid}").json()["trials"] == 0


def test_undo_naming_a_query_that_is_no_longer_pending_is_409(client: TestClient) -> None:
    sid = new_session(client)
    answer_once(client, sid)
    q = client.get(f"/api/sessions/{sid}/query").json()
    answer_once(client, sid)
    events = event_count(client, sid)
    r = client.post(f"/api/sessions/{sid}/undo", json={"query_id": q["query_id"]})
    assert r.status_code == 409 and "nothing was undone" in r.json()["detail"]
    # no query is pending yet after the answer (it was "no query is pending pending")
    assert "now no query is pending (another tab" in r.json()["detail"]
    assert event_count(client, sid) == events
    r = client.post(f"/api/sessions/{sid}/undo", json={"query_id": "x"})
    assert r.status_code == 422 and "query_id" in loc_of(r)


# -- reading the model -------------------------------------------------------------------------
def test_posterior_has_a_mean_and_sd_per_action(client: TestClient) -> None:
    sid = new_session(client, "exo-2d-length-width")
    for _ in range(3):
        answer_once(client, sid)
    post = client.get(f"/api/sessions/{sid}/posterior").json()
    assert post["shape"] == [15, 6] and post["features"] == ["step_length", "step_width"]
    assert len(post["mean"]) == len(post["sd"]) == 90
    assert all(s > 0 for s in post["sd"])
    assert post["argmax"]["index"] == max(range(90), key=lambda k: post["mean"][k])
    trials = client.get(f"/api/sessions/{sid}/trials").json()
    assert [t["trial"] for t in trials] == [1, 2, 3]
    assert post["trials"] == [t["gait"]["index"] for t in trials]


def test_learned_says_whether_recommended_means_anything(client: TestClient) -> None:
    """Before a preference is learned ``recommended`` and ``argmax`` still name the flat prior's
    argmax, the first gait; ``learned`` false tells a client so, as the trial page's "No
    preference learned yet" does; one preference turns it true."""
    sid = new_session(client)

    def learned() -> bool:
        post = client.get(f"/api/sessions/{sid}/posterior").json()
        page = client.get(f"/sessions/{sid}").text
        assert ("No preference learned yet" in page) is (not post["learned"])
        if not post["learned"]:  # kept as it was, for the clients that read it
            assert post["recommended"]["index"] == post["argmax"]["index"] == 0
            assert post["confidence"] is None
        return bool(post["learned"])

    assert learned() is False
    answer_once(client, sid)  # the first trial: nothing to compare it with
    assert learned() is False
    answer_once(client, sid, "first")  # one preference
    assert learned() is True
    schema = client.get("/openapi.json").json()["components"]["schemas"]["PosteriorOut"]
    assert schema["properties"]["learned"]["type"] == "boolean"


def test_notes_exclusion_and_status(client: TestClient) -> None:
    sid = new_session(client)
    answer_once(client, sid)
    answer_once(client, sid)
    assert (
        client.post(f"/api/sessions/{sid}/notes", json={"text": "battery swapped"}).status_code
        == 200
    )
    assert client.post(f"/api/sessions/{sid}/notes", json={"text": ""}).status_code == 422
    r = client.post(
        f"/api/sessions/{sid}/trials/1/exclude", json={"reason": "stumble", "detail": "tripped"}
    )
    assert r.status_code == 200 and r.json()[0]["excluded"] == "stumble"
    events = event_count(client, sid)
    assert (
        client.post(f"/api/sessions/{sid}/trials/1/exclude", json={"reason": "stumble"}).status_code
        == 409
    )
    assert (
        client.post(f"/api/sessions/{sid}/trials/9/exclude", json={"reason": "stumble"}).status_code
        == 409
    )
    r = client.post(f"/api/sessions/{sid}/trials/2/exclude", json={"reason": "bored"})
    assert r.status_code == 422 and "reason" in loc_of(r)
    assert event_count(client, sid) == events
    assert (
        client.post(f"/api/sessions/{sid}/status", json={"status": "paused"}).json()["status"]
        == "paused"
    )
    r = client.get(f"/api/sessions/{sid}/query")
    assert r.status_code == 409 and "paused" in r.json()["detail"]
    assert client.post(f"/api/sessions/{sid}/status", json={"status": "active"}).status_code == 200
    assert client.post(f"/api/sessions/{sid}/status", json={"status": "done"}).status_code == 422
    assert (
        client.post(f"/api/sessions/{sid}/status", json={"status": "finished"}).status_code == 200
    )
    events = event_count(client, sid)
    r = client.post(f"/api/sessions/{sid}/answers", json={"query_id": 3})
    assert r.status_code == 409 and "finished" in r.json()["detail"]
    assert client.post(f"/api/sessions/{sid}/status", json={"status": "active"}).status_code == 409
    assert event_count(client, sid) == events


# -- validation and export ---------------------------------------------------------------------
def test_blind_validation_round_trip(client: TestClient) -> None:
    sid = new_session(client)
    r = client.post(f"/api/sessions/{sid}/validation")
    assert r.status_code == 409 and "flat" in r.json()["detail"]  # nothing learned yet
    for outcome in ("first", "first", "second", "first"):
        answer_once(client, sid, outcome)
    plan = client.post(f"/api/sessions/{sid}/validation").json()
    assert [g["label"] for g in plan["gaits"]] == ["A", "B", "C"] and plan["ranking"] is None
    assert client.post(f"/api/sessions/{sid}/validation").json() == plan  # the same open round
    r = client.get(f"/api/sessions/{sid}/query")
    assert r.status_code == 409 and "validation" in r.json()["detail"]
    events = event_count(client, sid)
    bad = client.post(
        f"/api/sessions/{sid}/validation/1/ranking", json={"ranking": ["A", "A", "B"]}
    )
    assert bad.status_code == 422 and "ranking" in loc_of(bad)
    assert (
        client.post(
            f"/api/sessions/{sid}/validation/2/ranking", json={"ranking": ["A", "B", "C"]}
        ).status_code
        == 409
    )
    assert event_count(client, sid) == events
    post = client.get(f"/api/sessions/{sid}/posterior").json()
    by_mean = sorted(plan["gaits"], key=lambda g: -post["mean"][g["gait"]["index"]])
    best_first = [g["label"] for g in by_mean]
    done = client.post(
        f"/api/sessions/{sid}/validation/1/ranking", json={"ranking": best_first}
    ).json()
    assert done["agrees"] is True and done["kendall_tau"] == 1.0
    assert done["model_ranking"] == best_first
    assert sorted(done["roles"].values()) == ["max", "mean", "min"]
    assert client.get(f"/api/sessions/{sid}/validation").json() == [done]
    assert client.get(f"/api/sessions/{sid}/query").status_code == 200


@pytest.mark.parametrize("fmt", ["csv", "json"])
def test_export_is_a_zip_of_the_session_folder(client: TestClient, fmt: str) -> None:
    sid = new_session(client)
    answer_once(client, sid)
    answer_once(client, sid)
    r = client.get(f"/api/sessions/{sid}/export", params={"format": fmt})
    assert r.status_code == 200 and r.headers["content-type"] == "application/zip"
    with zipfile.ZipFile(io.BytesIO(r.content)) as zf:
        names = {n.split("/", 1)[1] for n in zf.namelist()}
        manifest = json.loads(zf.read(f"session-{sid}/manifest.json"))
    assert {"manifest.json", "config.toml", "events.jsonl", f"trials.{fmt}"} <= names
    assert manifest["session"]["id"] == sid
    assert client.get(f"/api/sessions/{sid}/export", params={"format": "xml"}).status_code == 422


def test_the_openapi_schema_describes_the_api(client: TestClient) -> None:
    schema = client.get("/openapi.json").json()
    paths = schema["paths"]
    for path in (
        "/api/sessions",
        "/api/sessions/{session_id}/query",
        "/api/sessions/{session_id}/answers",
        "/api/sessions/{session_id}/undo",
        "/api/sessions/{session_id}/posterior",
    ):
        assert path in paths
    answer = schema["components"]["schemas"]["AnswerIn"]
    assert answer["additionalProperties"] is False and answer["required"] == ["query_id"]
    assert not any(p.startswith("/sessions") for p in paths)  # pages are not API


def test_sessions_beyond_the_kept_ones_are_reopened_from_the_log(
    db_url: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    from gaitpref.console import service

    monkeypatch.setattr(service, "KEEP", 1)
    c = TestClient(create_app(db_url))
    first, second = new_session(c), new_session(c)
    answer_once(c, first)
    answer_once(c, second)  # the first session is no longer kept open
    state = c.app.state.service  # type: ignore[attr-defined]
    assert list(state._open) == [second]
    q = c.get(f"/api/sessions/{first}/query").json()
    assert q["trials_done"] == 1 and q["buffer"][0]["trial"] == 1
    assert list(state._open) == [first]


def test_a_busy_session_is_409_for_posts_and_never_for_reads(
    client: TestClient, db_url: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    from gaitpref.storage import base, open_storage

    sid = new_session(client)
    q = client.get(f"/api/sessions/{sid}/query").json()
    monkeypatch.setattr(base, "WRITER_WAIT_S", 0.05)
    other = open_storage(db_url)  # another process's writer, holding the session's turn
    with other.writer_turn(sid):
        r = client.get(f"/api/sessions/{sid}/query")
        assert r.status_code == 503 and r.headers["retry-after"] == "1"
        assert f"session {sid}" in r.json()["detail"] and "busy" in r.json()["detail"]
        assert client.get(f"/sessions/{sid}").status_code == 503  # the trial page
        r = client.post(f"/api/sessions/{sid}/notes", json={"text": "hello"})
        assert r.status_code == 409 and "busy" in r.json()["detail"]
    other.close()
    assert client.get(f"/api/sessions/{sid}/query").json() == q
    assert client.post(f"/api/sessions/{sid}/notes", json={"text": "hello"}).status_code == 200


@pytest.mark.parametrize("config", ["exo-1d-step-length", "compass-continuous-3d"])
def test_a_fresh_session_reads_and_draws_before_any_answer(client: TestClient, config: str) -> None:
    """Nothing learnt yet (on the line path not even a point): every read is 200, never a
    refused-input 422 from an empty array."""
    sid = new_session(client, config)
    for path in ("figure.png", "posterior.png"):
        r = client.get(f"/sessions/{sid}/{path}")
        assert r.status_code == 200 and r.headers["content-type"] == "image/png", path
    post = client.get(f"/api/sessions/{sid}/posterior")
    assert post.status_code == 200, post.text
    body = post.json()
    assert body["confidence"] is None
    assert (body["argmax"] is None) == (body["mean"] == [])
    assert (body["mean"] == []) == (config == "compass-continuous-3d")  # the line path: no point
    export = client.get(f"/api/sessions/{sid}/export")
    assert export.status_code == 200, export.text


def test_a_422_keeps_its_field_when_the_input_is_not_json(client: TestClient) -> None:
    """FastAPI echoes the refused ``input``; an infinite number or a lone surrogate cannot be
    written as JSON, and the 422 lost its field (``loc`` was ``["body"]``)."""
    sid = new_session(client)
    headers = {"content-type": "application/json"}
    r = client.post(
        "/api/sessions",
        content='{"config": "exo-1d-step-length", "subject": "S01", "seed": 1e400}',
        headers=headers,
    )
    assert r.status_code == 422 and loc_of(r) == ["body", "seed"], r.text
    assert "input" not in r.json()["detail"][0]
    r = client.post(f"/api/sessions/{sid}/notes", content='{"text": "\\ud800"}', headers=headers)
    assert r.status_code == 422 and loc_of(r) == ["body", "text"], r.text
    blank = client.post(f"/api/sessions/{sid}/notes", json={"text": "   "})
    assert blank.status_code == 422 and loc_of(blank) == ["body", "text"]
    assert "empty" in blank.json()["detail"][0]["msg"]
    assert client.get(f"/api/sessions/{sid}").json()["trials"] == 0
    assert [e["kind"] for e in client.get(f"/api/sessions/{sid}/events").json()] == ["created"]


def test_a_triple_of_the_wrong_length_is_422_not_413(client: TestClient) -> None:
    sid = new_session(client)
    q = client.get(f"/api/sessions/{sid}/query").json()
    body = {"query_id": q["query_id"], "comparisons": [[0, 1, "first", "extra"]]}
    r = client.post(f"/api/sessions/{sid}/answers", json=body)
    assert r.status_code == 422 and loc_of(r) == ["body", "comparisons", 0], r.text
