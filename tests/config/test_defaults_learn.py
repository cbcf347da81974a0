"""A bare config learns (issue 11 item 5), and sessions that relied on 0.1's defaults replay."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import ConfigError
from gaitpref.config import parse_config
from gaitpref.sessions.stored_config import config_of, library_meta
from tests.config.records import stored_record

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
# [model]'s share, jitter and warm_first, given (their defaults changed in 0.6, 0.7 and 0.8)
SHARE = 'share = "average"\njitter = 0.0\nwarm_first = "recommended"\n'


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


def test_a_session_records_the_defaults_its_config_relies_on() -> None:
    bare = parse_config(BARE)
    assert bare.relies_on_changed_defaults and library_meta(bare) == {"config_defaults": "0.13"}
    assert config_of(stored_record(BARE, library_meta(bare))).buffer == 1
    explicit = parse_config(BARE + SHARE + "[cospar]\nbuffer = 1\n")
    assert not explicit.relies_on_changed_defaults and library_meta(explicit) == {}


def test_a_session_recorded_by_0_1_replays_with_0_1_defaults() -> None:
    assert config_of(stored_record(BARE, {})).buffer == 0


RATED = (
    BARE + SHARE + '[cospar]\nbuffer = 1\n[feedback.rating]\nlabels = ["very bad", "bad", "good"]\n'
)
AVOID = '[safety]\navoid = ["very bad"]\n'


def test_a_region_of_avoidance_records_the_defaults_of_its_rule() -> None:
    cfg = parse_config(RATED + AVOID)  # the rule left to the defaults: risk since 0.3,
    assert cfg.safety.risk == pytest.approx(1 / 3 + 0.1)  # its cautious level since 0.4
    assert cfg.safety.cautious == 0.6
    assert cfg.relies_on_changed_defaults and library_meta(cfg) == {"config_defaults": "0.13"}
    assert config_of(stored_record(RATED + AVOID, library_meta(cfg))).safety == cfg.safety
    for explicit in (
        "lambda = 1.0\n",
        "risk = 0.5\ncautious = 0.6\n",
        "cautious = 0\nrisk = 0.5\n",
    ):
        assert not parse_config(RATED + AVOID + explicit).relies_on_changed_defaults
    assert parse_config(RATED + AVOID + "risk = 0.5\n").relies_on_changed_defaults  # cautious
    assert not parse_config(RATED).relies_on_changed_defaults  # no region: no rule relied on


def test_a_region_recorded_before_0_3_replays_with_roials_bound() -> None:
    for version in ("0.1", "0.2"):
        old = parse_config(RATED + AVOID, defaults=version).safety
        assert old.risk is None and old.lam == 1.0
    # a 0.2 session that relied on no changed default stored no version: 0.1's apply
    assert config_of(stored_record(RATED + AVOID, {})).safety.risk is None


def test_a_region_recorded_with_the_0_3_defaults_replays_without_the_cautious_level() -> None:
    old = config_of(stored_record(RATED + AVOID, {"config_defaults": "0.3"})).safety
    assert old.risk == pytest.approx(1 / 3 + 0.1) and old.cautious is None
    # a 0.3 session whose region gave risk itself relied on no changed default then and
    # stored no version: it replays with 0.1's defaults, also without the cautious level
    given = config_of(stored_record(RATED + AVOID + "risk = 0.5\n", {})).safety
    assert given.risk == 0.5 and given.cautious is None


def test_a_warm_starts_share_is_a_mixture_since_0_6_and_map_before() -> None:
    assert parse_config(BARE).learning.share == "average"
    assert "model.share" in parse_config(BARE).defaulted
    for version in ("0.1", "0.2", "0.3", "0.4", "0.5"):
        assert parse_config(BARE, defaults=version).learning.share == "map"
        assert parse_config(BARE + SHARE, defaults=version).learning.share == "average"
    assert config_of(stored_record(BARE, {"config_defaults": "0.5"})).learning.share == "map"
    assert config_of(stored_record(BARE, {})).learning.share == "map"  # recorded by 0.1
    assert (
        config_of(stored_record(BARE, library_meta(parse_config(BARE)))).learning.share == "average"
    )
    with pytest.raises(ConfigError, match="share"):
        parse_config(BARE + 'share = "mean"\n')


def test_a_config_without_jitter_gets_a_relative_nugget_since_0_7() -> None:
    from gaitpref.config.model import RELATIVE_JITTER

    assert parse_config(BARE).kernel.jitter == pytest.approx(RELATIVE_JITTER * 0.005, rel=1e-12)
    assert parse_config(BARE, defaults="0.6").kernel.jitter == 0.0  # as those sessions ran
    assert parse_config(BARE + "jitter = 0.0\n").kernel.jitter == 0.0  # given: kept
    assert config_of(stored_record(BARE, {"config_defaults": "0.6"})).kernel.jitter == 0.0


def test_a_warm_starts_first_trial_is_the_recommendation_since_0_8_the_strategys_before() -> None:
    assert parse_config(BARE).learning.warm_first == "recommended"
    assert "model.warm_first" in parse_config(BARE).defaulted
    for version in ("0.1", "0.4", "0.6", "0.7"):
        assert parse_config(BARE, defaults=version).learning.warm_first == "strategy"
        assert parse_config(BARE + SHARE, defaults=version).learning.warm_first == "recommended"
    assert config_of(stored_record(BARE, {"config_defaults": "0.7"})).learning.warm_first == (
        "strategy"
    )
    assert config_of(stored_record(BARE, {})).learning.warm_first == "strategy"  # by 0.1
    given = parse_config(BARE + 'warm_first = "strategy"\n')
    assert given.learning.warm_first == "strategy" and "model.warm_first" not in given.defaulted
    with pytest.raises(ConfigError, match=r"model.*warm_first.*'first'"):
        parse_config(BARE + 'warm_first = "first"\n')
