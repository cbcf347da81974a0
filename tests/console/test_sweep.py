"""A sweep for 500s and unbounded work: malformed requests to every route of the JSON API and
every form of the pages.

For each route a valid request is spoilt one field at a time (wrong types, missing, huge
numbers, NaN and infinities, long texts and lists, lone surrogates, other scripts' digits,
unknown fields), and its path one parameter at a time (negative, huge, unknown ids); Hypothesis
then sends arbitrary JSON and arbitrary form fields.  Every answer must be below 500, and a
refused one (4xx) must leave the database as it was.  Bounded work is checked by counting, not
timing: a body that never ends is cut after its limit's worth of chunks.

The schema-driven fuzzing of the JSON API is ``test_fuzz.py``; this sweep also covers the pages'
forms, which are not in the OpenAPI schema, and reaches each route's session code with the
pending query's own ids.
"""

from __future__ import annotations

import asyncio
import json
from collections import Counter
from collections.abc import Callable, Iterator, MutableMapping
from dataclasses import dataclass
from typing import Any

import httpx
import pytest
from fastapi import FastAPI
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gaitpref.console import create_app
from gaitpref.console.limits import MAX_FORM_BODY, MAX_FORM_FIELDS, MAX_JSON_BODY
from gaitpref.console.service import SessionService
from tests.console.conftest import csrf_of
from tests.console.test_ratings_safety import rated_config

#: what a field may be spoilt with (JSON values; a form field gets their text)
BAD: list[object] = [
    None,
    True,
    -1,
    0,
    2**63,
    -(2**63) - 1,
    10**400,
    1.5,
    float("nan"),
    float("inf"),
    float("-inf"),
    1e308,
    "",
    " ",
    "x" * 5000,
    "\ud800",  # a lone surrogate: not storable UTF-8
    "\x00",
    "\u0661",  # ARABIC-INDIC DIGIT ONE: a digit to str.isdigit, not an id
    "\u202e",
    "S01",
    [],
    [0] * 300,
    ["x"] * 300,
    {},
    {"a": 1},
    [[0, 1, "first"]],
]
#: what a form field may be spoilt with (strings only)
BAD_TEXT = [
    "",
    " ",
    "-1",
    "0",
    "1.5",
    "9" * 19,
    "9" * 5000,
    "\u0661",
    "\x00",
    "NaN",
    "inf",
    "1e9",
    "[" * 50_000,
    "{}",
    "x" * 100_000,
    "1," * 50_000,
    "<script>",
]
#: bodies that are not a JSON object of the route's fields
RAW = [
    b"",
    b"{",
    b"[]",
    b"1",
    b'"x"',
    b"null",
    b"NaN",
    b"-Infinity",
    b"[" * 100_000,
    b'{"a":' * 5000,
    b"9" * 5000,
    b"\xff\xfe",
    b'{"query_id": 1, "query_id": 2}',
]


@dataclass(frozen=True)
class Route:
    """A POST route: ``path`` with ``{sid}`` for its session, and a valid body made from the
    session's pending query (``None``: none) when the request is sent."""

    name: str
    path: str
    body: Callable[[dict[str, Any] | None], dict[str, Any]] | None


def _answer(q: dict[str, Any] | None) -> dict[str, Any]:
    q = q or {"query_id": 1, "actions": [{"index": 0}], "comparisons": []}
    a = q["actions"][0]["index"]
    return {
        "query_id": q["query_id"],
        "comparisons": [[*c, "first"] for c in q["comparisons"]],
        "suggestions": [[a, "step_length", "+small"]],
        "feedback": [{"kind": "rating", "action": a, "label": "okay"}],
        "note": "fine",
    }


