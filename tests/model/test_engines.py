"""Choosing the dense or scalable path: names, limits, config key, identical loops."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import CoSpar, GradientCoactive, SimulatedUser, load_config, run_simulation
from gaitpref.config import ConfigError, parse_config
from gaitpref.model import DENSE_MAX_ACTIONS, PreferenceGP, SquaredExponential
from gaitpref.model.engines import DENSE_LIMIT_ACTIONS, resolve_sampler
from gaitpref.space import Feature, Space


def test_auto_picks_by_grid_size() -> None:
    assert resolve_sampler("auto", DENSE_MAX_ACTIONS) == "dense"
    assert resolve_sampler("auto", DENSE_MAX_ACTIONS + 1) == "scalable"
    assert resolve_sampler("dense", DENSE_LIMIT_ACTIONS) == "dense"
    assert resolve_sampler("scalable", 2) == "scalable"


def test_bad_sampler_names_and_oversized_dense_grids_are_refused() -> None:
    with pytest.raises(ValueError, match="sampler must be one of auto, dense, scalable"):
        resolve_sampler("fast", 10)
    with pytest.raises(ValueError, match=r"8193 actions .* use sampler=\"scalable\""):
        resolve_sampler("dense", DENSE_LIMIT_ACTIONS + 1)
    space = Space([Feature.linspace("x", 0, 1, 5)])
    with pytest.raises(ValueError, match="sampler"):
        PreferenceGP(space, SquaredExponential(0.2, 1.0), 0.1, sampler="Dense")


def test_config_sampler_key() -> None:
    text = load_config("synthetic-2d").text
    assert load_config("synthetic-2d").sampler == "auto"
    forced = parse_config(text.replace("noise = 0.01", 'noise = 0.01\nsampler = "dense"'))
    assert forced.sampler == "dense" and forced.make_loop().posterior.sampler == "dense"
    with pytest.raises(ConfigError, match=r"\[model\]\.sampler: must be one of"):
        parse_config(text.replace("noise = 0.01", 'noise = 0.01\nsampler = "gpu"'))
    big = text.replace("num = 30", "num = 100")  # 10,000 actions
    with pytest.raises(ConfigError, match=r"\[model\]\.sampler: .*10000 actions"):
        parse_config(big.replace("noise = 0.01", 'noise = 0.01\nsampler = "dense"'))


def test_the_loop_proposes_the_same_actions_on_either_path() -> None:
    """Same seed, same draws: a seeded session does not depend on the path (to rounding)."""
    config = load_config("synthetic-2d")
    objective = np.sin(6 * config.space.points).sum(axis=1)
    results = []
    for sampler in ("dense", "scalable"):
        loop = CoSpar(
            config.space, config.kernel, config.noise, n=2, buffer=1, seed=4, sampler=sampler
        )
        assert loop.posterior.sampler == sampler
        user = SimulatedUser(config.space, objective, np.random.default_rng(0))
        coactive = GradientCoactive(config.space, objective)
        results.append(run_simulation(loop, user, 40, coactive))
    assert results[0].actions.tolist() == results[1].actions.tolist()
    scale = np.max(np.abs(results[0].posterior.mean))
    np.testing.assert_allclose(
        results[1].posterior.mean, results[0].posterior.mean, rtol=1e-9, atol=1e-9 * scale
    )
