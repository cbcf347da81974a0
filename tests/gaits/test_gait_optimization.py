"""HZD gaits: optimality conditions, the full-model check, COT over step length, infeasibility."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from gaitpref.gaits import (
    CompassGaitParams,
    Gait,
    GaitLibrary,
    GaitLibraryError,
    GaitRequest,
    HZDSettings,
    SimulationError,
    cot_over_step_length,
    optimize_gait,
    simulate_gait,
)
from gaitpref.gaits.dynamics import swing_foot_height


def test_gait_meets_its_request_and_constraints(gait: Gait) -> None:
    assert gait.feasible and gait.status == 0
    assert math.isclose(gait.step_duration, 0.12 / 0.2, rel_tol=1e-4)
    assert 0 < gait.delta_squared < 1
    assert gait.min_normal_force > 0 and gait.max_friction_ratio < 0.6
    assert gait.cot > 0 and gait.alpha.shape == (1, 7)
    # the orbit starts on the surface q2 = h(phi1), at the start of the phase
    h, dh, _ = gait.constraint(gait.orbit_state[0])
    assert gait.orbit_state[0] == pytest.approx(gait.phase_start)
    assert gait.orbit_state[1] == pytest.approx(float(h), abs=1e-12)
    assert gait.orbit_state[3] == pytest.approx(float(dh) * gait.orbit_state[2], rel=1e-9)


def test_full_model_simulation_returns_to_the_orbit(gait: Gait, params: CompassGaitParams) -> None:
    sim = simulate_gait(gait, params, steps=5)
    assert sim.returned_to_orbit, sim.orbit_error
    assert sim.orbit_error[-1] < 1e-4
    assert sim.post_impact.shape == (5, 4)
    # the simulated loads agree with the optimizer's and are physical
    assert sim.min_normal_force == pytest.approx(gait.min_normal_force, rel=1e-3)
    assert sim.max_friction_ratio == pytest.approx(gait.max_friction_ratio, rel=1e-3)
    # each simulated step lasts the gait's duration
    steps = [sim.time[sim.step == k] for k in range(5)]
    durations = [s[-1] - s[0] for s in steps]
    np.testing.assert_allclose(durations, gait.step_duration, rtol=1e-4)
    # the swing foot is above ground late in each step (the exempt early part may scuff)
    late = (sim.state[:, 0] - gait.phase_start) / (gait.phase_end - gait.phase_start) > 0.6
    assert swing_foot_height(params, sim.state[late, :2]).min() > -1e-9
    assert sim.min_late_swing_height > -1e-9


def test_perturbed_start_contracts_towards_the_orbit(gait: Gait, params: CompassGaitParams) -> None:
    start = gait.orbit_state * np.array([1.0, 1.0, 1.03, 1.03])
    sim = simulate_gait(gait, params, steps=4, initial_state=start)
    assert np.all(np.diff(sim.orbit_error) < 0), sim.orbit_error


def test_cot_over_step_length_is_u_shaped_at_the_papers_speed(speed_library: GaitLibrary) -> None:
    curve = cot_over_step_length(speed_library)
    assert curve.feasible.all()
    best = int(np.argmin(curve.cot))
    assert 0 < best < len(curve.cot) - 1, curve.cot
    assert np.all(np.diff(curve.cot[: best + 1]) < 0)
    assert np.all(np.diff(curve.cot[best:]) > 0)
    assert curve.best_step_length == curve.step_length[best]


def test_cot_curve_needs_a_fixed_speed_library(duration_library: GaitLibrary) -> None:
    with pytest.raises(GaitLibraryError, match="fixed speed"):
        cot_over_step_length(duration_library)


@pytest.mark.parametrize(
    ("request_", "reason"),
    [
        (GaitRequest(0.13, speed=3.0), "normal force"),
        # too slow to walk: which of the two ways of saying so the solver ends on depends on
        # the machine's rounding (SLSQP's path; an AMD and an Intel machine differ here)
        (GaitRequest(0.13, step_duration=20.0), "forward progress|stops or falls back"),
    ],
)
def test_infeasible_requests_say_so_and_why(request_: GaitRequest, reason: str) -> None:
    result = optimize_gait(request_, settings=HZDSettings(max_iterations=60))
    assert not result.feasible
    assert result.message.startswith("infeasible")
    assert re.search(reason, result.message), result.message


def test_warm_start_reaches_the_same_gait(gait: Gait) -> None:
    again = optimize_gait(GaitRequest(0.12, speed=0.2), warm_start=gait)
    assert again.feasible
    assert again.cot == pytest.approx(gait.cot, rel=1e-4)
    with pytest.raises(ValueError, match="degree"):
        optimize_gait(GaitRequest(0.12, speed=0.2), settings=HZDSettings(degree=5), warm_start=gait)


def test_bad_requests_are_rejected_at_the_boundary() -> None:
    with pytest.raises(ValueError, match="exactly one"):
        GaitRequest(0.1)
    with pytest.raises(ValueError, match="exactly one"):
        GaitRequest(0.1, step_duration=1.0, speed=0.2)
    with pytest.raises(ValueError, match="step_length"):
        GaitRequest(-0.1, speed=0.2)
    with pytest.raises(ValueError, match="step length must be in"):
        optimize_gait(GaitRequest(2.5, speed=0.2))
    with pytest.raises(ValueError, match="degree"):
        HZDSettings(degree=2)
    with pytest.raises(ValueError, match="leg_com"):
        CompassGaitParams(leg_com=1.5)


def test_simulation_reports_a_fall(gait: Gait, params: CompassGaitParams) -> None:
    slow = gait.orbit_state * np.array([1.0, 1.0, 0.05, 0.05])
    with pytest.raises(SimulationError, match="no heel strike"):
        simulate_gait(gait, params, steps=1, initial_state=slow)
