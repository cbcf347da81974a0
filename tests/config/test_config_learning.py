"""Config keys for strategies, ties and hyperparameter fitting."""

from __future__ import annotations

import pytest

from gaitpref import ConfigError
from gaitpref.config import (
    DEFAULT_FIT,
    DEFAULT_STRATEGY,
    DEFAULT_TIES,
    ExperimentConfig,
    parse_config,
)
from gaitpref.model.hyperfit import LogNormal
from gaitpref.strategies import GatedEubo, SelfSparring

BASE = """
[space.step_length]
min = 0.08
max = 0.18
num = 15

[space.step_width]
min = 0.25
max = 0.30
num = 6

[model]
lengthscale = {{ step_length = 0.03, step_width = 0.03 }}
signal_variance = 0.005
jitter = 1e-7
noise = 0.02
{model}

[cospar]
n = 1
buffer = 1
{cospar}
"""


def _cfg(model: str = "", cospar: str = "") -> ExperimentConfig:
    return parse_config(BASE.format(model=model, cospar=cospar))


def test_a_config_without_the_keys_gets_the_defaults() -> None:
    cfg = _cfg()
    assert (cfg.strategy, cfg.learning.ties, cfg.learning.fit) == (
        DEFAULT_STRATEGY, DEFAULT_TIES, DEFAULT_FIT,
    )  # fmt: skip
    loop = cfg.make_loop()
    assert loop.strategy.name == DEFAULT_STRATEGY and loop.learning == cfg.learning


def test_every_key_is_read() -> None:
    cfg = _cfg(
        'ties = "model"\ntie_band = "fit"\nfit = "evidence"\nrefit_every = 4\n'
        "[model.prior]\nlengthscale = { step_width = [0.02, 0.5] }\n"
        "signal_variance = [0.005, 1.0]\ntie_band = [0.01, 0.5]",
        'strategy = "gated-eubo"',
    )
    learning = cfg.learning
    assert learning.ties == "model" and learning.tie_band is None and learning.fit == "evidence"
    assert learning.refit_every == 4 and learning.prior is not None
    assert learning.hyper == "map" and learning.hypotheses == (0.5, 0.71, 1.0, 1.41, 2.0)
    averaged = _cfg('hyper = "average"\nhypotheses = [0.5, 1, 2]', "").learning
    assert averaged.hyper == "average" and averaged.hypotheses == (0.5, 1.0, 2.0)
    assert learning.prior.lengthscale[1] == LogNormal(0.02, 0.5)
    assert learning.prior.lengthscale[0].median == pytest.approx(0.025)  # default: range / 4
    assert learning.prior.variance == LogNormal(0.005, 1.0)
    assert learning.prior.band == LogNormal(0.01, 0.5)
    assert isinstance(cfg.make_loop().strategy, GatedEubo)
    fixed = _cfg('ties = "model"\ntie_band = 0.01\nfit = "fixed"', 'strategy = "self-sparring"')
    assert fixed.learning.tie_band == 0.01 and isinstance(fixed.make_loop().strategy, SelfSparring)


@pytest.mark.parametrize(
    ("model", "cospar", "message"),
    [
        ("", 'strategy = "ucb"', r"\[cospar\].strategy: must be one of self-sparring, eubo"),
        ('ties = "keep"', "", r"\[model\].ties: must be one of drop, model"),
        ('fit = "mle"', "", r"\[model\].fit: must be one of fixed, evidence"),
        ('ties = "drop"\ntie_band = 0.1', "", r'tie_band: only used with ties = "model"'),
        ('ties = "model"\nfit = "fixed"', "", "needs a number"),
        ('ties = "model"\nfit = "fixed"\ntie_band = "fit"', "", 'needs fit = "evidence"'),
        (
            'ties = "model"\ntie_band = -1',
            "",
            r'\[model\].tie_band: must be "fit" or a finite number >= 1e-12',
        ),
        ("refit_every = 0", "", r"\[model\].refit_every: must be an integer >= 1"),
        ('hyper = "mean"', "", r"\[model\].hyper: must be one of map, average"),
        ('fit = "fixed"\nhyper = "average"', "", r"\[model\]: hyper = 'average' needs fit"),
        ("hypotheses = []", "", r"\[model\].hypotheses: must be a list of 1..15 numbers"),
        ("hypotheses = [1, 0]", "", r"\[model\].hypotheses: must be a list of 1..15 numbers"),
        ("hypotheses = [1, 1]", "", r"\[model\]: hypotheses must differ"),
        ("[model.prior]\nnoise = [1, 1]", "", r"\[model.prior\]: unknown key 'noise'"),
        ("[model.prior]\nsignal_variance = 1", "", r"must be \[median, sd\]"),
        (
            "[model.prior]\nsignal_variance = [0, 1]",
            "",
            r"\[model.prior\].signal_variance: must be \[median, sd\] with 1e-12 <= median",
        ),
        ("[model.prior]\nlengthscale = { speed = [1, 1] }", "", "unknown key 'speed'"),
        (
            'ties = "drop"\n[model.prior]\ntie_band = [0.1, 1]',
            "",
            'only used with tie_band = "fit"',
        ),
    ],
)
def test_bad_learning_keys_name_the_key(model: str, cospar: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        _cfg(model, cospar)


def test_a_range_too_small_for_the_default_lengthscale_prior_is_named() -> None:
    """A quarter of a subnormal range rounds to 0: the prior's median would not be positive."""
    text = BASE.format(model="", cospar="")
    text = text.replace("min = 0.25\nmax = 0.30\nnum = 6", "min = 0.0\nmax = 5e-324\nnum = 2")
    with pytest.raises(ConfigError, match=r"\[space.step_width\]: range 5e-324 is too small"):
        parse_config(text)
