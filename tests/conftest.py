from __future__ import annotations

import numpy as np
import pytest

from gaitpref import Feature, Space, SquaredExponential


@pytest.fixture
def small_space() -> Space:
    """A 7 x 5 grid with units, small enough for dense references."""
    return Space(
        [
            Feature.linspace("step_length", 0.08, 0.18, 7, unit="m"),
            Feature.linspace("step_duration", 0.85, 1.15, 5, unit="s"),
        ]
    )


@pytest.fixture
def small_kernel() -> SquaredExponential:
    return SquaredExponential((0.03, 0.08), 0.005, 1e-7)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)
