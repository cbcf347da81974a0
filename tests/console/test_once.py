"""A double click without JavaScript posts a form twice: one session, one note, not two."""

from __future__ import annotations

import asyncio

from fastapi.testclient import TestClient

from gaitpref.console.once import OncePosts, new_token
from tests.console.conftest import event_count, new_session
from tests.console.htmlforms import forms_of


def test_a_create_form_posted_twice_creates_one_session(client: TestClient) -> None:
    form = forms_of(client.get("/").text)["create-form"]
    data = {**form.fields, "subject": "S01", "config": "exo-1d-step-length"}
    first = client.post("/sessions", data=data, follow_redirects=False)
    second = client.post("/sessions", data=data, follow_redirects=False)
    assert first.status_code == second.status_code == 303
    assert first.headers["location"] == second.headers["location"]
    assert len(client.get("/api/sessions").json()) == 1
    again = forms_of(client.get("/").text)["create-form"]  # a new page: a new form
    r = client.post("/sessions", data={**data, "once": again.fields["once"]})
    assert r.status_code == 200 and len(client.get("/api/sessions").json()) == 2


def test_a_note_form_posted_twice_writes_one_note(client: TestClient) -> None:
    sid = new_session(client)
    form = next(
        f for f in forms_of(client.get(f"/sessions/{sid}").text).values() if "note" in f.action
    )
    before = event_count(client, sid)
    for _ in range(2):
        r = client.post(form.action, data={**form.fields, "text": "knee"}, follow_redirects=False)
        assert r.status_code == 303
    assert event_count(client, sid) == before + 1


def test_a_refused_first_post_does_not_hold_its_token(client: TestClient) -> None:
    form = forms_of(client.get("/").text)["create-form"]
    bad = {**form.fields, "subject": "Jane Doe", "config": "exo-1d-step-length"}
    assert client.post("/sessions", data=bad).status_code == 422
    good = {**bad, "subject": "S01"}
    assert client.post("/sessions", data=good, follow_redirects=False).status_code == 303
    assert len(client.get("/api/sessions").json()) == 1


def test_a_foreign_token_is_refused_naming_it(client: TestClient) -> None:
    form = forms_of(client.get("/").text)["create-form"]
    data = {**form.fields, "subject": "S01", "config": "exo-1d-step-length", "once": "<x>"}
    r = client.post("/sessions", data=data)
    assert r.status_code == 422 and "<code>once</code>" in r.text
    assert client.get("/api/sessions").json() == []


def test_concurrent_posts_of_one_token_write_once_and_memory_is_bounded() -> None:
    posts = OncePosts(remembered=3)
    writes: list[int] = []

    async def post() -> str:
        await asyncio.sleep(0.01)
        writes.append(1)
        return f"/sessions/{len(writes)}"

    async def main() -> list[str]:
        token = new_token()
        return await asyncio.gather(*(posts.run(token, post) for _ in range(5)))

    assert asyncio.run(main()) == ["/sessions/1"] * 5 and writes == [1]

    async def many() -> None:
        for _ in range(10):
            await posts.run(new_token(), post)

    asyncio.run(many())
    assert len(posts) == 3


def test_a_failed_first_post_lets_a_waiting_second_run() -> None:
    posts = OncePosts()
    calls: list[str] = []

    async def post() -> str:
        calls.append("x")
        await asyncio.sleep(0.01)
        if len(calls) == 1:
            raise ValueError("refused")
        return "/sessions/1"

    async def main() -> tuple[str | BaseException, str | BaseException]:
        token = new_token()
        return await asyncio.gather(
            posts.run(token, post), posts.run(token, post), return_exceptions=True
        )

    first, second = asyncio.run(main())
    assert isinstance(first, ValueError) and second == "/sessions/1"
