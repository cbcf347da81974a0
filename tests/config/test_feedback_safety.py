"""``[feedback.rating]`` and ``[safety]``: a loop with a rating scale and a region of avoidance,
and errors that name the table and key."""

from __future__ import annotations

import pytest

from gaitpref import ConfigError
from gaitpref.config import parse_config

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
"""
RATING = '\n[feedback.rating]\nlabels = ["very bad", "bad", "okay", "good"]\n'


def test_rating_scale_and_region_of_avoidance() -> None:
    cfg = parse_config(BASE + RATING + '[safety]\navoid = ["very bad"]\nlambda = 0.5\n')
    assert cfg.ordinal is not None and cfg.ordinal.categories[-1] == "good"
    assert cfg.ordinal.noise == 0.02 and cfg.ordinal.thresholds is None
    assert cfg.safety.avoid == 1 and cfg.safety.lam == 0.5
    loop = cfg.make_loop()
    assert loop.gp.ordinal == cfg.ordinal and loop.safety == cfg.safety
    thresholds = parse_config(BASE + RATING + "thresholds = [-0.1, 0.0, 0.1]\nnoise = 0.05\n")
    assert thresholds.ordinal is not None and thresholds.ordinal.thresholds == (-0.1, 0.0, 0.1)


def test_without_the_tables_nothing_changes() -> None:
    cfg = parse_config(BASE)
    assert cfg.ordinal is None and cfg.safety.avoid == 0
    assert cfg.make_loop().allowed() is None


@pytest.mark.parametrize(
    ("extra", "where"),
    [
        ('\n[feedback.rating]\nlabels = ["only"]\n', r"\[feedback.rating\].labels"),
        ('\n[feedback.rating]\nlabels = ["a", "a"]\n', r"\[feedback.rating\].labels"),
        (
            RATING + "thresholds = [0.1, 0.0, 0.2]\n",
            r"\[feedback.rating\].thresholds: must increase",
        ),
        (RATING + "thresholds = [0.1]\n", r"\[feedback.rating\].thresholds: must hold 3"),
        (RATING + "noize = 0.1\n", r"\[feedback.rating\]: unknown key 'noize'"),
        ('\n[feedback.ratings]\nlabels = ["a", "b"]\n', r"\[feedback\]: unknown key 'ratings'"),
        ('\n[safety]\navoid = ["very bad"]\n', r"\[safety\].avoid: needs a \[feedback.rating\]"),
        (RATING + '[safety]\navoid = ["bad"]\n', r"\[safety\].avoid: must be the worst labels"),
        (
            RATING + '[safety]\navoid = ["very bad", "bad", "okay", "good"]\n',
            r"\[safety\].avoid: must leave",
        ),
        (RATING + "[safety]\nlambda = -1\n", r"\[safety\].lambda"),
        (RATING + "[safety]\nunsafe_radius = 2\n", r"\[safety\].unsafe_radius"),
    ],
)
def test_errors_name_the_table_and_key(extra: str, where: str) -> None:
    with pytest.raises(ConfigError, match=where):
        parse_config(BASE + extra)


AVOID = '[safety]\navoid = ["very bad"]\n'


def test_avoid_alone_takes_the_default_risk() -> None:
    assert parse_config(BASE + RATING + AVOID).safety.risk == pytest.approx(1 / 4 + 0.1)
    three = RATING.replace('"okay", "good"', '"good"')
    assert parse_config(BASE + three + AVOID).safety.risk == pytest.approx(1 / 3 + 0.1)
    roial = parse_config(BASE + RATING + AVOID + "lambda = 0.5\n").safety
    assert roial.risk is None and roial.lam == 0.5  # ROIAL's bound when lambda is given
    assert parse_config(BASE + RATING + AVOID + "risk = 0.5\n").safety.risk == 0.5
    assert parse_config(BASE).safety.risk is None


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ("lambda = 1.0\nrisk = 0.5\n", r"\[safety\].risk: give either risk or lambda"),
        ("risk = 0.25\n", r"\[safety\].risk: must exceed 0.25"),
        ("risk = 0\n", r"\[safety\].risk"),
        ("risk = 1.5\n", r"\[safety\].risk"),
        ("cautious = 1\n", r"\[safety\].cautious: must be below 1"),
        ("cautious = -0.1\n", r"\[safety\].cautious: must be a finite number >= 0"),
        ('cautious = "yes"\n', r"\[safety\].cautious"),
        ("cautious = 0.5\nlambda = 1.0\n", r"\[safety\].cautious: needs the risk rule"),
        ("cautious = 0\nexplore = 2.0\n", r"\[safety\].explore: is a setting of the cautious"),
        ("lambda = 1\nexplore = 2.0\n", r"\[safety\].explore: is a setting of the cautious"),
        ("cautious = 0.5\nexplore = -1\n", r"\[safety\].explore: must be a finite number"),
    ],
)
def test_bad_rules_name_the_key(extra: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        parse_config(BASE + RATING + AVOID + extra)


def test_fixed_thresholds_allow_any_risk() -> None:
    fixed = RATING + "thresholds = [-0.1, 0.0, 0.1]\n"
    assert parse_config(BASE + fixed + AVOID + "risk = 0.1\n").safety.risk == 0.1


def test_a_region_under_the_risk_rule_is_cautious_by_default() -> None:
    cfg = parse_config(BASE + RATING + AVOID)
    assert cfg.safety.cautious == 0.6 and cfg.safety.explore == 1.0
    assert cfg.safety.risk == pytest.approx(0.35) and cfg.make_loop().safety == cfg.safety
    assert "safety.cautious" in cfg.defaulted  # a session records the defaults it relied on
    given = parse_config(BASE + RATING + AVOID + "cautious = 0.3\nexplore = 2\n").safety
    assert (given.cautious, given.explore) == (0.3, 2.0)
    assert parse_config(BASE + RATING + AVOID + "cautious = 0\n").safety.cautious is None
    assert parse_config(BASE + RATING + AVOID + "lambda = 1.0\n").safety.cautious is None
    assert parse_config(BASE + RATING).safety.cautious is None  # no region: nothing to be
    for version in ("0.1", "0.2", "0.3"):  # sessions recorded earlier replay without it
        assert parse_config(BASE + RATING + AVOID, defaults=version).safety.cautious is None


def test_cautious_needs_a_region_of_avoidance() -> None:
    with pytest.raises(ConfigError, match=r"\[safety\].cautious: needs a region of avoidance"):
        parse_config(BASE + RATING + "[safety]\ncautious = 0.5\n")