API = [
    Route(
        "create",
        "/api/sessions",
        lambda q: {"config": "exo-1d-step-length", "subject": "S09", "seed": 3, "prior_from": [1]},
    ),
    Route("answers", "/api/sessions/{sid}/answers", _answer),
    Route("undo", "/api/sessions/{sid}/undo", lambda q: {"query_id": (q or {}).get("query_id")}),
    Route("notes", "/api/sessions/{sid}/notes", lambda q: {"text": "the strap slipped"}),
    Route(
        "exclude",
        "/api/sessions/{sid}/trials/1/exclude",
        lambda q: {"reason": "stumble", "detail": "tripped", "confirmed": "1"},
    ),
    Route("unsafe", "/api/sessions/{sid}/trials/2/unsafe", lambda q: {"reason": "knee"}),
    Route("withdraw", "/api/sessions/{sid}/trials/2/unsafe/withdraw", None),
    Route("status", "/api/sessions/{sid}/status", lambda q: {"status": "paused"}),
    Route("validation", "/api/sessions/{sid}/validation", None),
    Route(
        "ranking",
        "/api/sessions/{sid}/validation/1/ranking",
        lambda q: {"ranking": ["A", "B", "C"], "shown": ["G1", "G2", "G3"]},
    ),
    Route("ack", "/api/sessions/{sid}/query/{qid}/ack", None),
]

FORMS = [
    Route(
        "create",
        "/sessions",
        lambda q: {
            "subject": "S09",
            "config": "exo-1d-step-length",
            "seed": "3",
            "prior_from": "1",
        },
    ),
    Route("status", "/sessions/{sid}/status", lambda q: {"status": "paused", "back": "/"}),
    Route(
        "answers",
        "/sessions/{sid}/answer",
        lambda q: {
            "query_id": str((q or {}).get("query_id", 1)),
            "confirmed": "1",
            "note": "fine",
            **{f"cmp-{i}-{j}": "first" for i, j in (q or {}).get("comparisons", [])},
            **{f"rate-{g['index']}": "3" for g in (q or {}).get("actions", [])},
        },
    ),
    Route(
        "undo",
        "/sessions/{sid}/undo",
        lambda q: {"query_id": str((q or {}).get("query_id", 1)), "confirmed": "1"},
    ),
    Route("notes", "/sessions/{sid}/note", lambda q: {"text": "the strap slipped"}),
    Route(
        "exclude",
        "/sessions/{sid}/trials/1/exclude",
        lambda q: {"reason": "stumble", "detail": "tripped", "confirmed": "1"},
    ),
    Route(
        "unsafe", "/sessions/{sid}/trials/2/unsafe", lambda q: {"reason": "knee", "confirmed": "1"}
    ),
    Route("withdraw", "/sessions/{sid}/trials/2/unsafe/withdraw", lambda q: {"confirmed": "1"}),
    Route("validation", "/sessions/{sid}/validation", lambda q: {}),
    Route(
        "ranking",
        "/sessions/{sid}/validation/1",
        lambda q: {
            "rank1": "A",
            "rank2": "B",
            "rank3": "C",
            "shown": '["G1", "G2", "G3"]',
            "confirmed": "1",
        },
    ),
]

GETS = [
    "/api/sessions/{sid}",
    "/api/sessions/{sid}/query",
    "/api/sessions/{sid}/posterior",
    "/api/sessions/{sid}/trials",
    "/api/sessions/{sid}/events",
    "/api/sessions/{sid}/validation",
    "/sessions/{sid}",
    "/sessions/{sid}/validation",
]
BAD_IDS = ["0", "-1", str(2**63), "9" * 5000, "abc", "\u0661", "999", "1.5", "%00", "1e3"]


@dataclass
class Console:
    client: TestClient
    service: SessionService
    sid: dict[str, int]  # each route's own session (a status change must not stop the others)
    csrf: str
    statuses: Counter[tuple[str, int]]  # (route, status) of every request sent

    def snapshot(self) -> list[tuple[int, int, str]]:
        return [(r.id, r.last_seq, r.status) for r in self.service.storage.list_sessions()]

    def pending(self, name: str) -> dict[str, Any] | None:
        r = self.client.get(f"/api/sessions/{self.sid[name]}/query")
        return dict(r.json()) if r.status_code == 200 else None

    def restore(self, name: str) -> None:
        """Undo what a request that was taken did to its route's session, so that the next one
        meets the same state (an answer undone, a pause resumed)."""
        sid = self.sid[name]
        if name in ("answers", "answers-form"):
            self.client.post(f"/api/sessions/{sid}/undo", json={})
        if self.client.get(f"/api/sessions/{sid}").json()["status"] == "paused":
            self.client.post(f"/api/sessions/{sid}/status", json={"status": "active"})


