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
