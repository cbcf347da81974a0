"""Shared, session-scoped gaits: a few optimizations reused by many tests (keeps them fast)."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref.gaits import (
    CompassGaitParams,
    Gait,
    GaitLibrary,
    GaitRequest,
    build_library,
    optimize_gait,
)


@pytest.fixture(scope="session")
def params() -> CompassGaitParams:
    return CompassGaitParams()


@pytest.fixture(scope="session")
def gait(params: CompassGaitParams) -> Gait:
    """A typical gait: 0.12 m steps at the paper's 0.2 m/s."""
    result = optimize_gait(GaitRequest(0.12, speed=0.2), params)
    assert result.feasible, result.message
    return result


@pytest.fixture(scope="session")
def speed_library() -> GaitLibrary:
    """Seven step lengths over the paper's range at 0.2 m/s, with a two-value width label."""
    lengths = np.linspace(0.08, 0.18, 7).tolist()
    return build_library(lengths, speed=0.2, step_widths=[0.25, 0.30], n_jobs=1)


@pytest.fixture(scope="session")
def duration_library() -> GaitLibrary:
    """A 3 x 2 grid over step length and step duration."""
    return build_library([0.10, 0.13, 0.16], step_durations=[0.85, 1.15], n_jobs=1)
