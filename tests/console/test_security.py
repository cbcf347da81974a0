"""Access control: the token on every request, CSRF tokens on forms, the Host check."""

from __future__ import annotations

from html import unescape as html_unescape

import pytest
from fastapi.testclient import TestClient

from gaitpref.console import create_app
from gaitpref.console.security import CSRF_COOKIE, Csrf
from tests.console.conftest import csrf_of

TOKEN = "correct-horse-battery-staple"


@pytest.fixture
def guarded(db_url: str) -> TestClient:
    return TestClient(create_app(db_url, token=TOKEN), follow_redirects=False)


@pytest.mark.parametrize(
    "path", ["/", "/api/sessions", "/api/configs", "/static/console.css", "/openapi.json", "/docs"]
)
def test_every_request_without_the_token_is_refused(guarded: TestClient, path: str) -> None:
    r = guarded.get(path)
    assert r.status_code == 401
    assert "token" in r.json()["detail"]
    assert guarded.get(path, headers={"authorization": "Bearer nope"}).status_code == 401


def test_a_refused_request_writes_nothing(guarded: TestClient) -> None:
    body = {"config": "exo-1d-step-length", "subject": "S01"}
    assert guarded.post("/api/sessions", json=body).status_code == 401
    assert (
        guarded.post(
            "/api/sessions", json=body, headers={"x-gaitpref-token": TOKEN + "x"}
        ).status_code
        == 401
    )
    auth = {"authorization": f"Bearer {TOKEN}"}
    assert guarded.get("/api/sessions", headers=auth).json() == []
    assert guarded.post("/api/sessions", json=body, headers=auth).status_code == 201
    assert (
        guarded.post("/api/sessions", json=body, headers={"x-gaitpref-token": TOKEN}).status_code
        == 201
    )


def test_the_printed_url_sets_a_cookie_and_drops_the_token_from_the_address(
    guarded: TestClient,
) -> None:
    r = guarded.get("/sessions/3", params={"token": TOKEN, "x": "1"})
    assert r.status_code == 303
    assert r.headers["location"] == "/sessions/3?x=1"
    cookie = r.headers["set-cookie"]
    assert "gaitpref_token=" in cookie and "HttpOnly" in cookie and "SameSite=Strict" in cookie
    assert guarded.get("/").status_code == 200  # the client keeps the cookie
    assert TestClient(guarded.app).get("/", params={"token": "wrong"}).status_code == 401


def test_without_a_token_the_loopback_console_is_open(client: TestClient) -> None:
    assert client.get("/api/configs").status_code == 200


def test_foreign_host_headers_are_refused_when_hosts_are_listed(db_url: str) -> None:
    app = create_app(db_url, allowed_hosts=["127.0.0.1", "localhost", "::1"])
    c = TestClient(app, base_url="http://127.0.0.1:8000")
    assert c.get("/api/configs").status_code == 200
    assert c.get("/api/configs", headers={"host": "[::1]:8000"}).status_code == 200
    assert c.get("/api/configs", headers={"host": "localhost"}).status_code == 200
    r = c.get("/api/configs", headers={"host": "attacker.example:8000"})
    assert r.status_code == 400 and "attacker.example" in r.json()["detail"]


def test_csrf_tokens_are_signed_by_the_app() -> None:
    mine, other = Csrf(b"k" * 32), Csrf(b"z" * 32)
    token = mine.issue()
    assert mine.valid(token) and not other.valid(token)
    assert mine.check(token, token)
    assert not mine.check(token, mine.issue())
    assert not mine.check(None, token) and not mine.check(token, None)
    nonce = token.split(".")[0]
    assert not mine.valid(nonce) and not mine.valid(nonce + ".00") and not mine.valid("a.b.c")


def test_forms_without_a_valid_csrf_token_are_refused_and_write_nothing(client: TestClient) -> None:
    page = client.get("/")
    token = csrf_of(page.text)
    assert client.cookies.get(CSRF_COOKIE) == token
    form = {"subject": "S01", "config": "exo-1d-step-length"}
    r = client.post("/sessions", data=form, follow_redirects=False)
    assert r.status_code == 403 and "CSRF" in r.text
    forged = Csrf().issue()
    r = client.post("/sessions", data={**form, "csrf_token": forged}, follow_redirects=False)
    assert r.status_code == 403
    assert client.get("/api/sessions").json() == []
    r = client.post("/sessions", data={**form, "csrf_token": token}, follow_redirects=False)
    assert r.status_code == 303 and r.headers["location"] == "/sessions/1"


def test_pages_reuse_a_valid_csrf_cookie(client: TestClient) -> None:
    first = csrf_of(client.get("/").text)
    assert csrf_of(client.get("/").text) == first
    client.cookies.clear()
    client.cookies.set(CSRF_COOKIE, "forged.value", domain="testserver.local")
    renewed = csrf_of(client.get("/").text)
    assert renewed not in ("forged.value", first)
    assert client.cookies.get(CSRF_COOKIE) == renewed


def _redirect_of(path: str) -> tuple[int, str]:
    """Status and Location of the token middleware for a raw request path (no URL parsing:
    an HTTP client would read ``//evil.example/`` as a host)."""
    import asyncio

    from gaitpref.console.security import AccessMiddleware

    sent: list[dict[str, object]] = []

    async def app(scope: object, receive: object, send: object) -> None:
        raise AssertionError("the request reached the application")

    async def receive() -> dict[str, object]:
        return {"type": "http.request", "body": b""}

    async def send(message: dict[str, object]) -> None:
        sent.append(message)

    scope = {
        "type": "http",
        "method": "GET",
        "path": path,
        "root_path": "",
        "query_string": f"token={TOKEN}&page=2".encode(),
        "headers": [(b"host", b"testserver")],
    }
    asyncio.run(AccessMiddleware(app, TOKEN)(scope, receive, send))  # type: ignore[arg-type]
    start = sent[0]
    headers = dict(start["headers"])  # type: ignore[call-overload]
    return int(start["status"]), headers[b"location"].decode()  # type: ignore[call-overload]


