"""Full-model check of a gait: the two-degree-of-freedom hybrid model under output feedback.

Westervelt et al. (2007), ch. 5: with ``y = q2 - h(phi1)`` and ``D qdd = (0, u) - C qd - G``,
``qdd = a + b u`` (``a = D^-1 (-C qd - G)``, ``b = D^-1 e_2``) and
``ydd = qdd_2 - h' qdd_1 - h'' phi1d^2``.  Feedback linearization with PD,
``ydd = -K_p y - K_d yd``, gives ``u = (-K_p y - K_d yd - a_2 + h' a_1 + h'' phi1d^2) /
(b_2 - h' b_1)``; the decoupling term equals ``I(phi1) / det D`` and is positive along a gait.

A step ends at heel strike: ``phi1 + phi2 = 0`` crossed upward (the swing foot comes down ahead).
Because a rigid compass gait scuffs near mid-stance, the guard is armed only once the phase
passes ``arm_at`` (the optimizer's ``clearance_start``).  The impact map and relabelling of
:mod:`gaitpref.gaits.impact` start the next step.  The result reports each step's post-impact
state against the gait's orbit, the minimum normal force and the maximum friction ratio.

Notation: state ``x = (phi1, q2, phi1d, q2d)``, ``(4,)``; ``K`` samples over all steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from gaitpref.errors import SimulationError
from gaitpref.gaits.dynamics import (
    coriolis,
    gravity_vector,
    ground_reaction,
    mass_matrix,
    swing_foot_height,
)
from gaitpref.gaits.gait import Gait
from gaitpref.gaits.impact import impact
from gaitpref.gaits.params import CompassGaitParams
from gaitpref.space import FloatArray, IntArray


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """Samples of a multi-step simulation and its verdict against the gait's orbit."""

    time: FloatArray  # (K,)
    state: FloatArray  # (K, 4) in each step's own coordinates
    step: IntArray  # (K,) step number of each sample
    torque: FloatArray  # (K,)
    force: FloatArray  # (K, 2) ground reaction (tangential, normal)
    post_impact: FloatArray  # (steps, 4) state after each heel strike
    orbit_error: FloatArray  # (steps,) max-abs distance of post_impact to the gait's orbit
    impulse_ratio: FloatArray  # (steps,) |F_t| / F_n of each impact impulse
    min_late_swing_height: float  # m, after the guard is armed (0 at strike; < 0: penetration)
    tolerance: float

    @property
    def returned_to_orbit(self) -> bool:
        return bool(self.orbit_error[-1] < self.tolerance)

    @property
    def min_normal_force(self) -> float:
        return float(self.force[:, 1].min())

    @property
    def max_friction_ratio(self) -> float:
        fn = self.force[:, 1]
        path = float(np.max(np.abs(self.force[:, 0]) / fn)) if fn.min() > 0 else math.inf
        return max(path, float(self.impulse_ratio.max()))

    def leg_trajectories(self) -> dict[str, FloatArray]:
        """Angles and velocities of one physical leg (the first step's stance leg), per sample.

        ``leg`` is its absolute angle from the vertical; ``hip`` the angle of this leg relative
        to the other one.  The legs swap roles at every impact, so on odd steps this leg swings.
        """
        odd = (self.step % 2 == 1)[:, None]
        phi1, q2 = self.state[:, :2].T
        w1, w2 = self.state[:, 2:].T
        leg = np.where(odd, np.stack([phi1 + q2, w1 + w2], -1), np.stack([phi1, w1], -1))
        hip = np.where(odd, np.stack([q2, w2], -1), np.stack([-q2, -w2], -1))
        return {"leg": leg[:, 0], "leg_rate": leg[:, 1], "hip": hip[:, 0], "hip_rate": hip[:, 1]}


def _control(
    p: CompassGaitParams, gait: Gait, x: FloatArray, kp: float, kd: float
) -> tuple[float, FloatArray]:
    q, qd = x[:2], x[2:]
    h, dh, ddh = (float(v) for v in gait.constraint(x[0]))
    dmat = mass_matrix(p, q)
    rhs = -coriolis(p, q, qd) - gravity_vector(p, q)
    sol = np.linalg.solve(dmat, np.column_stack([rhs, [0.0, 1.0]]))
    a, b = sol[:, 0], sol[:, 1]
    y, yd = q[1] - h, qd[1] - dh * qd[0]
    u = (-kp * y - kd * yd - a[1] + dh * a[0] + ddh * qd[0] ** 2) / (b[1] - dh * b[0])
    return float(u), a + b * u


