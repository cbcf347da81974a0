"""User text the console shows or draws: feature names, units, labels, notes and reasons.

Each test is a defect an operator hit: a unit ``$\\foo$`` made every figure of the session a
422 (matplotlib read it as mathtext), a feature named ``Schrittlänge`` could not be given a
suggestion, ...
"""

from __future__ import annotations

from importlib import resources

import pytest
from fastapi.testclient import TestClient

from tests.console.conftest import answer_once, csrf_of

EXO_1D = (resources.files("gaitpref.config") / "shipped" / "exo-1d-step-length.toml").read_text(
    encoding="utf-8"
)


def _session(client: TestClient, config: str) -> int:
    r = client.post("/api/sessions", json={"config": config, "subject": "S01"})
    assert r.status_code == 201, r.text
    return int(r.json()["id"])


@pytest.mark.parametrize("unit", ["$\\\\foo$", "$x", "$x$", "m$"])
def test_a_unit_with_dollar_signs_is_drawn_as_text(client: TestClient, unit: str) -> None:
    sid = _session(client, EXO_1D.replace('unit = "m"', f'unit = "{unit}"'))
    answer_once(client, sid)
    for figure in ("figure.png", "posterior.png"):
        r = client.get(f"/sessions/{sid}/{figure}")
        assert r.status_code == 200, r.text
        assert r.content.startswith(b"\x89PNG")


@pytest.mark.parametrize("name", ["Schrittlänge", "μ"])
def test_a_non_ascii_feature_takes_suggestions_and_downloads(client: TestClient, name: str) -> None:
    config = EXO_1D.replace("[space.step_length]", f'[space."{name}"]')
    sid = _session(client, config.replace("step_length =", f'"{name}" ='))
    page = client.get(f"/sessions/{sid}")
    assert page.status_code == 200
    query = client.get(f"/api/sessions/{sid}/query").json()
    data = {"csrf_token": csrf_of(page.text), "query_id": str(query["query_id"]), "confirmed": "1"}
    data |= {f"cmp-{i}-{j}": "first" for i, j in query["comparisons"]}
    data[f"sug-{query['actions'][0]['index']}-{name}"] = "+small"
    r = client.post(f"/sessions/{sid}/answer", data=data, follow_redirects=False)
    assert r.status_code == 303, r.text
    answers = [
        e
        for e in client.get(f"/api/sessions/{sid}/events").json()
        if e["kind"] == "suggestion_given"
    ]
    assert name in str(answers[-1])
    for path in ("figure.png", "posterior.png", "export.zip", "export.zip?format=json"):
        assert client.get(f"/sessions/{sid}/{path}").status_code == 200, path


@pytest.mark.parametrize(
    ("path", "field"),
    [("status", "status"), ("trials/1/exclude", "reason"), ("answer", "query_id")],
)
def test_a_refused_value_is_quoted_by_its_start_and_length(
    client: TestClient, path: str, field: str
) -> None:
    sid = _session(client, "exo-1d-step-length")
    csrf = csrf_of(client.get(f"/sessions/{sid}").text)
    data = {"csrf_token": csrf, "status": "active", "reason": "other", "query_id": "1"}
    data[field] = "x" * 500_000
    r = client.post(f"/sessions/{sid}/{path}", data=data, follow_redirects=False)
    assert r.status_code == 422, r.text
    assert "x" * 61 not in r.text
    assert "(500,000 characters)" in r.text and f"<code>{field}</code>" in r.text
    assert len(r.content) < 20_000


def test_a_long_field_name_is_not_echoed(client: TestClient) -> None:
    sid = _session(client, "exo-1d-step-length")
    csrf = csrf_of(client.get(f"/sessions/{sid}").text)
    query = client.get(f"/api/sessions/{sid}/query").json()
    data = {"csrf_token": csrf, "query_id": str(query["query_id"]), "y" * 100_000: "first"}
    r = client.post(f"/sessions/{sid}/answer", data=data, follow_redirects=False)
    assert r.status_code == 422 and "unknown field" in r.text
    assert "y" * 61 not in r.text


