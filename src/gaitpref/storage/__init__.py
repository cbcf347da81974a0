"""Durable storage of experiment sessions: one interface, three backends.

- :class:`Storage` (``base.py``): the interface and its written contract.
- :class:`SQLStorage` (``sql.py``): SQLite (the default, ``sqlite:///gaitpref.db``) and
  PostgreSQL (``postgresql+psycopg://...``) through SQLAlchemy 2, with Alembic migrations.
- :class:`MemoryStorage` (``memory.py``): for tests and dry runs.

:func:`open_storage` takes a URL (or a storage, returned as is); :func:`resolve_url` picks the URL
from ``--db``, then ``$GAITPREF_DB``, then ``sqlite:///gaitpref.db`` in the working directory.
A bare path (no ``://``) means a SQLite file.
"""

from __future__ import annotations

import os

from sqlalchemy.engine import URL

from gaitpref.errors import StorageError
from gaitpref.storage.base import (
    STATUSES,
    ConflictError,
    EventRecord,
    NewEvent,
    SchemaError,
    SessionBusyError,
    SessionFinishedError,
    SessionNotFoundError,
    SessionRecord,
    SessionsCheck,
    SessionSpec,
    Status,
    Storage,
    StorageConnectError,
    StorageFailureError,
    SubjectRecord,
)
from gaitpref.storage.memory import MemoryStorage
from gaitpref.storage.sql import SQLStorage

DEFAULT_URL = "sqlite:///gaitpref.db"
ENV_VAR = "GAITPREF_DB"


def resolve_url(url: str | None = None) -> str:
    """The database URL to use: ``url``, else ``$GAITPREF_DB``, else ``sqlite:///gaitpref.db``."""
    chosen = url or os.environ.get(ENV_VAR) or DEFAULT_URL
    if "://" not in chosen:  # the file of that name: "?", "#" and "%" quoted, not read as a URL's
        chosen = URL.create("sqlite", database=chosen).render_as_string(hide_password=False)
    return chosen


def open_storage(target: str | Storage | None = None, *, create: bool = True) -> Storage:
    """A storage for ``target`` (a URL, a storage, or None for :func:`resolve_url`'s choice).

    ``create=False`` refuses to create a new database (for commands that only read).
    """
    if isinstance(target, Storage):
        return target
    url = resolve_url(target)
    if url == "memory://":
        return MemoryStorage()
    return SQLStorage(url, create=create)


__all__ = [
    "DEFAULT_URL",
    "ENV_VAR",
    "STATUSES",
    "ConflictError",
    "EventRecord",
    "MemoryStorage",
    "NewEvent",
    "SQLStorage",
    "SchemaError",
    "SessionBusyError",
    "SessionFinishedError",
    "SessionNotFoundError",
    "SessionRecord",
    "SessionSpec",
    "SessionsCheck",
    "Status",
    "Storage",
    "StorageConnectError",
    "StorageError",
    "StorageFailureError",
    "SubjectRecord",
    "open_storage",
    "resolve_url",
]