@pytest.fixture(scope="module")
def console(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Console]:
    app = create_app(f"sqlite:///{tmp_path_factory.mktemp('sweep') / 'sweep.db'}")
    service: SessionService = app.state.service
    names = [r.name for r in API if r.name != "create"]
    names += [f"{r.name}-form" for r in FORMS if r.name != "create"] + ["lines"]
    sid: dict[str, int] = {}
    for name in names:
        config = rated_config()
        if name == "lines":  # a line session over discrete features, its grid never made
            config = (
                "[model]\nlengthscale = 0.2\nsignal_variance = 0.005\nnoise = 0.02\n"
                "[space.step_length]\nmin = 0\nmax = 1\nnum = 2000\n"
                "[space.step_width]\nmin = 0\nmax = 1\nnum = 2000\n"
            )
        session = service.create(config, "S01")
        for _ in range(3):
            q = session.next_query()
            session.answer(q.id, [(q.actions[0], b, "first") for b in q.buffer], [])
        if name.startswith("ranking"):
            session.start_validation()
        else:
            session.next_query()
        sid[name] = session.id
    with TestClient(app) as client:
        console = Console(client, service, sid, csrf_of(client.get("/").text), Counter())
        yield console
    # the sweep reached the sessions: each route's spoilt requests were refused in their own
    # words, and its valid ones (and some spoilt ones: an unknown gait's rating is no error)
    # were taken
    seen = console.statuses
    for route in API + FORMS:
        if route.body is not None:
            assert seen[route.path, 422] > 0, (route.path, seen)
    assert sum(n for (path, status), n in seen.items() if status in (200, 201, 303)) > 50, seen


def _check(
    console: Console, route: Route, response: httpx.Response, before: list[Any], what: str
) -> None:
    console.statuses[route.path, response.status_code] += 1
    assert response.status_code < 500, (what, response.status_code, response.text[:500])
    if response.status_code >= 400:
        assert console.snapshot() == before, f"{what}: refused ({response.status_code}) but wrote"
        if response.status_code == 422 and response.headers["content-type"].startswith(
            "application/json"
        ):
            detail = response.json()["detail"]
            assert isinstance(detail, list) and all(d["loc"] and d["msg"] for d in detail), what


def _post_json(console: Console, route: Route, body: object, raw: bytes | None = None) -> None:
    sid = console.sid.get(route.name, 1)
    q = console.pending(route.name) if route.name in console.sid else None
    path = route.path.format(sid=sid, qid=(q or {}).get("query_id", 1))
    data = raw if raw is not None else json.dumps(body).encode("utf-8", "surrogatepass")
    before = console.snapshot()
    r = console.client.post(path, content=data, headers={"content-type": "application/json"})
    _check(console, route, r, before, f"POST {path} {data[:200]!r}")
    if r.status_code < 400 and route.name in console.sid:
        console.restore(route.name)


def _spoilt(body: dict[str, Any]) -> Iterator[dict[str, Any]]:
    """``body`` with one field, or one item of a list field, spoilt; each field left out; an
    unknown field added."""
    for key, value in body.items():
        for bad in BAD:
            yield {**body, key: bad}
        yield {k: v for k, v in body.items() if k != key}
        if isinstance(value, list) and value and isinstance(value[0], list):
            for i in range(len(value[0])):
                for bad in BAD:
                    yield {**body, key: [[*value[0][:i], bad, *value[0][i + 1 :]]]}
        if isinstance(value, list) and value and isinstance(value[0], dict):
            for field in value[0]:
                for bad in BAD:
                    yield {**body, key: [{**value[0], field: bad}]}
    yield {**body, "unknown": 1}


@pytest.mark.parametrize("route", API, ids=[r.name for r in API])
def test_spoilt_json_bodies_are_refused_not_500_and_write_nothing(
    console: Console, route: Route
) -> None:
    for raw in RAW:
        _post_json(console, route, None, raw)
    if route.body is None:
        for bad in BAD[:12]:
            _post_json(console, route, bad)
        return
    q = console.pending(route.name) if route.name in console.sid else None
    for body in _spoilt(route.body(q)):
        if route.name == "answers" and "query_id" in body and isinstance(body["query_id"], int):
            pending = console.pending(route.name)
            if pending is not None and body["query_id"] == (q or {}).get("query_id"):
                body = {**body, "query_id": pending["query_id"]}  # reach the session's checks
        _post_json(console, route, body)


