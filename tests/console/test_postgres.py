"""The console on a PostgreSQL database: its pages and its start line never show the password
of the URL, and a terminal writing the same session beside it takes turns with it."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from gaitpref import Session
from gaitpref.cli import app
from gaitpref.cli import console as console_cli
from gaitpref.console import create_app
from tests.console.conftest import answer_once, event_count, new_session

pytestmark = pytest.mark.postgres

PASSWORD, ENCODED = "p@ss:w/rd% #", "p%40ss%3Aw%2Frd%25%20%23"


def _hidden(text: str) -> bool:
    return ENCODED not in text and "p%40ss" not in text and PASSWORD not in text


def test_the_console_on_postgres_shows_no_password(
    postgres_url: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The sessions page showed ``Database: postgresql+psycopg://user:PASSWORD@...`` and
    ``gaitpref console`` printed it on starting."""
    url = postgres_url.replace("gaitpref@", f"gaitpref:{ENCODED}@")  # the test server trusts
    with TestClient(create_app(url)) as client:
        sid = new_session(client)
        answer_once(client, sid)
        # the terminal (a Session of its own) writes the same session between two answers
        terminal = Session.open(url, sid)
        terminal.note("from the terminal")
        terminal.close()
        answer_once(client, sid)
        event_count_before = event_count(client, sid)
        page = client.get("/").text
        assert "Database: <code>postgresql+psycopg://gaitpref:***@" in page, page
        for path in ("/", f"/sessions/{sid}", f"/api/sessions/{sid}", "/api/sessions"):
            assert _hidden(client.get(path).text), path
    reopened = Session.open(url, sid)  # the log replays, both writers' events in it
    assert [text for _, text in reopened.notes()] == ["from the terminal"]
    kinds = [e.kind for e in reopened.events()]
    assert kinds[:event_count_before].count("comparison_answered") == 1, kinds
    reopened.close()

    seen: dict[str, Any] = {}
    monkeypatch.setattr("uvicorn.run", lambda application, **kw: seen.update(kw))
    monkeypatch.setattr(console_cli, "port_taken", lambda host, port: False)
    result = CliRunner().invoke(app, ["console", "--db", url, "--port", "8124"])
    assert result.exit_code == 0, result.output
    assert "gaitpref console on postgresql+psycopg://gaitpref:***@" in result.output
    assert _hidden(result.output), result.output
