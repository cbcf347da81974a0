"""The SQL schema of a gaitpref database (SQLAlchemy Core), as the newest migration leaves it.

Three tables: ``subjects`` (pseudonymous codes), ``sessions`` (config as given and its hash, seed,
software version, status, times, the last event's sequence number) and ``events`` (one row per
event, keyed by ``(session_id, seq)``, append-only: triggers refuse updates and deletes).
Migrations in ``storage/migrations`` create exactly this; a test compares the two.
"""

from __future__ import annotations

from sqlalchemy import (
    JSON,
    BigInteger,
    CheckConstraint,
    Column,
    DateTime,
    ForeignKey,
    Integer,
    MetaData,
    String,
    Table,
    Text,
    text,
)

NAMING = {
    "ix": "ix_%(column_0_label)s",
    "uq": "uq_%(table_name)s_%(column_0_name)s",
    "ck": "ck_%(table_name)s_%(constraint_name)s",
    "fk": "fk_%(table_name)s_%(column_0_name)s_%(referred_table_name)s",
    "pk": "pk_%(table_name)s",
}

metadata = MetaData(naming_convention=NAMING)

subjects = Table(
    "subjects",
    metadata,
    Column("code", String(64), primary_key=True),
    Column("created_at", DateTime(timezone=True), nullable=False),
)

sessions = Table(
    "sessions",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("subject", String(64), ForeignKey("subjects.code"), nullable=False, index=True),
    Column("config_name", String(200), nullable=False),
    Column("config_text", Text, nullable=False),
    Column("config_sha256", String(64), nullable=False),
    Column("seed", BigInteger, nullable=False),
    Column("software_version", String(64), nullable=False),
    Column("status", String(16), nullable=False),
    Column("created_at", DateTime(timezone=True), nullable=False),
    Column("updated_at", DateTime(timezone=True), nullable=False),
    Column("last_seq", Integer, nullable=False),
    Column("meta", JSON, nullable=False),
    CheckConstraint("status IN ('active', 'paused', 'finished')", name="status"),
    CheckConstraint("last_seq >= 0", name="last_seq"),
)

events = Table(
    "events",
    metadata,
    Column("session_id", Integer, ForeignKey("sessions.id"), primary_key=True),
    Column("seq", Integer, primary_key=True),
    Column("kind", String(32), nullable=False),
    Column("payload", JSON, nullable=False),
    Column("at", DateTime(timezone=True), nullable=False),
    Column("version", Integer, nullable=False, server_default=text("1")),  # payload schema
    CheckConstraint("seq >= 1", name="seq"),
)
