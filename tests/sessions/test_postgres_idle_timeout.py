"""A PostgreSQL server (or role) with a low ``idle_in_transaction_session_timeout``.

A writer's turn on PostgreSQL is an advisory lock held by a transaction of its own, idle while the
session computes (a refit, a replay of another writer's events).  A server that ends such
transactions after 1 s ended the turn mid-operation: a second writer took it, wrote first, and the
first writer's append then lost its compare-and-set ("another writer appended to it; reload it").
The turn's transaction now turns that timeout off for itself (``SET LOCAL``); every other
transaction keeps the server's setting.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest
from sqlalchemy import create_engine, text

from gaitpref import Session
from tests.sessions.sessionkit import CONFIG

pytestmark = pytest.mark.postgres

#: the server's timeout, and how long the first writer's operation stays inside its turn (longer)
TIMEOUT, SLOW_S = "1s", 2.5


def _set_timeout(url: str, setting: str = "idle_in_transaction_session_timeout") -> None:
    engine = create_engine(url, isolation_level="AUTOCOMMIT")
    try:
        with engine.connect() as conn:
            name = conn.execute(text("SELECT current_database()")).scalar_one()
            conn.execute(text(f'ALTER DATABASE "{name}" SET {setting} = {TIMEOUT!r}'))
    finally:
        engine.dispose()


def test_a_slow_operation_keeps_its_turn_past_the_servers_idle_timeout(
    postgres_url: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    _set_timeout(postgres_url)  # for the connections opened from now on
    a = Session.create(postgres_url, CONFIG, "S01", seed=4)
    b = Session.open(postgres_url, a.id)
    append = a.storage.append
    in_turn = threading.Event()

    def slow_append(*args: Any, **kwargs: Any) -> Any:
        in_turn.set()
        time.sleep(SLOW_S)  # inside a's turn, idle in its transaction past the server's timeout
        return append(*args, **kwargs)

    monkeypatch.setattr(a.storage, "append", slow_append)
    errors: list[BaseException] = []

    def second() -> None:
        in_turn.wait(timeout=60)
        try:
            b.note("second")
        except BaseException as exc:  # the outcome is the test's verdict
            errors.append(exc)

    other = threading.Thread(target=second)
    other.start()
    try:
        a.note("first")  # raised ConflictError: b had taken the turn and written first
    finally:
        other.join(timeout=60)
    assert not other.is_alive() and errors == []
    monkeypatch.undo()
    assert [n for _, n in Session.open(postgres_url, a.id).notes()] == ["first", "second"]
    q = a.next_query()  # an answer stores, once, on the same server
    a.answer(q.id, [], [])
    b.refresh()
    executed = [e for e in b.events() if e.kind == "trial_executed"]
    assert [e.payload["query"] for e in executed] == [q.id]
    a.close()
    b.close()
    Session.open(postgres_url, a.id).close()  # the log replays


def test_pooled_connections_the_server_closed_while_idle_are_replaced(postgres_url: str) -> None:
    """``idle_session_timeout`` (PostgreSQL 14+) closes the pool's idle connections: the next
    write opens a new one (``pool_pre_ping``) instead of failing."""
    engine = create_engine(postgres_url)
    try:
        with engine.connect() as conn:
            version = conn.execute(text("SHOW server_version_num")).scalar_one()
    finally:
        engine.dispose()
    if int(version) < 140000:
        pytest.skip("idle_session_timeout is PostgreSQL 14's")
    _set_timeout(postgres_url, "idle_session_timeout")
    a = Session.create(postgres_url, CONFIG, "S01", seed=5)
    time.sleep(SLOW_S)  # the pool's connections idle past the server's timeout
    a.note("after a pause")
    q = a.next_query()
    a.answer(q.id, [], [])
    a.close()
    again = Session.open(postgres_url, a.id)
    assert [n for _, n in again.notes()] == ["after a pause"] and len(again.trials()) == 1
    again.close()
