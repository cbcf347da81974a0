"""Helpers shared by the session tests (imported by name; pytest puts this folder on sys.path)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gaitpref import Session

CONFIG = "exo-1d-step-length"

Drive = Callable[[Session, int], None]


def state_of(session: Session) -> tuple[np.ndarray, np.ndarray, object, object]:
    """Posterior mean and variance, the next query and the generator state."""
    post = session.posterior()
    query = session.next_query() if session.status == "active" else session.pending
    rng = session._state.loop.rng.bit_generator.state
    return np.asarray(post.mean).copy(), np.asarray(post.variance).copy(), query, rng
