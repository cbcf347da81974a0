"""Configs that cannot hurt the process (issue 15 items 1-3, config side)."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from scipy.linalg import LinAlgError

from gaitpref import ConfigError, ConvergenceError, Feature, Space, SquaredExponential
from gaitpref.config import parse_config
from gaitpref.config.schema import MAX_ACTIONS, MAX_FEATURE_VALUES, MAX_SIGNAL_TO_NOISE
from gaitpref.loop.cospar import CoSpar
from gaitpref.model.laplace import fit_laplace
from gaitpref.model.likelihood import Probit
from gaitpref.strategies import STRATEGIES, make_strategy

MODEL = "[model]\nlengthscale = 0.2\nsignal_variance = 0.005\nnoise = 0.02\n"
GRID = '[cospar]\nsubspace = "grid"\n'  # the full grid asked for: no line path (issue 13)


def _feature(name: str, num: int | str) -> str:
    return f"[space.{name}]\nmin = 0.0\nmax = 1.0\nnum = {num}\n"


def _peak_of(text: str) -> tuple[ConfigError, int]:
    tracemalloc.start()
    try:
        with pytest.raises(ConfigError) as info:
            parse_config(text)
        return info.value, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize(
    ("text", "table", "key"),
    [
        (_feature("x", 1_000_000_000) + MODEL + GRID, "space.x", "num"),  # 23 GB before 0.2
        (_feature("x", 10_000_000) + MODEL + GRID, "space.x", "num"),
        (
            _feature("x", 1000) + _feature("y", 1001) + _feature("z", 1000) + MODEL + GRID,
            "space.y",
            "num",
        ),
        (_feature("x", 2**200) + MODEL, "space.x", "num"),
    ],
)
def test_a_huge_grid_fails_before_anything_is_built(text: str, table: str, key: str) -> None:
    error, peak = _peak_of(text)
    assert (error.table, error.key) == (table, key)
    assert f"at most {MAX_ACTIONS}" in str(error) or "<= " in str(error)
    assert peak < 1_000_000  # bytes: nothing grid-sized was allocated


def test_the_size_limit_is_checked_before_building_a_values_list() -> None:
    values = ", ".join(["0.1", "0.2", "0.3"])
    text = f"[space.x]\nvalues = [{values}]\n" + _feature("y", 999_999) + MODEL + GRID
    error, peak = _peak_of(text)
    assert (error.table, error.key) == ("space.y", "num")
    assert peak < 1_000_000


def test_a_server_can_lower_the_limit() -> None:
    with pytest.raises(ConfigError, match=r"\[space.x\].num: .*at most 100 are allowed"):
        parse_config(_feature("x", 101) + MODEL + GRID, max_actions=100)
    # without subspace = "grid", a num past the limit is a continuous feature (issue 13)
    assert parse_config(_feature("x", 101) + MODEL, max_actions=100).subspace == "line"


def test_a_feature_with_more_values_than_a_kernel_factor_holds_is_refused_by_name() -> None:
    """A 1-D grid of 240,000 values is within the actions limit, but its kernel factor would be
    240,000 x 240,000 (429 GiB): the full grid refuses it at the feature's key, before anything
    is built; without subspace = "grid" it runs on the line path."""
    error, peak = _peak_of(_feature("x", 2) + _feature("y", 240_000) + MODEL + GRID)
    assert (error.table, error.key) == ("space.y", "num")
    assert f"at most {MAX_FEATURE_VALUES} a feature" in str(error)
    assert peak < 1_000_000
    assert parse_config(_feature("x", MAX_FEATURE_VALUES) + MODEL + GRID).subspace == "grid"
    assert parse_config(_feature("x", MAX_FEATURE_VALUES + 1) + MODEL).subspace == "line"
    wide = Space([Feature.linspace("step", 0.0, 1.0, MAX_FEATURE_VALUES + 1)])
    with pytest.raises(ValueError, match=r"feature 'step' has 1,001 values.*LineCoSpar"):
        CoSpar(wide, SquaredExponential(0.3, 1.0), 0.05)


@pytest.mark.parametrize(
    ("text", "why"),
    [
        ("b = " + "[" * 500 + "]" * 500, "nested too deeply"),  # a RecursionError in tomllib
        ("b = " + "9" * 5000, "4300 digits"),  # a ValueError in tomllib
        (_feature("x", "9" * 5000) + MODEL, "4300 digits"),
    ],
)
def test_toml_that_python_cannot_read_is_a_config_error(text: str, why: str) -> None:
    with pytest.raises(ConfigError, match=f"config is not valid TOML: .*{why}") as info:
        parse_config(text)
    assert "set_int_max_str_digits" not in str(info.value)


@pytest.mark.parametrize("key", ["n", "buffer"])
def test_n_and_buffer_cannot_exceed_the_grid(key: str) -> None:  # item 2
    with pytest.raises(ConfigError, match=rf"\[cospar\].{key}: must be at most the grid's 5 "):
        parse_config(_feature("x", 5) + MODEL + f"[cospar]\n{key} = 6\n")
    parse_config(_feature("x", 5) + MODEL + f"[cospar]\n{key} = 5\n")


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_every_strategy_proposes_even_when_the_query_fills_the_grid(strategy: str) -> None:
    cfg = parse_config(
        _feature("x", 3) + MODEL + f'[cospar]\nn = 3\nbuffer = 3\nstrategy = "{strategy}"\n'
    )
    loop = cfg.make_loop()
    for _ in range(4):
        q = loop.ask()
        assert len(q.actions) == 3 and all(0 <= a < 3 for a in q.actions)
        loop.tell(
            q, [(q.actions[0], q.actions[1], "first")] if q.actions[0] != q.actions[1] else []
        )


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_a_loop_built_by_hand_with_n_past_the_grid_is_refused_by_name(strategy: str) -> None:
    space = Space([Feature.linspace("x", 0, 1, 4)])
    # refused where it is built (it was at the first ask, by the strategy's context)
    with pytest.raises(ValueError, match=r"must be at most the grid's size, 4, got 5"):
        CoSpar(space, SquaredExponential((0.2,), 0.005), 0.02, n=5,
               strategy=make_strategy(strategy))  # fmt: skip
    # past the bound on every query (QUERY_LIMIT, a config's [cospar] n) whatever the grid
    with pytest.raises(ValueError, match=r"must be at most 64, got 1000000000"):
        CoSpar(space, SquaredExponential((0.2,), 0.005), 0.02, n=10**9,
               strategy=make_strategy(strategy))  # fmt: skip


@pytest.mark.parametrize(
    ("model", "key", "why"),
    [
        ("noise = 1e-12", "noise", "cannot be fitted"),  # item 3
        ("noise = 1e-5", "noise", "signal_variance / noise\\*\\*2 is 5e\\+07"),
        ("signal_variance = 1e300", "signal_variance", "<= 1e\\+12"),
        ("jitter = 1", "jitter", "must be at most signal_variance"),
    ],
)
def test_degenerate_scales_are_refused_with_the_reason(model: str, key: str, why: str) -> None:
    lines = dict(line.split(" = ") for line in MODEL.splitlines()[1:])
    name, value = model.split(" = ")
    lines[name] = value
    text = _feature("x", 5) + "[model]\n" + "".join(f"{k} = {v}\n" for k, v in lines.items())
    with pytest.raises(ConfigError, match=why) as info:
        parse_config(text)
    assert (info.value.table, info.value.key) == ("model", key)


def test_the_coactive_weight_counts_in_the_signal_to_noise_bound() -> None:
    noise = (0.005 / MAX_SIGNAL_TO_NOISE) ** 0.5 * 1.01
    text = _feature("x", 5) + MODEL.replace("noise = 0.02", f"noise = {noise}")
    parse_config(text)
    with pytest.raises(ConfigError, match=r"\[model\].noise: .*coactive_weight\*\*2 \(2\*\*2\)"):
        parse_config(text + "[cospar]\ncoactive_weight = 2.0\n")


def test_a_loop_at_the_signal_to_noise_bound_takes_contradicting_answers() -> None:
    noise = (0.005 / MAX_SIGNAL_TO_NOISE) ** 0.5
    cfg = parse_config(
        _feature("x", 15) + _feature("y", 10) + MODEL.replace("noise = 0.02", f"noise = {noise}")
    )
    loop, rng = cfg.make_loop(seed=1), np.random.default_rng(0)
    for _ in range(30):
        q = loop.ask()
        comps = [(q.actions[0], q.buffer[0], rng.choice(["first", "second"]))] if q.buffer else []
        loop.tell(q, comps)
    assert len(loop.preferences) >= 20


def test_a_hessian_that_cannot_be_factorised_is_a_convergence_error() -> None:
    k_vv = np.array([[1e300, 0.0], [0.0, 1e300]])
    first, second = np.array([0]), np.array([1])
    with (
        np.errstate(over="ignore"),
        pytest.raises(ConvergenceError, match=r"Hessian .* cannot be factorised") as info,
    ):
        fit_laplace(k_vv, np.array([0, 1]), first, second, Probit(np.array([1e-12])))
    assert not isinstance(info.value, LinAlgError)


RATED = (
    _feature("x", 10)
    + "[model]\nlengthscale = 0.2\nsignal_variance = 1.0\nnoise = 0.1\n"
    + '[feedback.rating]\nlabels = ["very bad", "bad", "good"]\n'
)


@pytest.mark.parametrize(
    ("text", "table", "key", "why"),
    [
        (RATED + '[safety]\navoid = ["very bad"]\nrisk = 1\n', "safety", "risk", "< 1"),
        (
            _feature("x", 10)
            + MODEL
            + "[feedback.rating]\nlabels = ["
            + ", ".join(f'"c{k}"' for k in range(10))
            + "]\n[safety]\navoid = ["
            + ", ".join(f'"c{k}"' for k in range(9))
            + "]\n",
            "safety",
            "avoid",
            "not below 1",
        ),
        (RATED.replace('"good"]', '"good"]\nnoise = 1e-12'), "feedback.rating", "noise", r"1e\+24"),
        (
            "[space.x]\nvalues = [0.0, 0.5, 1.0]\n"
            + MODEL
            + '[cospar]\nsubspace = "line"\nn = 4\n',
            "cospar",
            "n",
            "at most 3",
        ),
        (
            "[space.x]\nmin = 0.0\nmax = 1.0\n" + MODEL + "[cospar]\nn = 8\nline_points = 2\n",
            "cospar",
            "n",
            "at most 2",
        ),
        (
            "[space.a]\nvalues = [3.0]\n" + MODEL + '[cospar]\nsubspace = "line"\n',
            "cospar",
            "subspace",
            "no line to draw",
        ),
    ],
)
def test_settings_that_failed_at_the_first_ask_are_config_errors(
    text: str, table: str, key: str, why: str
) -> None:
    with pytest.raises(ConfigError, match=why) as info:
        parse_config(text)
    assert (info.value.table, info.value.key) == (table, key)


def test_snapping_to_a_million_values_is_a_bisection() -> None:
    """The line path snaps every point of a query to each feature's values: an array rebuilt
    per call made a 1,000,000-value feature cost seconds a query."""
    feature = Feature.linspace("x", 0.0, 1.0, 1_000_001)
    values = feature.array
    for v in np.random.default_rng(0).uniform(-0.1, 1.1, 200):
        assert feature.snap(v) == values[np.argmin(np.abs(values - np.clip(v, 0.0, 1.0)))]
    assert feature.snap(-1.0) == 0.0 and feature.snap(2.0) == 1.0
