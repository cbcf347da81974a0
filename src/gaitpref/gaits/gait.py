"""Records of the HZD gait problem: what is asked (:class:`GaitRequest`), how it is posed
(:class:`HZDSettings`) and what comes back (:class:`Gait`).

A gait is the Bezier virtual constraint ``q2 = B(alpha, tau)``, ``tau = (phi1 - phase_start) /
(phase_end - phase_start)`` (``docs/gaits.md``, "The HZD formulation"), and the periodic orbit
it induces on the hybrid zero dynamics.  ``alpha`` is stored as a matrix with one row per output
(one here: the hip angle), as exoskeleton gait libraries do.

Notation: ``M`` Bezier degree; ``alpha`` is ``1 x (M + 1)``; ``orbit_state`` is
``(phi1, q2, phi1d, q2d)`` at the start of a step, right after the impact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gaitpref.gaits import bezier
from gaitpref.space import FloatArray


def _positive(name: str, value: float) -> None:
    if not isinstance(value, int | float) or not math.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be a positive number, got {value!r}")


@dataclass(frozen=True)
class GaitRequest:
    """A step length and exactly one of a forward speed or a step duration."""

    step_length: float
    step_duration: float | None = None
    speed: float | None = None

    def __post_init__(self) -> None:
        _positive("step_length", self.step_length)
        if (self.step_duration is None) == (self.speed is None):
            raise ValueError("give exactly one of step_duration and speed")
        if self.step_duration is not None:
            _positive("step_duration", self.step_duration)
        if self.speed is not None:
            _positive("speed", self.speed)

    @property
    def target_duration(self) -> float:
        """The step duration the gait must have: ``T`` or ``L / v``."""
        if self.step_duration is not None:
            return float(self.step_duration)
        assert self.speed is not None
        return float(self.step_length / self.speed)


@dataclass(frozen=True)
class HZDSettings:
    """The optimization's formulation: Bezier degree, grids, physical margins and solver options.

    Clearance: the swing foot of a rigid-legged compass gait must pass through the ground near
    mid-stance (the legs are equally long), so only ``tau >= clearance_start`` is constrained; there
    the swing foot must be at least ``clearance * step_length * (1 - tau) / (1 - clearance_start)``
    above the ground (a ramp that reaches zero at heel strike).
    """

    degree: int = 6
    n_points: int = 201
    n_constraint_points: int = 41
    clearance_start: float = 0.6
    clearance: float = 0.01
    friction_coefficient: float = 0.6
    min_normal_force: float = 0.2  # fraction of body weight
    max_delta_squared: float = 0.999
    min_phase_speed: float = 0.1  # fraction of the step's mean stance-angle velocity
    max_iterations: int = 300
    tolerance: float = 1e-10
    feasibility_tolerance: float = 1e-6
    smoothing: float = 1e-3  # of |u qd| in the objective (J/rad); the reported COT is exact

    def __post_init__(self) -> None:
        if not isinstance(self.degree, int) or not 3 <= self.degree <= 12:
            raise ValueError(f"degree must be an integer in 3..12, got {self.degree!r}")
        if not isinstance(self.n_points, int) or self.n_points < 5:
            raise ValueError(f"n_points must be an integer >= 5, got {self.n_points!r}")
        if not 3 <= self.n_constraint_points <= self.n_points:
            raise ValueError(
                f"n_constraint_points must be in 3..n_points, got {self.n_constraint_points}"
            )
        if not 0.0 <= self.clearance_start < 1.0:
            raise ValueError(f"clearance_start must be in [0, 1), got {self.clearance_start}")
        if not 0.0 < self.max_delta_squared < 1.0:
            raise ValueError(f"max_delta_squared must be in (0, 1), got {self.max_delta_squared}")
        for name in ("clearance", "min_normal_force", "min_phase_speed"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0:
                raise ValueError(f"{name} must be >= 0, got {value}")
        for name in ("friction_coefficient", "tolerance", "feasibility_tolerance", "smoothing"):
            _positive(name, getattr(self, name))
        if self.max_iterations < 1:
            raise ValueError(f"max_iterations must be >= 1, got {self.max_iterations}")

    def to_dict(self) -> dict[str, float | int]:
        return {name: getattr(self, name) for name in self.__dataclass_fields__}


@dataclass(frozen=True, eq=False)
class Gait:
    """An optimized gait: virtual constraint, periodic orbit, cost and the solver's verdict.

    ``feasible`` is true only when the solver converged and every constraint holds at the
    returned point; otherwise ``message`` names what failed.  An infeasible gait is kept (never
    silently replaced) so that a library can say which requests had no gait.
    """

    step_length: float
    step_duration: float
    alpha: FloatArray  # (1, M + 1)
    phase_start: float
    phase_end: float
    orbit_state: FloatArray  # (4,) post-impact (phi1, q2, phi1d, q2d)
    cot: float
    delta_squared: float
    feasible: bool
    status: int
    message: str
    min_normal_force: float  # N, along the orbit
    max_friction_ratio: float  # |F_t| / F_n along the orbit and at impact

    def __post_init__(self) -> None:
        for name in ("alpha", "orbit_state"):
            arr = np.array(getattr(self, name), dtype=np.float64)  # a private, read-only copy
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)

    @property
    def degree(self) -> int:
        return int(self.alpha.shape[-1] - 1)

    @property
    def speed(self) -> float:
        return self.step_length / self.step_duration

    def tau(self, phi1: FloatArray | float) -> FloatArray:
        """Phase ``tau(phi1)`` (not clipped: the polynomial extends past the step's ends)."""
        return np.asarray(
            (np.asarray(phi1) - self.phase_start) / (self.phase_end - self.phase_start)
        )

    def constraint(self, phi1: FloatArray | float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``h``, ``dh/dphi1`` and ``d2h/dphi1^2`` of the virtual constraint at ``phi1``."""
        span = self.phase_end - self.phase_start
        tau = self.tau(phi1)
        coef = self.alpha[0]
        return (
            bezier.evaluate(coef, tau, 0),
            bezier.evaluate(coef, tau, 1) / span,
            bezier.evaluate(coef, tau, 2) / span**2,
        )
