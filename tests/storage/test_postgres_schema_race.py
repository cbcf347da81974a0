"""Two processes creating one PostgreSQL database's schema at once: both end with the schema.

Before, the second ``gaitpref db upgrade`` (or first ``gaitpref session new``) on an empty
database read it empty while the first's creation was not yet committed, created the tables
too and failed, once the first committed, with ``duplicate key value violates unique
constraint "pg_type_typname_nsp_index"`` (or ``relation "alembic_version" already exists``).
Now each creation or migration first takes the server's advisory lock ``migrate.SCHEMA_LOCK``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from sqlalchemy import create_engine, text

import gaitpref
from gaitpref.storage import migrate, open_storage
from gaitpref.storage.sql import upgrade_database

pytestmark = pytest.mark.postgres

#: the most a bounded wait below waits (it ends as soon as what it waits for happens)
WAIT_S = 60.0


def _gaitpref(*args: str) -> subprocess.Popen[str]:
    """``gaitpref ARGS`` in a process of its own (this checkout's package)."""
    src = str(Path(gaitpref.__file__).resolve().parents[1])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([src, os.environ.get("PYTHONPATH", "")]))
    return subprocess.Popen(
        [sys.executable, "-m", "gaitpref", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
    )


def _waiting_on_a_lock(url: str, process: subprocess.Popen[str]) -> None:
    """Return once another connection to the database waits on a lock (bounded)."""
    engine = create_engine(url)
    try:
        deadline = time.monotonic() + WAIT_S
        with engine.connect() as conn:
            while time.monotonic() < deadline:
                if process.poll() is not None:
                    pytest.fail(f"it did not wait: {process.communicate()[0]}")
                waiting = conn.execute(
                    text(
                        "SELECT count(*) FROM pg_stat_activity WHERE datname = "
                        "current_database() AND wait_event_type = 'Lock'"
                    )
                ).scalar_one()
                conn.rollback()
                if waiting:
                    return
                time.sleep(0.05)
    finally:
        engine.dispose()
    process.kill()
    pytest.fail(f"the second process never waited on a lock in {WAIT_S} s")


@pytest.mark.parametrize(
    "command",
    [("db", "upgrade"), ("session", "new", "--config", "exo-1d-step-length", "--subject", "S01")],
    ids=["db upgrade", "session new"],
)
def test_a_second_creation_waits_for_the_first_and_finds_the_schema(
    postgres_url: str, command: tuple[str, ...]
) -> None:
    engine = create_engine(postgres_url)
    try:
        with engine.connect() as first:
            first.begin()
            migrate.upgrade(first)  # the first creation, not committed yet
            second = _gaitpref(*command, "--db", postgres_url)
            try:
                _waiting_on_a_lock(postgres_url, second)
            finally:
                first.commit()
            out = second.communicate(timeout=WAIT_S)[0]
        assert second.returncode == 0, out
        assert "duplicate key" not in out and "already exists" not in out, out
        with engine.connect() as conn:
            assert migrate.current_revision(conn) == migrate.head_revision()
    finally:
        engine.dispose()
    store = open_storage(postgres_url, create=False)
    try:
        assert len(store.list_sessions()) == (command[0] == "session")
    finally:
        store.close()


def test_a_second_migration_waits_for_the_first(postgres_url: str) -> None:
    """A database at the first revision migrated by two ``db upgrade`` at once: the second read
    the old revision, then failed adding the column the first had added."""
    engine = create_engine(postgres_url)
    try:
        with engine.begin() as conn:
            migrate.upgrade(conn, migrate.known_revisions()[0])
        with engine.connect() as first:
            first.begin()
            migrate.upgrade(first)  # the first migration, not committed yet
            second = _gaitpref("db", "upgrade", "--db", postgres_url)
            try:
                _waiting_on_a_lock(postgres_url, second)
            finally:
                first.commit()
            out = second.communicate(timeout=WAIT_S)[0]
        assert second.returncode == 0 and "already exists" not in out, out
        with engine.connect() as conn:
            assert migrate.current_revision(conn) == migrate.head_revision()
    finally:
        engine.dispose()


def test_two_threads_upgrading_one_empty_database_both_succeed(postgres_url: str) -> None:
    """Two threads (each its own engine) hung: Alembic's proxies are module globals, so one's
    migrations ran on the other's connection, which waited on the first's transaction."""
    barrier = threading.Barrier(2)
    outcomes: list[str] = []

    def go() -> None:
        barrier.wait()
        try:
            upgrade_database(postgres_url)
            outcomes.append("ok")
        except Exception as exc:  # the outcome is the test's verdict
            outcomes.append(f"{type(exc).__name__}: {exc}")

    threads = [threading.Thread(target=go, daemon=True) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=WAIT_S)
    assert not any(t.is_alive() for t in threads), "an upgrade hung"
    assert outcomes == ["ok", "ok"], outcomes
    store = open_storage(postgres_url, create=False)
    store.close()