def test_a_rating_posted_to_an_unrated_session_says_it_is_not_rated(client: TestClient) -> None:
    sid = _session(client, "exo-1d-step-length")
    csrf = csrf_of(client.get(f"/sessions/{sid}").text)
    query = client.get(f"/api/sessions/{sid}/query").json()
    action = query["actions"][0]["index"]
    data = {"csrf_token": csrf, "query_id": str(query["query_id"]), f"rate-{action}": "2"}
    data |= {f"cmp-{i}-{j}": "first" for i, j in query["comparisons"]}
    for confirmed in ("", "1"):
        r = client.post(f"/sessions/{sid}/answer", data=data | {"confirmed": confirmed})
        assert r.status_code == 422, r.text
        assert "this session is not rated" in r.text and "[feedback.rating]" in r.text
        assert f"<code>rate-{action}</code>" in r.text
    assert client.get(f"/api/sessions/{sid}/trials").json() == []


CONTROL = ["a\x07b", "ring\x1b[31m", "nul\x00", "cr\rhere", "bidi\u202eevil"]


@pytest.mark.parametrize("text", CONTROL)
def test_control_characters_in_free_text_are_refused_naming_the_field(
    client: TestClient, text: str
) -> None:
    sid = _session(client, "exo-1d-step-length")
    answer_once(client, sid)
    csrf = csrf_of(client.get(f"/sessions/{sid}").text)
    before = client.get(f"/api/sessions/{sid}/events").json()
    query = client.get(f"/api/sessions/{sid}/query").json()
    answer = {"csrf_token": csrf, "query_id": str(query["query_id"])}
    answer |= {f"cmp-{i}-{j}": "first" for i, j in query["comparisons"]}
    posts = [  # the review steps (no "confirmed") first: refused there already
        ("answer", "note", answer | {"note": text}),
        ("answer", "note", answer | {"note": text, "confirmed": "1"}),
        ("trials/1/unsafe", "reason", {"csrf_token": csrf, "reason": text}),
        ("trials/1/unsafe", "reason", {"csrf_token": csrf, "reason": text, "confirmed": "1"}),
        ("note", "text", {"csrf_token": csrf, "text": text}),
        ("trials/1/exclude", "detail", {"csrf_token": csrf, "reason": "other", "detail": text}),
    ]
    for path, field, data in posts:
        r = client.post(f"/sessions/{sid}/{path}", data=data, follow_redirects=False)
        assert r.status_code == 422, (path, r.text)
        assert f"<code>{field}</code>" in r.text and "holds U+" in r.text, (path, r.text)
    compared = [[i, j, "first"] for i, j in query["comparisons"]]
    api = [
        ("notes", "text", {"text": text}),
        ("trials/1/unsafe", "reason", {"reason": text}),
        ("trials/1/exclude", "detail", {"reason": "other", "detail": text}),
        ("answers", "note", {"query_id": query["query_id"], "comparisons": compared, "note": text}),
    ]
    for path, field, body in api:
        r = client.post(f"/api/sessions/{sid}/{path}", json=body)
        assert r.status_code == 422, (path, r.text)
        assert r.json()["detail"][0]["loc"] == ["body", field], (path, r.text)
    assert client.get(f"/api/sessions/{sid}/events").json() == before


def test_tabs_and_newlines_pass_in_a_note(client: TestClient) -> None:
    sid = _session(client, "exo-1d-step-length")
    r = client.post(f"/api/sessions/{sid}/notes", json={"text": "two\tcolumns\nand a line"})
    assert r.status_code == 200, r.text


def test_a_redirect_naming_a_queries_trials_is_answered_up_to_64_of_them(
    client: TestClient,
) -> None:
    """The flash of the redirect after an answer names its trials (``?answered=1001,...``):
    cut at 200 characters, the page after an answer of 40 gaits from trial 1000 on was a 422;
    up to 64 trials (``[cospar] n`` is at most 64) are taken, more are refused naming it."""
    sid = _session(client, "exo-1d-step-length")
    many = ",".join(str(t) for t in range(10**16, 10**16 + 64))
    for name in ("answered", "undone"):
        assert client.get(f"/sessions/{sid}", params={name: many}).status_code == 200
        r = client.get(f"/sessions/{sid}", params={name: many + ",7"})
        assert r.status_code == 422 and "names 65 trials" in r.text, r.text
        assert f"<code>{name}</code>" in r.text
