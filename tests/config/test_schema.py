"""The schema: each kind of error names its table and key (issue 15 item 9); the defaults."""

from __future__ import annotations

import dataclasses

import pytest

from gaitpref import ConfigError
from gaitpref.config import DEFAULT_BUFFER, DEFAULTS, LIMITS, parse_config
from gaitpref.config.model import RELATIVE_JITTER
from gaitpref.config.schema import STRATEGY_TABLES, TABLES
from gaitpref.strategies import STRATEGY_CLASSES, STRATEGY_SETTINGS

SPACE = "[space.x]\nmin = 0.0\nmax = 1.0\nnum = 11\n"
MODEL = "[model]\nlengthscale = 0.2\nsignal_variance = 0.005\nnoise = 0.02\n"


def _error(text: str) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        parse_config(text)
    return info.value


@pytest.mark.parametrize(
    ("text", "table", "key", "message"),
    [
        # issue 15 item 9: the location is part of the message and of the error
        (
            SPACE + MODEL + "noize = 1\n",
            "model",
            None,
            "[model]: unknown key 'noize' (allowed: lengthscale, signal_variance, noise, jitter,",
        ),
        (SPACE + "[cospar]\nn = 1\n", "", "model", "model: missing (required: a table"),
        (
            SPACE + MODEL + "[cospar]\nbuffer = -1\n",
            "cospar",
            "buffer",
            "[cospar].buffer: must be an integer >= 0, got -1",
        ),
        (
            SPACE + MODEL + "[cospar]\nn = 65\n",
            "cospar",
            "n",
            "[cospar].n: must be an integer <= 64, got 65",
        ),
        (
            SPACE + MODEL + "[cospar]\nseed = 1.5\n",
            "cospar",
            "seed",
            "[cospar].seed: must be an integer from 0 to",
        ),
        (
            SPACE + MODEL.replace("noise = 0.02", "noise = nan"),
            "model",
            "noise",
            "[model].noise: must be a finite number >= 1e-12 and <= 1e+12, got nan",
        ),
        (
            SPACE + MODEL.replace("0.005", "inf"),
            "model",
            "signal_variance",
            "[model].signal_variance: must be a finite number",
        ),
        (SPACE + MODEL.replace("noise = 0.02", ""), "model", "noise", "[model].noise: missing"),
        (
            SPACE + MODEL + 'sampler = "fast"\n',
            "model",
            "sampler",
            "[model].sampler: must be one of auto, dense, scalable, got 'fast'",
        ),
        (
            SPACE.replace("num = 11", 'num = "11"') + MODEL,
            "space.x",
            "num",
            "[space.x].num: must be an integer from 1 to 4611686018427387904, got '11'",
        ),
        (SPACE + "unit = 3\n" + MODEL, "space.x", "unit", "[space.x].unit: must be text"),
        (
            SPACE + 'words = ["up"]\n' + MODEL,
            "space.x",
            "words",
            "[space.x].words: must be two words",
        ),
        (SPACE.replace("min = 0.0\n", "") + MODEL, "space.x", "min", "[space.x].min: missing"),
        (
            "[space.x]\nvalues = [0.1, 0.1]\n" + MODEL,
            "space.x",
            "values",
            "[space.x].values: the values must be strictly increasing",
        ),
        (
            "[space.x]\nvalues = []\n" + MODEL,
            "space.x",
            "values",
            "[space.x].values: must be a list of 1..1000000 numbers",
        ),
        ("[space]\n" + MODEL, "space", None, "[space]: needs one table per feature"),
        ("space = 3\n" + MODEL, "", "space", "space: must be a table"),
        (
            SPACE + MODEL + "[model.prior]\nsignal_variance = [1e-3, -1]\n",
            "model.prior",
            "signal_variance",
            "[model.prior].signal_variance: must be [median, sd]",
        ),
        (
            SPACE + MODEL.replace("lengthscale = 0.2", "lengthscale = { x = -1 }"),
            "model.lengthscale",
            "x",
            "[model.lengthscale].x: must be a finite number >= 1e-12",
        ),
        (
            SPACE + MODEL.replace("lengthscale = 0.2", "lengthscale = { y = 1 }"),
            "model.lengthscale",
            None,
            "[model.lengthscale]: unknown key 'y' (allowed: x)",
        ),
        (
            SPACE + MODEL.replace("lengthscale = 0.2", "lengthscale = {}"),
            "model.lengthscale",
            "x",
            "[model.lengthscale].x: missing",
        ),
        ("name = 1\n" + SPACE + MODEL, "", "name", "name: must be text"),
    ],
)
def test_each_error_names_its_table_and_key(
    text: str, table: str, key: str | None, message: str
) -> None:
    error = _error(text)
    assert str(error).startswith(message)
    assert (error.table, error.key) == (table, key)


def test_a_missing_model_table_is_named() -> None:
    error = _error(SPACE)
    assert str(error).startswith("model: missing") and "a table" in str(error)
    assert error.key == "model"


def test_invalid_toml_is_a_config_error_without_a_place() -> None:
    error = _error("[space.x\n")
    assert str(error).startswith("config is not valid TOML") and error.table is None


def test_the_defaults_table_is_what_a_bare_config_gets() -> None:
    cfg = parse_config(SPACE + MODEL)
    cospar = DEFAULTS["cospar"]
    assert (cfg.n, cfg.buffer, cfg.coactive_weight, cfg.seed, cfg.strategy) == (
        cospar["n"],
        cospar["buffer"],
        cospar["coactive_weight"],
        cospar["seed"],
        cospar["strategy"],
    )
    assert DEFAULT_BUFFER == 1 == cfg.buffer  # the paper's b = 1: a bare config compares
    assert DEFAULTS["model"]["jitter"] is None  # a nugget relative to the signal (0.7 on)
    assert cfg.kernel.jitter == RELATIVE_JITTER * cfg.kernel.variance
    assert cfg.learning.fit == DEFAULTS["model"]["fit"] and cfg.sampler == "auto"
    assert cfg.space.features[0].coactive == DEFAULTS["space.<feature>"]["coactive"]
    assert cfg.strategy_settings == {}
    assert cfg.defaulted >= {"cospar.buffer", "cospar.n", "cospar.strategy"}
    assert set(TABLES) >= {"", "model", "model.prior", "cospar", "gaits", "space.<feature>"}
    assert LIMITS["actions"] == 1_000_000


def test_strategy_defaults_are_the_classes_own() -> None:
    for name, table in STRATEGY_TABLES.items():
        assert tuple(table) == STRATEGY_SETTINGS[name]
        made = STRATEGY_CLASSES[name]()
        for setting, key in table.items():
            assert getattr(made, setting) == key.default
        assert {f.name for f in dataclasses.fields(made)} >= set(table)
