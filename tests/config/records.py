"""A session's row as the database gives it back, for tests of how a stored config is read."""

from __future__ import annotations

import hashlib
from datetime import UTC, datetime

from gaitpref.storage.base import SessionRecord


def stored_record(text: str, meta: dict[str, object]) -> SessionRecord:
    """Session 1's row holding the config ``text`` (with its hash) and ``meta``."""
    now = datetime.now(UTC)
    return SessionRecord(
        id=1, subject="S01", config_name="bare", config_text=text,
        config_sha256=hashlib.sha256(text.encode()).hexdigest(), seed=0,
        software_version="0.1.0", status="active", created_at=now, updated_at=now, last_seq=1,
        meta=meta,
    )  # fmt: skip
