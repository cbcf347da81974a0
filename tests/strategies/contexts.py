"""One way for the strategy tests to build an :class:`AskContext`."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from gaitpref.model.posterior import Posterior
from gaitpref.strategies import AskContext


def ask_context(
    post: Posterior,
    n: int,
    buffer: tuple[int, ...],
    seed: int,
    allowed: NDArray[np.bool_] | None = None,
    trial: int | None = None,
) -> AskContext:
    """``n`` new actions against ``buffer`` at ``trial`` (default: one per buffered action),
    drawn from ``numpy.random.default_rng(seed)``, among ``allowed``."""
    at = len(buffer) if trial is None else trial
    return AskContext(post, n, buffer, at, np.random.default_rng(seed), allowed)
