"""A bare config learns (issue 11 item 5), and sessions that relied on 0.1's defaults replay."""

from __future__ import annotations

from datetime import UTC, datetime

import numpy as np
import pytest

from gaitpref import ConfigError
from gaitpref.config import parse_config
from gaitpref.sessions.stored_config import config_of, library_meta
from gaitpref.storage.base import SessionRecord

BARE = """
[space.step_length]
min = 0.08
max = 0.18
num = 15

[model]
lengthscale = 0.03
signal_variance = 0.005
noise = 0.02
"""


def test_a_config_with_only_space_and_model_asks_comparisons() -> None:
    loop = parse_config(BARE).make_loop()
    objective = -((np.linspace(0.08, 0.18, 15) - 0.15) ** 2)
    asked = 0
    for _ in range(8):
        q = loop.ask()
        if q.buffer:
            asked += 1
            a, b = q.actions[0], q.buffer[0]
            if a != b:
                loop.tell(q, [(a, b, "first" if objective[a] > objective[b] else "second")])
                continue
        loop.tell(q)
    assert asked == 7  # every query after the first compares with the trial before
    assert len(loop.preferences) >= 1
    assert not np.allclose(loop.posterior.mean, 0.0)  # it learnt from comparisons alone


def test_the_0_1_defaults_give_the_old_loop() -> None:
    assert parse_config(BARE, defaults="0.1").buffer == 0
    assert parse_config(BARE + "[cospar]\nbuffer = 1\n", defaults="0.1").buffer == 1
    with pytest.raises(ConfigError, match=r"unknown config defaults version '9\.9'"):
        parse_config(BARE, defaults="9.9")


def _record(text: str, meta: dict[str, object]) -> SessionRecord:
    import hashlib

    now = datetime.now(UTC)
    return SessionRecord(
        id=1, subject="S01", config_name="bare", config_text=text,
        config_sha256=hashlib.sha256(text.encode()).hexdigest(), seed=0,
        software_version="0.1.0", status="active", created_at=now, updated_at=now, last_seq=1,
        meta=meta,
    )  # fmt: skip


def test_a_session_records_the_defaults_its_config_relies_on() -> None:
    bare = parse_config(BARE)
    assert bare.relies_on_changed_defaults and library_meta(bare) == {"config_defaults": "0.2"}
    assert config_of(_record(BARE, library_meta(bare))).buffer == 1
    explicit = parse_config(BARE + "[cospar]\nbuffer = 1\n")
    assert not explicit.relies_on_changed_defaults and library_meta(explicit) == {}


def test_a_session_recorded_by_0_1_replays_with_0_1_defaults() -> None:
    assert config_of(_record(BARE, {})).buffer == 0