def _post_form(console: Console, route: Route, fields: dict[str, str]) -> None:
    name = f"{route.name}-form"
    path = route.path.format(sid=console.sid.get(name, 1))
    before = console.snapshot()
    data = {"csrf_token": console.csrf, **fields}
    r = console.client.post(path, data=data, follow_redirects=False)
    _check(console, route, r, before, f"POST {path} {str(fields)[:300]}")
    if r.status_code == 303 and name in console.sid:
        console.restore(name)


@pytest.mark.parametrize("route", FORMS, ids=[r.name for r in FORMS])
def test_spoilt_forms_are_refused_not_500_and_write_nothing(console: Console, route: Route) -> None:
    assert route.body is not None
    name = f"{route.name}-form"
    make = route.body

    def valid() -> dict[str, Any]:
        return make(console.pending(name) if name in console.sid else None)

    for key in valid():
        for bad in BAD_TEXT:
            _post_form(console, route, {**valid(), key: bad})
        _post_form(console, route, {k: v for k, v in valid().items() if k != key})
    for extra in (
        {"cmp-9999999999-0": "first"},
        {"cmp-0-1": "sideways"},
        {"sug-9999999999-step_length": "+small"},
        {"sug-0-no_such_feature": "+small"},
        {"rate-9999999999": "1"},
        {"rate-0": "999"},
        {"unknown": "x"},
        {f"f{i}": "v" for i in range(MAX_FORM_FIELDS + 1)},  # past the form parser's limit
    ):
        _post_form(console, route, {**valid(), **extra})
    path = route.path.format(sid=console.sid.get(name, 1))
    for content, kind in (
        (f"csrf_token={console.csrf}&a=1&a=2".encode(), "application/x-www-form-urlencoded"),
        (b"\xff\xfe=\xff", "application/x-www-form-urlencoded"),
        (b"--x\r\n", "multipart/form-data; boundary=x"),
        (b"{}", "application/json"),
    ):
        before = console.snapshot()
        r = console.client.post(path, content=content, headers={"content-type": kind})
        _check(console, route, r, before, f"POST {path} {content[:80]!r}")


@pytest.mark.parametrize("template", GETS)
def test_reads_of_any_id_and_of_every_kind_of_session_are_not_500(
    console: Console, template: str
) -> None:
    for bad in BAD_IDS:
        r = console.client.get(template.format(sid=bad))
        assert r.status_code in (404, 422), (template, bad, r.status_code)
    for name, sid in console.sid.items():
        r = console.client.get(template.format(sid=sid))
        assert r.status_code < 500, (template, name, r.text[:500])


def test_posts_to_any_id_are_refused_and_write_nothing(console: Console) -> None:
    for route in API[1:] + FORMS[1:]:
        for bad in BAD_IDS:
            path = route.path.format(sid=bad, qid=bad)
            before = console.snapshot()
            r = console.client.post(path, json={}, headers={"content-type": "application/json"})
            assert r.status_code in (403, 404, 405, 422), (path, r.status_code)
            assert console.snapshot() == before
    for query in (
        "?answered=" + "1," * 5000,
        "?undone=9999999999999999999999",
        "?flagged=-1",
        "?replaced=2",
        "?withdrawn=" + "9" * 100,
    ):
        r = console.client.get(f"/sessions/{console.sid['answers']}{query}")
        assert r.status_code in (200, 422), query
    for fmt in ("xml", "x" * 10_000, "%00"):
        r = console.client.get(f"/api/sessions/{console.sid['answers']}/export?format={fmt}")
        assert r.status_code == 422


def _endless(app: FastAPI, path: str, first: bytes, chunk: bytes, kind: str) -> tuple[int, int]:
    """POST ``path`` a body that never ends (``first``, then ``chunk`` again and again, with no
    length declared), straight to the ASGI app; returns the status and the bytes it read."""
    read = 0
    sent: list[MutableMapping[str, Any]] = []

    async def receive() -> dict[str, Any]:
        nonlocal read
        body = first if read == 0 else chunk
        read += len(body)
        return {"type": "http.request", "body": body, "more_body": True}

    async def send(message: MutableMapping[str, Any]) -> None:
        sent.append(message)

    scope = {
        "type": "http",
        "asgi": {"version": "3.0"},
        "http_version": "1.1",
        "method": "POST",
        "scheme": "http",
        "path": path,
        "raw_path": path.encode(),
        "query_string": b"",
        "root_path": "",
        "headers": [(b"host", b"testserver"), (b"content-type", kind.encode())],
        "client": ("127.0.0.1", 1),
        "server": ("testserver", 80),
    }
    asyncio.run(app(scope, receive, send))
    return int(sent[0]["status"]), read


