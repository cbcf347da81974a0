"""The shipped continuous example has a safety radius: without one an unsafe flag removed the
flagged point alone, and on continuous features the next line could propose a gait a few
hundredths of the ranges from it (the loop never proposes that exact point again anyway)."""

from __future__ import annotations

import numpy as np

from gaitpref import load_config
from gaitpref.config import ExperimentConfig, parse_config


def _nearest_to_a_flag(config: ExperimentConfig, asks: int = 8) -> float:
    """The least distance (each feature scaled by its range) from the first trial, flagged
    unsafe, of the points the next ``asks`` queries propose, for a subject who prefers gaits
    near it: the loop only, no gait is made."""
    loop = config.make_loop(seed=3)
    lo = np.array([f.values[0] for f in config.space.features])
    span = np.array([f.span for f in config.space.features])
    q = loop.ask()
    loop.tell(q, [])
    flagged = q.actions[0]
    centre = (loop.space.point(flagged) - lo) / span
    loop.flag_unsafe(flagged)
    nearest = np.inf
    for _ in range(asks):
        q = loop.ask()
        for a in q.actions:
            nearest = min(
                nearest, float(np.linalg.norm((loop.space.point(a) - lo) / span - centre))
            )
        if q.buffer:  # the subject prefers gaits near the flagged one (its pain aside)
            a, b = q.actions[0], q.buffer[0]
            closer = np.linalg.norm((loop.space.points_of([a, b]) - lo) / span - centre, axis=1)
            loop.tell(q, [(a, b, "first" if closer[0] <= closer[1] else "second")])
        else:
            loop.tell(q, [])
    return nearest


def test_compass_continuous_3d_keeps_the_line_path_away_from_an_unsafe_flag() -> None:
    config = load_config("compass-continuous-3d")
    assert config.safety.unsafe_radius == 0.1 and config.subspace == "line"
    assert _nearest_to_a_flag(config) > 0.1
    # as shipped before, without the radius: the same asks come within it
    bare = parse_config(config.text.replace("[safety]\nunsafe_radius = 0.1\n", ""))
    assert bare.safety.unsafe_radius == 0
    assert 0 < _nearest_to_a_flag(bare) <= 0.1
