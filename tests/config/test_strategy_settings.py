"""Strategy settings from the config (``[cospar.strategy_settings]``) and ``make_strategy``."""

from __future__ import annotations

import pytest

from gaitpref import ConfigError
from gaitpref.config import parse_config
from gaitpref.strategies import ConfidentEubo, Eubo, GatedEubo, Switch, make_strategy

BASE = """
[space.x]
min = 0.0
max = 1.0
num = 11

[model]
lengthscale = 0.2
signal_variance = 0.005
noise = 0.02

[cospar]
strategy = "{name}"

[cospar.strategy_settings]
{settings}
"""


@pytest.mark.parametrize(
    ("name", "settings", "expected"),
    [
        ("gated-eubo", "gates = 4", GatedEubo(gates=4)),
        ("eubo-then-sparring", "trials = 7", Switch(trials=7)),
        ("confident-eubo", "beta = 2.5\ncandidates = 8", ConfidentEubo(beta=2.5, candidates=8)),
        ("confident-eubo", "beta = 3", ConfidentEubo(beta=3.0)),
        ("eubo", "candidates = 16", Eubo(candidates=16)),
        ("gated-eubo", "", GatedEubo()),
        (
            "gated-eubo",
            "early_scale = 0.5\nearly_trials = 12",
            GatedEubo(early_scale=0.5, early_trials=12),
        ),
        (
            "gated-eubo",
            "sparring_from = 20\nsparring_until = 45",
            GatedEubo(sparring_from=20, sparring_until=45),
        ),
    ],
)
def test_settings_reach_the_strategy(name: str, settings: str, expected: object) -> None:
    cfg = parse_config(BASE.format(name=name, settings=settings))
    assert cfg.make_loop().strategy == expected


def test_a_plain_strategy_name_still_works() -> None:
    text = BASE.format(name="self-sparring", settings="").replace(
        "[cospar.strategy_settings]\n", ""
    )
    assert parse_config(text).make_loop().strategy.name == "self-sparring"


@pytest.mark.parametrize(
    ("name", "settings", "key", "message"),
    [
        (
            "gated-eubo",
            "gate = 2",
            None,
            "[cospar.strategy_settings]: unknown key 'gate' for "
            "strategy 'gated-eubo' (allowed: gates, early_scale, early_trials, sparring_from, "
            "sparring_until)",
        ),
        (
            "self-sparring",
            "beta = 1",
            None,
            "[cospar.strategy_settings]: unknown key 'beta' for strategy 'self-sparring' "
            "(allowed: none)",
        ),
        (
            "gated-eubo",
            "gates = 0",
            "gates",
            "[cospar.strategy_settings].gates: must be an integer >= 1, got 0",
        ),
        (
            "confident-eubo",
            "beta = -1.0",
            "beta",
            "[cospar.strategy_settings].beta: must be a finite number >= 0",
        ),
        ("confident-eubo", "beta = inf", "beta", "[cospar.strategy_settings].beta: must be"),
        (
            "gated-eubo",
            "early_scale = 0.0",
            "early_scale",
            "[cospar.strategy_settings].early_scale: must be a finite number >= 0.01 and <= 100",
        ),
        (
            "gated-eubo",
            "early_trials = -3",
            "early_trials",
            "[cospar.strategy_settings].early_trials: must be an integer >= 0",
        ),
        (
            "eubo-then-sparring",
            "trials = 2.5",
            "trials",
            "[cospar.strategy_settings].trials: must be an integer",
        ),
    ],
)
def test_bad_settings_name_the_setting(
    name: str, settings: str, key: str | None, message: str
) -> None:
    with pytest.raises(ConfigError) as info:
        parse_config(BASE.format(name=name, settings=settings))
    assert str(info.value).startswith(message)
    assert (info.value.table, info.value.key) == ("cospar.strategy_settings", key)


def test_make_strategy_names_the_setting() -> None:
    assert make_strategy("gated-eubo", gates=3) == GatedEubo(gates=3)
    with pytest.raises(ValueError, match=r"strategy 'eubo' has no setting 'gates' .*candidates"):
        make_strategy("eubo", gates=3)
    with pytest.raises(ValueError, match="unknown strategy 'ucb'"):
        make_strategy("ucb")
    with pytest.raises(ValueError, match="beta must be a finite number >= 0"):
        make_strategy("confident-eubo", beta=float("nan"))
    with pytest.raises(ValueError, match="trials must be an integer >= 0"):
        make_strategy("eubo-then-sparring", trials=-1)
    with pytest.raises(ValueError, match="candidates must be an integer >= 2"):
        make_strategy("eubo", candidates=1)
