"""``[safety]``'s rule: ``risk`` by default since defaults 0.3, ROIAL's ``lambda`` when given, and
sessions recorded with 0.1's or 0.2's defaults replay with ROIAL's bound, as they ran."""

from __future__ import annotations

import hashlib
from datetime import UTC, datetime

import pytest

from gaitpref import ConfigError
from gaitpref.config import parse_config
from gaitpref.sessions.stored_config import config_of, library_meta
from gaitpref.storage.base import SessionRecord

BASE = """
name = "rated"
[space.x]
min = 0.0
max = 1.0
num = 11
[model]
lengthscale = 0.2
signal_variance = 0.01
noise = 0.02
fit = "fixed"
[cospar]
buffer = 1
[feedback.rating]
labels = ["very bad", "bad", "okay", "good"]
"""
AVOID = '[safety]\navoid = ["very bad"]\n'


def _record(text: str, meta: dict[str, object]) -> SessionRecord:
    now = datetime.now(UTC)
    return SessionRecord(
        id=1, subject="S01", config_name="rated", config_text=text,
        config_sha256=hashlib.sha256(text.encode()).hexdigest(), seed=0,
        software_version="0.2.0", status="active", created_at=now, updated_at=now, last_seq=1,
        meta=meta,
    )  # fmt: skip


def test_avoid_alone_takes_the_default_risk_and_records_the_defaults_version() -> None:
    cfg = parse_config(BASE + AVOID)
    assert cfg.safety.risk == pytest.approx(1 / 4 + 0.1)
    assert cfg.relies_on_changed_defaults and library_meta(cfg) == {"config_defaults": "0.3"}
    assert config_of(_record(BASE + AVOID, library_meta(cfg))).safety == cfg.safety
    three = BASE.replace('"okay", "good"', '"good"')
    assert parse_config(three + AVOID).safety.risk == pytest.approx(1 / 3 + 0.1)


def test_sessions_recorded_before_0_3_replay_with_roials_bound() -> None:
    for version in ("0.1", "0.2"):
        old = parse_config(BASE + AVOID, defaults=version).safety
        assert old.risk is None and old.lam == 1.0
    # a 0.2 session that relied on no changed default stored no version: 0.1's apply
    assert config_of(_record(BASE + AVOID, {})).safety.risk is None


def test_an_explicit_rule_needs_no_defaults_version() -> None:
    roial = parse_config(BASE + AVOID + "lambda = 0.5\n")
    assert roial.safety.risk is None and roial.safety.lam == 0.5
    assert not roial.relies_on_changed_defaults
    risky = parse_config(BASE + AVOID + "risk = 0.5\n")
    assert risky.safety.risk == 0.5 and not risky.relies_on_changed_defaults
    bare = parse_config(BASE)
    assert bare.safety.risk is None and not bare.relies_on_changed_defaults


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ("lambda = 1.0\nrisk = 0.5\n", r"\[safety\].risk: give either risk or lambda"),
        ("risk = 0.25\n", r"\[safety\].risk: must exceed 0.25"),
        ("risk = 0\n", r"\[safety\].risk"),
        ("risk = 1.5\n", r"\[safety\].risk"),
    ],
)
def test_bad_rules_name_the_key(extra: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        parse_config(BASE + AVOID + extra)


def test_fixed_thresholds_allow_any_risk() -> None:
    fixed = BASE + "thresholds = [-0.1, 0.0, 0.1]\n"
    assert parse_config(fixed + AVOID + "risk = 0.1\n").safety.risk == 0.1