def test_a_billion_item_list_is_refused_by_size_before_it_is_parsed(console: Console) -> None:
    """A body of a billion comparisons (or a form of endless fields) is cut when it passes its
    limit: what the console reads is bounded by the limit, whatever the client sends."""
    app = console.client.app
    assert isinstance(app, FastAPI)
    triple = b'[0, 1, "first"],' * 4000
    status, read = _endless(
        app,
        f"/api/sessions/{console.sid['answers']}/answers",
        b'{"query_id": 1, "comparisons": [',
        triple,
        "application/json",
    )
    assert status == 413 and read <= MAX_JSON_BODY + len(triple)
    note = b"x" * 1_000_000
    status, read = _endless(
        app,
        f"/sessions/{console.sid['notes']}/note",
        f"csrf_token={console.csrf}&text=".encode(),
        note,
        "application/x-www-form-urlencoded",
    )
    assert status in (400, 413) and read <= MAX_FORM_BODY + len(note)


JSON_VALUES = st.recursive(
    st.one_of(
        st.none(),
        st.booleans(),
        st.integers(min_value=-(2**70), max_value=2**70),
        st.floats(allow_nan=True, allow_infinity=True),
        st.text(max_size=30),
        st.sampled_from(["first", "second", "none", "+small", "-big", "step_length", "rating"]),
        st.sampled_from(["okay", "A", "B", "C", "S01", "paused", "active", "stumble"]),
    ),
    lambda inner: st.one_of(
        st.lists(inner, max_size=5),
        st.dictionaries(
            st.sampled_from(
                [
                    "query_id",
                    "comparisons",
                    "suggestions",
                    "feedback",
                    "note",
                    "kind",
                    "action",
                    "label",
                    "text",
                    "reason",
                    "detail",
                    "status",
                    "ranking",
                    "shown",
                    "config",
                    "subject",
                    "seed",
                    "prior_from",
                    "unknown",
                ]
            ),
            inner,
            max_size=6,
        ),
    ),
    max_leaves=15,
)


#: The fuzz tests' examples: many, the same every run (derandomized, no example database)
FUZZ = settings(
    max_examples=300,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=list(HealthCheck),
)


@FUZZ
@given(route=st.sampled_from(API), body=JSON_VALUES, pending=st.booleans())
def test_any_json_to_any_api_route_is_not_500(
    console: Console, route: Route, body: object, pending: bool
) -> None:
    if pending and isinstance(body, dict) and "query_id" in body and route.name in console.sid:
        q = console.pending(route.name)
        body = {**body, "query_id": (q or {}).get("query_id", 1)}
    _post_json(console, route, body)


FIELD_NAMES = st.one_of(
    st.sampled_from(
        [
            "query_id",
            "confirmed",
            "note",
            "text",
            "reason",
            "detail",
            "status",
            "back",
            "subject",
            "config",
            "seed",
            "prior_from",
            "rank1",
            "rank2",
            "rank3",
            "shown",
            "cmp-0-1",
            "sug-0-step_length",
            "rate-0",
        ]
    ),
    st.from_regex(
        r"(cmp-\d{1,12}-\d{1,12}|sug-\d{1,12}-[a-z_]{1,12}|rate-\d{1,12})", fullmatch=True
    ),
    st.text(max_size=20),
)


@FUZZ
@given(
    route=st.sampled_from(FORMS),
    fields=st.dictionaries(FIELD_NAMES, st.one_of(st.text(max_size=40), st.sampled_from(BAD_TEXT))),
)
def test_any_form_to_any_page_route_is_not_500(
    console: Console, route: Route, fields: dict[str, str]
) -> None:
    fields = {k: v for k, v in fields.items() if k != "csrf_token"}
    _post_form(console, route, fields)
