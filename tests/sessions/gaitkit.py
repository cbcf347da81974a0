"""A quick stand-in gait generator for tests of gaits on demand (no optimisation).

``FakeSteps`` makes a "gait" over a ``step_length`` feature (and any labels) at once: feasible
when the step length is at least ``FakeSteps.below`` (a class setting a test may change), and it
records every call with the step length of its warm start, so tests can see what was made and
from where.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import numpy as np

from gaitpref import Session
from gaitpref.gaits import Gait, GaitGenerator, register_generator
from gaitpref.space import FloatArray

NAME = "test-steps"


class FakeSteps(GaitGenerator):
    name: ClassVar[str] = NAME
    below: ClassVar[float] = 0.3
    calls: ClassVar[list[tuple[float, float | None]]] = []  # (step length, warm start's)

    def __init__(self, features: Sequence[str], settings: Mapping[str, Any]) -> None:
        self.features = tuple(features)
        self.k = self.features.index("step_length")

    def settings(self) -> dict[str, Any]:
        return {"below": self.below}

    def parameters(self, vector: FloatArray) -> dict[str, float]:
        return {"step_length": float(self.check(vector)[self.k])}

    def gait_id(self, vector: FloatArray) -> str:
        return "-".join(
            f"{n[0].upper()}{v:.3f}" for n, v in zip(self.features, vector, strict=True)
        )

    def make(self, vector: FloatArray, warm_start: Gait | None = None) -> Gait:
        length = self.parameters(vector)["step_length"]
        FakeSteps.calls.append((length, None if warm_start is None else warm_start.step_length))
        ok = length >= self.below
        return Gait(
            step_length=length,
            step_duration=1.0,
            alpha=np.full((1, 7), length),
            phase_start=-0.1,
            phase_end=0.1,
            orbit_state=np.zeros(4),
            cot=(length - 0.5) ** 2,
            delta_squared=0.9,
            feasible=ok,
            status=0 if ok else 8,
            message="optimal: fake" if ok else f"infeasible: step length {length:.3f} too short",
            min_normal_force=100.0,
            max_friction_ratio=0.1,
        )


register_generator(NAME, FakeSteps)


def prefer_short_steps(s: Session, queries: int) -> None:
    """Answer ``queries`` queries as a subject who prefers the shorter step (on a grid or the
    line path): drives the loop towards the short steps, which have no gait."""
    for _ in range(queries):
        q = s.next_query()
        a, b = q.actions[0], (q.buffer[0] if q.buffer else None)
        if b is None or b == a:
            s.answer(q.id, [])
            continue
        shorter = q.points[0][0] < s.space.points[b][0]
        s.answer(q.id, [(a, b, "first" if shorter else "second")])


CONFIG = f"""
name = "on-demand-1d"
[space.step_length]
min = 0.0
max = 1.0
num = 21
unit = "m"
[space.step_width]
values = [0.2, 0.3]
[gaits]
generator = "{NAME}"
avoid_radius = 0.1
[model]
lengthscale = 0.2
signal_variance = 0.005
noise = 0.02
fit = "fixed"
[cospar]
seed = 4
strategy = "self-sparring"
"""

#: the fake over a continuous step length (the line path) and a continuous width label
CONTINUOUS = (
    CONFIG.replace("num = 21\n", "").replace("values = [0.2, 0.3]", "min = 0.2\nmax = 0.3")
    + "line_points = 12\n"
)

#: the real compass-hzd generator on a grid whose shortest step (0.02 m) has no gait at 0.2 m/s;
#: with its seed, a subject who always prefers the new gait reaches it by the third query
COMPASS = """
name = "compass-on-demand"
[space.step_length]
values = [0.02, 0.04, 0.06, 0.08, 0.10, 0.12, 0.14]
unit = "m"
[gaits]
generator = "compass-hzd"
speed = 0.2
avoid_radius = 0.0
[model]
lengthscale = 0.03
signal_variance = 1e-4
noise = 0.01
fit = "fixed"
[cospar]
strategy = "self-sparring"
seed = 3
"""
