"""Alembic environment: migrations run on a connection that gaitpref hands over.

``gaitpref.storage.migrate.upgrade`` opens the connection (with gaitpref's SQLite settings and a
write transaction) and passes it in ``config.attributes["connection"]``.
"""

from __future__ import annotations

from alembic import context

from gaitpref.storage.schema import metadata

connection = context.config.attributes.get("connection")
if connection is None:
    raise RuntimeError("run gaitpref's migrations with `gaitpref db upgrade`")
context.configure(connection=connection, target_metadata=metadata, render_as_batch=True)
with context.begin_transaction():
    context.run_migrations()
