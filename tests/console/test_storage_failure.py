"""A database that fails while the console runs is a 503 naming the storage problem.

A SQLite disk I/O error, a locked or damaged file (SQLAlchemy's ``OperationalError`` /
``DatabaseError``) or a database file removed under the console were reported as "422 refused
by storage", as if the operator's input were at fault; now they are
:class:`~gaitpref.storage.StorageFailureError`, answered 503 with ``Retry-After`` and the
problem in words, and nothing is written.
"""

from __future__ import annotations

import os
import sqlite3
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import event

from gaitpref.console import create_app
from gaitpref.storage import SQLStorage, StorageFailureError
from tests.console.conftest import csrf_of, new_session


@pytest.fixture
def console(tmp_path: Path) -> Iterator[tuple[TestClient, Path]]:
    path = tmp_path / "lab.db"
    with TestClient(create_app(f"sqlite:///{path}")) as c:
        yield c, path


def test_a_removed_database_file_is_a_503_naming_it(console: tuple[TestClient, Path]) -> None:
    client, path = console
    sid = new_session(client)
    csrf = csrf_of(client.get(f"/sessions/{sid}").text)
    os.remove(path)
    r = client.get(f"/api/sessions/{sid}")
    assert r.status_code == 503, r.text
    assert "was deleted, moved or replaced" in r.json()["detail"]
    assert r.headers["retry-after"] == "1"
    page = client.get(f"/sessions/{sid}")
    assert page.status_code == 503 and "was deleted, moved or replaced" in page.text
    post = client.post(f"/sessions/{sid}/note", data={"csrf_token": csrf, "text": "x"})
    assert post.status_code == 503 and "Database failed" in post.text


def test_an_operational_error_is_a_503_naming_it(console: tuple[TestClient, Path]) -> None:
    client, _ = console
    sid = new_session(client)
    storage = client.app.state.service.storage  # type: ignore[attr-defined]
    assert isinstance(storage, SQLStorage)

    def fail(*_: Any) -> None:
        raise sqlite3.OperationalError("disk I/O error")

    event.listen(storage.engine, "before_cursor_execute", fail)
    try:
        r = client.get(f"/api/sessions/{sid}/trials")
        assert r.status_code == 503, r.text
        assert "disk I/O error" in r.json()["detail"]
        page = client.get(f"/sessions/{sid}")
        assert page.status_code == 503 and "disk I/O error" in page.text
        with pytest.raises(StorageFailureError, match="disk I/O error"):
            storage.get_session(sid)
    finally:
        event.remove(storage.engine, "before_cursor_execute", fail)
    assert client.get(f"/api/sessions/{sid}").status_code == 200


def test_an_answer_the_locked_database_refuses_says_nothing_was_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Another program holding the SQLite file's write lock past the busy timeout: the
    confirmed answer (form and API) is a 503 that names the lock and says nothing was written
    (the page said only 'database is locked', leaving the operator to guess whether the answer
    was saved); sent again once the lock is gone, it is saved once."""
    import gaitpref.storage.sql as sql

    monkeypatch.setattr(sql, "BUSY_TIMEOUT_S", 0.2)  # before the console opens the database
    path = tmp_path / "lab.db"
    with TestClient(create_app(f"sqlite:///{path}")) as client:
        _answer_under_a_lock(client, path)


def _answer_under_a_lock(client: TestClient, path: Path) -> None:
    sid = new_session(client)
    q = client.get(f"/api/sessions/{sid}/query").json()
    csrf = csrf_of(client.get(f"/sessions/{sid}").text)
    before = len(client.get(f"/api/sessions/{sid}/events").json())
    form = {"csrf_token": csrf, "query_id": str(q["query_id"]), "confirmed": "1"}
    body = {"query_id": q["query_id"], "comparisons": []}
    other = sqlite3.connect(path, isolation_level=None)
    try:
        other.execute("BEGIN EXCLUSIVE")
        page = client.post(f"/sessions/{sid}/answer", data=form)
        assert page.status_code == 503
        assert "database is locked; nothing was written" in page.text
        r = client.post(f"/api/sessions/{sid}/answers", json=body)
        assert r.status_code == 503 and r.headers["retry-after"] == "1"
        assert r.json()["detail"].endswith("database is locked; nothing was written")
        other.execute("ROLLBACK")
    finally:
        other.close()
    assert len(client.get(f"/api/sessions/{sid}/events").json()) == before
    r = client.post(f"/api/sessions/{sid}/answers", json=body)
    assert r.status_code == 200, r.text
    assert [t["trial"] for t in client.get(f"/api/sessions/{sid}/trials").json()] == [1]
