"""Fixtures for console tests: an application over a temporary SQLite database, and for the
browser tests a Chromium (module-scoped) and a console served on loopback."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from gaitpref.console import create_app
from tests.console.live import HOW_TO_ENABLE, chromium_path, launch_chromium, serve
from tests.sessions.gaitkit import fresh_fake_steps


@pytest.fixture
def db_url(tmp_path: Path) -> str:
    return f"sqlite:///{tmp_path / 'console.db'}"


@pytest.fixture
def client(db_url: str) -> Iterator[TestClient]:
    with TestClient(create_app(db_url)) as c:
        yield c


def keys_ready(page: Any) -> None:
    """Waits (bounded) for a freshly loaded page to take its shortcut keys: until they have
    rested a moment after the load, Enter and the letter and digit keys do nothing."""
    page.wait_for_selector("html[data-keys=ready]", state="attached")


@pytest.fixture(scope="module")
def chromium() -> Iterator[Any]:
    """Debian's Chromium through Playwright (skips, or fails under CI=true, without it)."""
    if chromium_path() is None:
        pytest.skip(f"no Chromium on this machine: {HOW_TO_ENABLE}")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = launch_chromium(p)
        yield browser
        browser.close()


@pytest.fixture
def live(tmp_path: Path) -> Iterator[str]:
    """A console on loopback over its own SQLite file; yields its base URL."""
    with serve(create_app(f"sqlite:///{tmp_path / 'live.db'}")) as url:
        yield url


def new_session(client: TestClient, config: str = "exo-1d-step-length", **extra: Any) -> int:
    r = client.post("/api/sessions", json={"config": config, "subject": "S01", **extra})
    assert r.status_code == 201, r.text
    return int(r.json()["id"])


def answer_once(client: TestClient, sid: int, outcome: str = "first") -> dict[str, Any]:
    """Answer the pending query: every asked comparison with ``outcome``, no suggestions."""
    q = client.get(f"/api/sessions/{sid}/query").json()
    body = {
        "query_id": q["query_id"],
        "comparisons": [[i, j, outcome] for i, j in q["comparisons"]],
    }
    r = client.post(f"/api/sessions/{sid}/answers", json=body)
    assert r.status_code == 200, r.text
    return dict(r.json())


def event_count(client: TestClient, sid: int) -> int:
    return len(client.get(f"/api/sessions/{sid}/events").json())


def csrf_of(html: str) -> str:
    m = re.search(r'name="csrf_token" value="([^"]+)"', html)
    assert m, "the page carries no CSRF token"
    return m.group(1)


@pytest.fixture(autouse=True)
def _fresh_fake_steps() -> Iterator[None]:
    """Every test starts with the fake gait generator as :mod:`tests.sessions.gaitkit` makes it."""
    yield from fresh_fake_steps()
