"""Each event records the schema version of its payload (``gaitpref.payloads``).

Events written before this revision (gaitpref 0.1.0) all have version 1 payloads: the column is
added with that default, and no stored event is changed.

Revision ID: 0002
Revises: 0001
Create Date: 2026-12-02
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0002"
down_revision = "0001"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.add_column(
        "events",
        sa.Column("version", sa.Integer(), nullable=False, server_default=sa.text("1")),
    )


def downgrade() -> None:
    op.drop_column("events", "version")
