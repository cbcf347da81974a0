"""A strategy built by hand has the bounds a config's settings have: a candidate count, a number
of samples or gates past them allocated without bound at the first ask (10**9 samples were a
10**9 x A draw; 10**6 candidates a 10**6 x 10**6 pair matrix)."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import make_strategy
from gaitpref.strategies import Switch
from gaitpref.strategies.base import MAX_CANDIDATES, MAX_GATES, MAX_SAMPLES

CASES = [
    ("eubo", "candidates", MAX_CANDIDATES),
    ("confident-eubo", "candidates", MAX_CANDIDATES),
    ("information-gain", "candidates", MAX_CANDIDATES),
    ("plausible-eubo", "samples", MAX_SAMPLES),
    ("gated-eubo", "gates", MAX_GATES),
]


@pytest.mark.parametrize(("name", "setting", "high"), CASES)
def test_counts_past_the_bound_are_refused(name: str, setting: str, high: int) -> None:
    with pytest.raises(ValueError, match=rf"{setting} must be an integer >= \d and <= {high}"):
        make_strategy(name, **{setting: high + 1})
    with pytest.raises(ValueError, match=f"{setting} must be an integer"):
        make_strategy(name, **{setting: 10**12})
    assert getattr(make_strategy(name, **{setting: high}), setting) == high


@pytest.mark.parametrize(("name", "setting", "high"), CASES)
def test_numpy_counts_are_counts(name: str, setting: str, high: int) -> None:
    # np.int64(5) was refused: "must be an integer >= 1, got np.int64(5)"
    strategy = make_strategy(name, **{setting: np.int64(5)})
    value = getattr(strategy, setting)
    assert value == 5 and type(value) is int
    with pytest.raises(ValueError, match=f"{setting} must be an integer"):
        make_strategy(name, **{setting: np.True_})


def test_a_strategy_name_is_a_name() -> None:
    for name in (["eubo"], None, 3):
        with pytest.raises(ValueError, match="unknown strategy"):  # a list was "unhashable type"
            make_strategy(name)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("name", "setting", "value", "expected"),
    [
        # refused before: "must be a finite number >= 0, got np.float64(2.0)" and the like
        ("confident-eubo", "beta", np.float32(2.0), 2.0),
        ("confident-eubo", "beta", np.int64(2), 2),
        ("gated-eubo", "early_scale", np.float64(0.5), 0.5),
        ("gated-eubo", "early_trials", np.int64(7), 7),
        ("gated-eubo", "sparring_from", np.uint8(3), 3),
        ("gated-eubo", "sparring_until", np.int32(9), 9),
        ("eubo-then-sparring", "trials", np.int64(5), 5),
    ],
)
def test_numpy_numbers_are_numbers(name: str, setting: str, value: object, expected: float) -> None:
    made = getattr(make_strategy(name, **{setting: value}), setting)
    assert made == expected and type(made) is type(expected)
    with pytest.raises(ValueError, match=f"{setting} must be"):
        make_strategy(name, **{setting: np.True_})


@pytest.mark.parametrize(
    ("name", "setting", "value"),
    [
        ("confident-eubo", "beta", np.float64(np.nan)),
        ("confident-eubo", "beta", "1"),
        ("gated-eubo", "early_scale", np.float64(np.nan)),
        ("gated-eubo", "early_trials", np.int64(-1)),
        ("gated-eubo", "early_trials", 2.0),
        ("eubo-then-sparring", "trials", np.float64(3.0)),
    ],
)
def test_bad_numbers_stay_refused(name: str, setting: str, value: object) -> None:
    with pytest.raises(ValueError, match=f"{setting} must be"):
        make_strategy(name, **{setting: value})


def test_a_switch_switches_between_strategies() -> None:
    # a name in place of a strategy was an AttributeError at the first ask
    for part in ("early", "late"):
        with pytest.raises(TypeError, match=f"{part} must be a strategy"):
            Switch(**{part: "eubo"})  # type: ignore[arg-type]
    assert Switch(early=make_strategy("information-gain")).early.name == "information-gain"
