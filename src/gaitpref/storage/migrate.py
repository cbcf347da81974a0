"""Schema versions: Alembic migrations shipped in the package, and the checks on open.

A gaitpref database carries Alembic's ``alembic_version`` table.  On open, :func:`check_schema`
accepts a database at the newest revision this gaitpref knows; an empty database is created
(when allowed); anything else raises :class:`~gaitpref.storage.base.SchemaError` that says what
to do (a revision this gaitpref does not know was written by a newer gaitpref; an older one needs
``gaitpref db upgrade``).

Creating or migrating the schema is done by one process at a time: on PostgreSQL the transaction
first takes the server's advisory lock :data:`SCHEMA_LOCK` (``pg_advisory_xact_lock``, let go at
commit or rollback), and only then reads the revision, so two ``gaitpref db upgrade`` (or first
``gaitpref session new``) at once on an empty database no longer both created the tables (the
second failed with ``duplicate key value violates unique constraint "pg_type_typname_nsp_index"``
or ``relation "alembic_version" already exists``): the second waits for the first to commit and
finds the schema made.  SQLite's ``BEGIN IMMEDIATE`` write transaction serialises them already.
Within one process Alembic's ``context`` and ``op`` are module globals, so its runs are
serialised by a thread lock too (two threads upgrading at once wired one's migrations to the
other's connection and hung).
"""

from __future__ import annotations

import threading
from functools import cache
from importlib import resources
from typing import TYPE_CHECKING

from sqlalchemy import Connection, inspect, text

from gaitpref.storage.base import SchemaError

if TYPE_CHECKING:  # alembic is imported when first needed: it costs a tenth of a second
    from alembic.config import Config
    from alembic.script import ScriptDirectory

_TABLES = {"subjects", "sessions", "events"}

#: PostgreSQL's advisory lock held while the schema is created or migrated: one 64-bit key,
#: "gaitpref" in ASCII (a key space apart from the two-key locks of the writers' turns)
SCHEMA_LOCK = 0x6761697470726566

#: Alembic's ``context``/``op`` proxies are module globals: one run in this process at a time
_ALEMBIC = threading.Lock()


def _config(connection: Connection | None = None) -> Config:
    from alembic.config import Config

    cfg = Config()
    cfg.set_main_option("script_location", str(resources.files("gaitpref.storage") / "migrations"))
    if connection is not None:
        cfg.attributes["connection"] = connection
    return cfg


@cache
def _script() -> ScriptDirectory:
    from alembic.script import ScriptDirectory

    return ScriptDirectory.from_config(_config())


def head_revision() -> str:
    """The newest schema revision this gaitpref writes."""
    head = _script().get_current_head()
    assert head is not None
    return head


def known_revisions() -> list[str]:
    """Every schema revision this gaitpref knows, oldest first."""
    return [s.revision for s in reversed(list(_script().walk_revisions()))]


def current_revision(connection: Connection) -> str | None:
    """The database's revision; ``None`` for a database without gaitpref's schema."""
    if "alembic_version" not in inspect(connection).get_table_names():
        return None
    rows = connection.execute(text("SELECT version_num FROM alembic_version")).scalars().all()
    if len(rows) != 1:
        raise SchemaError(f"alembic_version holds {len(rows)} rows; expected exactly one")
    return str(rows[0])


def lock_schema(connection: Connection) -> None:
    """On PostgreSQL, wait for (then hold, until the transaction ends) :data:`SCHEMA_LOCK`:
    the schema is read after another process's creation or migration committed."""
    if connection.dialect.name == "postgresql":
        connection.execute(text("SELECT pg_advisory_xact_lock(:key)"), {"key": SCHEMA_LOCK})


def _run_upgrade(connection: Connection, revision: str) -> None:
    from alembic import command

    with _ALEMBIC:
        command.upgrade(_config(connection), revision)


def upgrade(connection: Connection, revision: str = "head") -> None:
    """Migrate the database on ``connection`` (inside its transaction) to ``revision``."""
    lock_schema(connection)
    current = current_revision(connection)
    _check_known(current)
    if current is None:
        _check_empty(connection)
    _run_upgrade(connection, revision)


def check_schema(connection: Connection, where: str, create: bool) -> bool:
    """Check the schema on open; create it in an empty database if ``create``.

    Returns True when it created the schema.  With ``create`` it waits first for another
    process's creation or migration (:func:`lock_schema`).
    """
    if create:
        lock_schema(connection)
    current = current_revision(connection)
    if current is None:
        _check_empty(connection)
        if not create:
            raise SchemaError(
                f"{where} holds no gaitpref database; create one with "
                "`gaitpref db upgrade` or `gaitpref session new`"
            )
        _run_upgrade(connection, "head")
        return True
    _check_known(current)
    head = head_revision()
    if current != head:
        raise SchemaError(
            f"{where} is at schema revision {current}; this gaitpref writes {head}: back the "
            "database up, then run `gaitpref db upgrade`"
        )
    return False


def _check_known(current: str | None) -> None:
    if current is not None and current not in known_revisions():
        raise SchemaError(
            f"the database is at schema revision {current!r}, which this gaitpref does not know "
            f"(its newest is {head_revision()!r}): it was written by a newer gaitpref; use that "
            "version (or newer) to open it"
        )


def _check_empty(connection: Connection) -> None:
    tables = set(inspect(connection).get_table_names())
    if tables:
        ours = sorted(tables & _TABLES)
        what = f"gaitpref-like tables {ours}" if ours else f"{len(tables)} other tables"
        raise SchemaError(
            f"the database has {what} but no gaitpref schema version (alembic_version): it is "
            "not a gaitpref database; use an empty database or another file"
        )