def simulate_gait(
    gait: Gait,
    params: CompassGaitParams | None = None,
    steps: int = 5,
    initial_state: FloatArray | None = None,
    natural_frequency: float = 20.0,
    arm_at: float = 0.6,
    samples_per_step: int = 200,
    tolerance: float = 1e-4,
) -> SimulationResult:
    """Simulate ``steps`` steps from ``initial_state`` (default: the gait's orbit).

    Raises :class:`SimulationError` if a step does not end in a heel strike within ten times the
    gait's step duration (a fall or a stall), or if a heel strike is not physical.
    """
    p = params or CompassGaitParams()
    if steps < 1:
        raise ValueError(f"steps must be >= 1, got {steps}")
    kp, kd = natural_frequency**2, 2.0 * natural_frequency
    x = np.array(gait.orbit_state if initial_state is None else initial_state, dtype=np.float64)
    if x.shape != (4,) or not np.all(np.isfinite(x)):
        raise ValueError(f"initial_state must be 4 finite numbers (phi1, q2, phi1d, q2d), got {x}")
    arm_angle = gait.phase_start + arm_at * (gait.phase_end - gait.phase_start)
    horizon = 10.0 * gait.step_duration

    def rhs(_t: float, s: FloatArray) -> FloatArray:
        _u, qdd = _control(p, gait, s, kp, kd)
        return np.concatenate([s[2:], qdd])

    def armed(_t: float, s: FloatArray) -> float:
        return float(s[0] - arm_angle)

    def strike(_t: float, s: FloatArray) -> float:
        return float(2.0 * s[0] + s[1])

    armed.terminal, armed.direction = True, 1.0  # type: ignore[attr-defined]
    strike.terminal, strike.direction = True, 1.0  # type: ignore[attr-defined]

    t0 = 0.0
    times, states, labels, posts, ratios, late = [], [], [], [], [], []
    for k in range(steps):
        start = t0
        for event in (armed, strike):
            sol = solve_ivp(
                rhs, (t0, start + horizon), x, method="DOP853", events=event,
                rtol=1e-10, atol=1e-12, dense_output=True,
            )  # fmt: skip
            if sol.status != 1:
                raise SimulationError(
                    f"step {k + 1}: no heel strike within {horizon:.2f} s "
                    f"(phi1 = {sol.y[0, -1]:.4f} rad; the walker stalled or fell)"
                )
            grid = np.linspace(t0, sol.t[-1], samples_per_step // 2)
            times.append(grid)
            states.append(sol.sol(grid).T)
            if event is strike:
                late.append(swing_foot_height(p, states[-1][:, :2]).min())
            labels.append(np.full(grid.size, k))
            t0, x = float(sol.t[-1]), sol.y[:, -1].copy()
        hit = impact(p, x[:2], x[2:])
        if hit.impulse[1] <= 0 or hit.lift_off_velocity[1] <= 0:
            raise SimulationError(
                f"step {k + 1}: non-physical impact (normal impulse {hit.impulse[1]:.3g} N s, "
                f"lift-off speed {hit.lift_off_velocity[1]:.3g} m/s)"
            )
        ratios.append(abs(hit.impulse[0]) / hit.impulse[1])
        x = np.concatenate([hit.q, hit.qd])
        posts.append(x.copy())

    state = np.concatenate(states)
    torque, force = _loads(p, gait, state, kp, kd)
    post = np.array(posts)
    return SimulationResult(
        time=np.concatenate(times),
        state=state,
        step=np.concatenate(labels).astype(np.intp),
        torque=torque,
        force=force,
        post_impact=post,
        orbit_error=np.max(np.abs(post - gait.orbit_state[None, :]), axis=1),
        impulse_ratio=np.array(ratios),
        min_late_swing_height=float(min(late)),
        tolerance=tolerance,
    )


def _loads(
    p: CompassGaitParams, gait: Gait, state: FloatArray, kp: float, kd: float
) -> tuple[FloatArray, FloatArray]:
    torque = np.empty(len(state))
    qdd = np.empty((len(state), 2))
    for i, s in enumerate(state):
        torque[i], qdd[i] = _control(p, gait, s, kp, kd)
    return torque, ground_reaction(p, state[:, :2], state[:, 2:], qdd)