@pytest.mark.parametrize(
    ("path", "expected"),
    [
        ("//evil.example/", "/evil.example/"),
        ("///evil.example/x", "/evil.example/x"),
        ("/\\evil.example/", "/evil.example/"),
        ("/\t/evil.example", "/%09/evil.example"),
        ("/sessions/3", "/sessions/3"),
    ],
)
def test_the_token_redirect_never_leaves_the_console(path: str, expected: str) -> None:
    assert _redirect_of(path) == (303, f"{expected}?page=2")


def test_the_token_redirect_over_http(guarded: TestClient) -> None:
    r = guarded.get("/sessions/3", params={"token": TOKEN, "page": "2"})
    assert r.status_code == 303 and r.headers["location"] == "/sessions/3?page=2"


BODYLESS = ["undo", "validation", "trials/1/unsafe/withdraw"]


@pytest.mark.parametrize("action", BODYLESS)
@pytest.mark.parametrize(
    "headers",
    [
        {"origin": "http://evil.example", "content-type": "text/plain"},
        {"origin": "http://testserver:8001"},  # another console or app on the same host
        {"origin": "null"},  # a sandboxed frame or a file:// page
        {"sec-fetch-site": "cross-site"},
    ],
)
def test_a_change_a_browser_says_is_cross_origin_is_refused(
    client: TestClient, action: str, headers: dict[str, str]
) -> None:
    """The body-less API posts are "simple" requests a foreign page could send without a CORS
    preflight: a foreign Origin (or Sec-Fetch-Site) refuses them before anything runs."""
    from tests.console.conftest import answer_once, event_count, new_session

    sid = new_session(client)
    answer_once(client, sid)
    client.post(f"/api/sessions/{sid}/trials/1/unsafe", json={"reason": "pain"})
    before = event_count(client, sid)
    r = client.post(f"/api/sessions/{sid}/{action}", content=b"", headers=headers)
    assert r.status_code == 403 and "cross-origin request refused" in r.json()["detail"]
    assert event_count(client, sid) == before
    assert client.get(f"/api/sessions/{sid}", headers=headers).status_code == 200  # reads are fine


@pytest.mark.parametrize(
    "headers",
    [
        {},  # scripts and command-line clients send no Origin
        {"origin": "http://testserver"},
        {"origin": "http://TestServer:80", "sec-fetch-site": "same-origin"},
        {"origin": "https://console.lab.example", "x-forwarded-host": "console.lab.example"},
    ],
)
def test_the_consoles_own_origin_and_clients_without_one_may_change(
    client: TestClient, headers: dict[str, str]
) -> None:
    from tests.console.conftest import answer_once, new_session

    sid = new_session(client)
    answer_once(client, sid)
    r = client.post(f"/api/sessions/{sid}/undo", headers=headers)
    assert r.status_code == 200, r.text


#: markup an operator might type (or paste) into a free-text field, one per field
TYPED = {
    "note": '<script>alert("note")</script>',
    "unsafe": '"><img src=x onerror=alert("unsafe")>',
    "detail": "<b onmouseover=alert('detail')>x</b>",
    "withdraw": "</textarea><svg onload=alert('withdraw')>",
}


def test_free_text_typed_at_the_bench_is_escaped_on_every_page(client: TestClient) -> None:
    """Notes, unsafe reasons, exclusion details and why a validation round was withdrawn are
    free text: every page shows them as text, never as markup (subject codes are letters,
    digits, '-', '_' and '.' only)."""
    from tests.console.conftest import answer_once, new_session

    sid = new_session(client)
    for _ in range(3):
        answer_once(client, sid)
    opened = client.post(f"/api/sessions/{sid}/validation")
    assert opened.is_success, opened.text
    round_ = opened.json()["round"]
    withdrawn = client.post(
        f"/api/sessions/{sid}/validation/{round_}/withdraw", json={"reason": TYPED["withdraw"]}
    )
    assert withdrawn.is_success, withdrawn.text
    assert client.post(f"/api/sessions/{sid}/notes", json={"text": TYPED["note"]}).is_success
    flagged = client.post(f"/api/sessions/{sid}/trials/1/unsafe", json={"reason": TYPED["unsafe"]})
    assert flagged.is_success, flagged.text
    excluded = client.post(
        f"/api/sessions/{sid}/trials/2/exclude", json={"reason": "other", "detail": TYPED["detail"]}
    )
    assert excluded.is_success, excluded.text
    pages = {
        path: client.get(path).text
        for path in ("/", f"/sessions/{sid}", f"/sessions/{sid}?trials=all")
    }
    for path, html in pages.items():
        for field, text in TYPED.items():
            assert text not in html, (path, field)
        for tag in ("<script>alert", "<img src=x", "<b onmouseover", "<svg onload"):
            assert tag not in html, (path, tag)
    shown = html_unescape("\n".join(pages.values()))  # the text the browser shows
    for field in ("note", "unsafe"):  # shown (an exclusion's detail and a round's reason: not)
        assert TYPED[field] in shown, field
