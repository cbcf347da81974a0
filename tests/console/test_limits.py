"""Request bodies and lists have documented maximums (413 beyond them), checked before parsing."""

from __future__ import annotations

import json
from collections.abc import Iterator

from fastapi.testclient import TestClient

from gaitpref.console.limits import (
    FEATURES_MOST,
    MAX_COMPARISONS,
    MAX_FORM_BODY,
    MAX_FORM_FIELDS,
    MAX_JSON_BODY,
    MAX_LIST,
    QUERY_MOST,
)
from tests.console.conftest import event_count, new_session


def test_a_body_over_the_limit_is_refused_before_it_is_parsed(client: TestClient) -> None:
    sid = new_session(client)
    q = client.get(f"/api/sessions/{sid}/query").json()
    huge = {"query_id": q["query_id"], "suggestions": [[0, "step_length", "+small"]] * 200_000}
    data = json.dumps(huge).encode()
    assert len(data) > MAX_JSON_BODY
    before = event_count(client, sid)
    r = client.post(
        f"/api/sessions/{sid}/answers", content=data, headers={"content-type": "application/json"}
    )
    assert r.status_code == 413
    assert f"{MAX_JSON_BODY:,} bytes" in r.json()["detail"]
    assert event_count(client, sid) == before


def test_a_chunked_body_without_length_is_cut_at_the_limit(client: TestClient) -> None:
    sid = new_session(client)

    def chunks() -> Iterator[bytes]:  # no Content-Length: the server counts what arrives
        yield b'{"text": "'
        for _ in range(100):
            yield b"x" * 64_000
        yield b'"}'

    r = client.post(
        f"/api/sessions/{sid}/notes", content=chunks(), headers={"content-type": "application/json"}
    )
    assert r.status_code == 413
    assert event_count(client, sid) == 1  # only session_created: no note


def test_a_declared_length_over_the_limit_is_refused_unread(client: TestClient) -> None:
    r = client.post(
        "/sessions",
        content=b"x" * 10,
        headers={"content-length": str(MAX_FORM_BODY + 1), "content-type": "text/plain"},
    )
    assert r.status_code == 413


def test_a_list_over_its_maximum_is_413_naming_the_field(client: TestClient) -> None:
    sid = new_session(client)
    q = client.get(f"/api/sessions/{sid}/query").json()
    body = {
        "query_id": q["query_id"],
        "comparisons": [[0, 1, "first"]] * (MAX_COMPARISONS + 1),
    }
    r = client.post(f"/api/sessions/{sid}/answers", json=body)
    assert r.status_code == 413
    assert r.json()["detail"].startswith(f"comparisons: at most {MAX_COMPARISONS} items")
    body = {"query_id": q["query_id"], "feedback": [{"kind": "rating"}] * (MAX_LIST + 1)}
    r = client.post(f"/api/sessions/{sid}/answers", json=body)
    assert r.status_code == 413
    assert r.json()["detail"].startswith(f"feedback: at most {MAX_LIST} items")
    ok = {"query_id": q["query_id"], "comparisons": [[i, j, "first"] for i, j in q["comparisons"]]}
    assert client.post(f"/api/sessions/{sid}/answers", json=ok).status_code == 200


def test_the_limits_are_documented() -> None:
    from pathlib import Path

    doc = (Path(__file__).parents[2] / "docs" / "console.md").read_text()
    assert "413" in doc and f"{MAX_LIST}" in doc and "1 MB" in doc


def test_a_content_length_that_is_not_a_number_is_a_400_saying_so(client: TestClient) -> None:
    """It was a 413 "larger than 1,000,000 bytes", which the body was not."""
    sid = new_session(client)
    before = event_count(client, sid)
    for value in ("abc", "12x", "-5", "1e3"):
        headers = {"content-type": "application/json", "content-length": value}
        r = client.post(f"/api/sessions/{sid}/notes", content=b'{"text": "x"}', headers=headers)
        assert r.status_code == 400, (value, r.text)
        assert r.json() == {"detail": "the Content-Length header is not a number of bytes"}
        form = {"content-type": "application/x-www-form-urlencoded", "content-length": value}
        r = client.post(f"/sessions/{sid}/note", content=b"text=x", headers=form)
        assert r.status_code == 400 and "Content-Length header is not a number" in r.text
        assert 'id="back-to-trial"' in r.text
    assert event_count(client, sid) == before


def test_the_answer_limits_hold_the_largest_query_a_config_may_have() -> None:
    """Every comparison, suggestion and rating of the largest query a config allows fits the
    JSON lists and the answer form (a config with ``n = 24`` had more pairs than the 256 items a
    list took, and one with 45 gaits more radio groups than the form's 1,000 fields)."""
    from gaitpref.config.schema import MAX_FEATURES, MAX_QUERY

    assert (QUERY_MOST, FEATURES_MOST) == (MAX_QUERY, MAX_FEATURES)
    n = b = MAX_QUERY
    assert n * (n - 1) // 2 + n * b == MAX_COMPARISONS
    assert MAX_COMPARISONS + n * MAX_FEATURES + n + 8 <= MAX_FORM_FIELDS


def test_an_answer_to_every_pair_of_a_large_query_is_taken(client: TestClient) -> None:
    config = """
[space.x]
min = 0.0
max = 1.0
num = 40
[space.y]
min = 0.0
max = 1.0
num = 40
[model]
lengthscale = 0.2
signal_variance = 1.0
noise = 0.05
[cospar]
n = 24
buffer = 0
strategy = "self-sparring"
"""
    r = client.post("/api/sessions", json={"config": config, "subject": "S01"})
    assert r.status_code == 201, r.text
    sid = r.json()["id"]
    q = client.get(f"/api/sessions/{sid}/query").json()
    pairs = [[i, j, "first"] for i, j in q["comparisons"]]
    assert len(pairs) > MAX_LIST  # 276 with 24 distinct gaits
    r = client.post(
        f"/api/sessions/{sid}/answers", json={"query_id": q["query_id"], "comparisons": pairs}
    )
    assert r.status_code == 200, r.text
