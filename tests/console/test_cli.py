"""``gaitpref console``: the URL it prints, and the token it requires off the loopback interface."""

from __future__ import annotations

import re
import socket
from pathlib import Path
from typing import Any

import pytest
import uvicorn
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from gaitpref.cli import app
from gaitpref.cli import console as console_cli


@pytest.fixture
def served(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    """What ``uvicorn.run`` was asked to serve (nothing is served)."""
    seen: dict[str, Any] = {}

    def fake_run(application: Any, **kwargs: Any) -> None:
        seen["app"] = application
        seen.update(kwargs)

    monkeypatch.setattr(uvicorn, "run", fake_run)
    # nothing listens, so whether the port is free here is no matter (tested on its own below)
    monkeypatch.setattr(console_cli, "port_taken", lambda host, port: False)
    monkeypatch.delenv("GAITPREF_TOKEN", raising=False)
    return seen


def run(*args: str, env: dict[str, str] | None = None) -> str:
    result = CliRunner().invoke(app, ["console", *args], env=env)
    assert result.exit_code == 0, result.output
    return result.output


def test_loopback_needs_no_token(served: dict[str, Any], db_url: str) -> None:
    out = run("--db", db_url, "--port", "8123")
    assert "open http://127.0.0.1:8123/\n" in out and "?token" not in out
    assert served["host"] == "127.0.0.1" and served["port"] == 8123
    client = TestClient(served["app"], base_url="http://127.0.0.1:8123")
    assert client.get("/api/configs").status_code == 200
    # DNS rebinding: a loopback console answers only to loopback host names
    assert client.get("/api/configs", headers={"host": "evil.example"}).status_code == 400


def test_other_interfaces_get_a_generated_token(served: dict[str, Any], db_url: str) -> None:
    out = run("--db", db_url, "--host", "0.0.0.0")
    token = re.search(r"\?token=([A-Za-z0-9_-]+)", out)
    assert token is not None and len(token.group(1)) >= 32
    client = TestClient(served["app"])
    assert client.get("/api/configs").status_code == 401
    auth = {"authorization": f"Bearer {token.group(1)}"}
    assert client.get("/api/configs", headers=auth).status_code == 200


def test_a_given_token_from_the_option_or_the_environment(
    served: dict[str, Any], db_url: str
) -> None:
    out = run("--db", db_url, "--host", "10.0.0.5", "--token", "opt-token")
    assert "http://10.0.0.5:8000/?token=opt-token" in out
    out = run("--db", db_url, "--host", "10.0.0.5", env={"GAITPREF_TOKEN": "env-token"})
    assert "?token=env-token" in out
    client = TestClient(served["app"])
    assert client.get("/api/configs", headers={"x-gaitpref-token": "env-token"}).status_code == 200
    # a token given on the loopback interface is required too
    out = run("--db", db_url, "--token", "local")
    assert "?token=local" in out
    loopback = TestClient(served["app"], base_url="http://127.0.0.1:8000")
    assert loopback.get("/api/configs").status_code == 401


def test_a_file_given_as_the_libraries_folder_is_refused(
    served: dict[str, Any], db_url: str, tmp_path: Path
) -> None:
    """It was taken: the console served, and every upload then failed to make its folder."""
    file = tmp_path / "libs"
    file.write_text("not a folder", encoding="utf-8")
    result = CliRunner().invoke(app, ["console", "--db", db_url, "--libraries", str(file)])
    assert result.exit_code == 2, result.output
    assert "--libraries" in result.output and "is a file, not a folder" in result.output
    assert served == {}  # nothing served
    run("--db", db_url, "--libraries", str(tmp_path / "new-folder"))  # a new folder is fine


def test_a_new_database_is_said_to_be_new(served: dict[str, Any], tmp_path: Path) -> None:
    """A mistyped --db served an empty session list with nothing saying the file was new: the
    operator's sessions looked lost."""
    missing = tmp_path / "typo.db"
    out = run("--db", str(missing))
    assert missing.is_file()
    assert f"no database was at {str(missing)!r}: a new, empty one was made there" in out
    assert "check --db and $GAITPREF_DB" in out
    # the same file again, and a database given by URL that is there: nothing said
    assert "no database was at" not in run("--db", str(missing))
    assert "no database was at" not in run("--db", f"sqlite:///{missing}")


def test_a_port_in_use_is_refused_naming_it(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """Before, uvicorn printed its raw "[Errno 98] address already in use" and exited 3."""

    def must_not_run(application: Any, **kwargs: Any) -> None:
        raise AssertionError("served on a port in use")

    monkeypatch.setattr(uvicorn, "run", must_not_run)
    db = tmp_path / "console.db"
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as other:  # another program's server
        other.bind(("127.0.0.1", 0))
        other.listen()
        port = other.getsockname()[1]
        assert console_cli.port_taken("127.0.0.1", port)
        result = CliRunner().invoke(app, ["console", "--db", str(db), "--port", str(port)])
    assert result.exit_code == 2, result.output
    assert f"port {port} on 127.0.0.1 is already in use" in result.output
    assert "--port" in result.output and "Errno" not in result.output
    assert not db.exists()  # refused before the database is opened
    # closed: free again (an address not this machine's is left to uvicorn, not called taken)
    assert not console_cli.port_taken("127.0.0.1", port)
    assert not console_cli.port_taken("10.0.0.5", port)


def test_requests_are_not_logged_by_default(served: dict[str, Any], db_url: str) -> None:
    """uvicorn's access log (INFO) would write every request's address, the printed
    ``/?token=...`` among them: the console serves at WARNING, so it writes none (no address
    carries a subject code or a note; the token does)."""
    run("--db", db_url, "--host", "10.0.0.5", "--token", "opt-token")
    assert served["log_level"] == "warning"
