"""A page's form past a limit gets the console's HTML error page saying what was too large.

Starlette's form parser refuses a field over 1 MiB, too many fields or files, and malformed
multipart data with an ``HTTPException(400)``, which reached the operator's browser as FastAPI's
bare ``{"detail": "Part exceeded maximum size of 1024KB."}``; a body over the console's own form
limit was a JSON 413.  Now the form limits are set in ``console/limits.py`` and a page answers
with the error page (413 or 400) naming the limit; the API still answers JSON.
"""

from __future__ import annotations

from collections.abc import Iterator

import httpx
import pytest
from fastapi.testclient import TestClient

from gaitpref.console import limits
from gaitpref.console.limits import MAX_FORM_BODY, MAX_FORM_FIELD, MAX_FORM_FIELDS, MAX_JSON_BODY
from tests.console.conftest import csrf_of, event_count, new_session


def _html_error(r: httpx.Response, status: int) -> str:
    """The console's error page, as ``status``; its text."""
    assert r.status_code == status, r.text
    assert r.headers["content-type"].startswith("text/html")
    assert 'id="error"' in r.text and "Nothing was written." in r.text
    return r.text


@pytest.mark.parametrize("multipart", [False, True])
def test_a_field_over_its_limit_is_an_html_413_saying_so(
    client: TestClient, multipart: bool
) -> None:
    sid = new_session(client)
    csrf = csrf_of(client.get(f"/sessions/{sid}").text)
    before = event_count(client, sid)
    files = {"extra": ("a.txt", b"x")} if multipart else None
    data = {"csrf_token": csrf, "text": "x" * (MAX_FORM_FIELD + 1)}
    r = client.post(f"/sessions/{sid}/note", data=data, files=files, follow_redirects=False)
    text = _html_error(r, 413)
    assert f"a field of the form is larger than {MAX_FORM_FIELD:,} bytes" in text
    assert "Form too large" in text and 'id="back-to-trial"' in text
    assert event_count(client, sid) == before


def test_too_many_fields_is_an_html_413_saying_so(client: TestClient) -> None:
    csrf = csrf_of(client.get("/").text)
    data = {f"k{i}": "v" for i in range(MAX_FORM_FIELDS)} | {"csrf_token": csrf, "subject": "S1"}
    r = client.post("/sessions", data=data, follow_redirects=False)
    assert f"more than {MAX_FORM_FIELDS:,} fields" in _html_error(r, 413)
    assert client.get("/api/sessions").json() == []


def test_malformed_multipart_is_an_html_400(client: TestClient) -> None:
    headers = {"content-type": "multipart/form-data; boundary=xyz"}
    r = client.post("/sessions", content=b"not a multipart body", headers=headers)
    text = _html_error(r, 400)
    assert "the form could not be read" in text and "Form not readable" in text


def test_a_form_body_over_its_limit_is_an_html_413(client: TestClient) -> None:
    """Declared: refused unread, by the body limit, before routing."""
    sid = new_session(client)
    headers = {
        "content-length": str(MAX_FORM_BODY + 1),
        "content-type": "application/x-www-form-urlencoded",
    }
    r = client.post(f"/sessions/{sid}/note", content=b"x", headers=headers)
    text = _html_error(r, 413)
    assert f"the form is larger than {MAX_FORM_BODY:,} bytes" in text
    assert f'href="/sessions/{sid}"' in text  # the link back to the trial
    assert event_count(client, sid) == 1


def test_a_chunked_form_body_cut_at_its_limit_is_an_html_413(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(limits, "MAX_FORM_BODY", 100_000)
    sid = new_session(client)
    csrf = csrf_of(client.get(f"/sessions/{sid}").text)
    before = event_count(client, sid)

    def chunks() -> Iterator[bytes]:  # no Content-Length: the server counts what arrives
        yield f"csrf_token={csrf}&text=".encode()
        for _ in range(10):
            yield b"x" * 64_000

    headers = {"content-type": "application/x-www-form-urlencoded"}
    r = client.post(f"/sessions/{sid}/note", content=chunks(), headers=headers)
    assert "the form is larger than 100,000 bytes" in _html_error(r, 413)
    assert event_count(client, sid) == before


def test_the_api_still_answers_json(client: TestClient) -> None:
    sid = new_session(client)
    body = b'{"text": "' + b"x" * MAX_JSON_BODY + b'"}'
    r = client.post(
        f"/api/sessions/{sid}/notes", content=body, headers={"content-type": "application/json"}
    )
    assert r.status_code == 413 and r.headers["content-type"] == "application/json"
    assert f"{MAX_JSON_BODY:,} bytes" in r.json()["detail"]


def test_a_config_text_past_200000_characters_is_refused_naming_config(
    client: TestClient,
) -> None:
    """A pasted config was parsed whatever its length (the form field's 1 MiB, the API's
    100,000 characters); both now take 200,000 characters, as an uploaded config file."""
    csrf = csrf_of(client.get("/").text)
    text = "# a long comment\n" * (limits.MAX_CONFIG_TEXT // 17 + 1)
    assert len(text) > limits.MAX_CONFIG_TEXT
    r = client.post("/sessions", data={"csrf_token": csrf, "subject": "S1", "config": text})
    page = _html_error(r, 422)
    assert "<code>config</code>" in page and "at most 200,000 are taken" in page
    api = client.post("/api/sessions", json={"config": text, "subject": "S1"})
    assert api.status_code == 422 and api.json()["detail"][0]["loc"] == ["body", "config"]
    assert "200000 characters" in api.json()["detail"][0]["msg"]
    ok = client.post("/api/sessions", json={"config": "# c\n" * 40_000, "subject": "S1"})
    assert ok.status_code == 422 and "at most" not in ok.text  # parsed: 160,000 characters pass
    assert client.get("/api/sessions").json() == []


def test_a_text_field_sent_as_a_file_is_refused_naming_it(client: TestClient) -> None:
    """A note sent as a file part was read as missing: "the note is empty"."""
    sid = new_session(client)
    csrf = csrf_of(client.get(f"/sessions/{sid}").text)
    before = event_count(client, sid)
    files = {"text": ("note.txt", b"the knee felt loose")}
    r = client.post(f"/sessions/{sid}/note", data={"csrf_token": csrf}, files=files)
    assert r.status_code == 422 and "<code>text</code>" in r.text, r.text
    assert "was sent as a file; this field is text" in r.text
    assert event_count(client, sid) == before
    as_text = {"text": (None, b"the knee felt loose")}  # a plain multipart field: taken
    r = client.post(f"/sessions/{sid}/note", data={"csrf_token": csrf}, files=as_text)
    assert r.status_code == 200 and event_count(client, sid) == before + 1
