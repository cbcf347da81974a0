"""Heel-strike map, Bezier polynomials, impact invariance and the zero dynamics."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from gaitpref.gaits import CompassGaitParams, Gait, bezier
from gaitpref.gaits.dynamics import (
    energy,
    gravity_vector,
    hip_torque,
    point_positions,
    unactuated_residual,
)
from gaitpref.gaits.impact import angular_momentum, impact, point_jacobians
from gaitpref.gaits.zero_dynamics import StepGeometry, guard_angle, step_profile

P = CompassGaitParams()


def _pre_impact(step_length: float, w1: float, w2: float) -> tuple[np.ndarray, np.ndarray]:
    th0 = guard_angle(P, step_length)
    return np.array([th0, -2 * th0]), np.array([w1, w2])


@settings(max_examples=40, deadline=None)
@given(st.floats(0.05, 0.6), st.floats(0.05, 2.0), st.floats(-2.0, 2.0))
def test_impact_conserves_angular_momentum_about_the_impact_point(
    step_length: float, w1: float, w2: float
) -> None:
    q, qd = _pre_impact(step_length, w1, w2)
    foot = point_positions(P, q)["swing_foot"]
    hit = impact(P, q, qd)
    before = angular_momentum(P, q, np.concatenate([[0.0, 0.0], qd]), foot)
    after = angular_momentum(P, q, hit.extended_velocity, foot)
    np.testing.assert_allclose(after, before, rtol=1e-10, atol=1e-12)
    # the striking foot stops; kinetic energy is lost, not gained
    np.testing.assert_allclose(
        point_jacobians(P, q)["swing_foot"] @ hit.extended_velocity, 0, atol=1e-12
    )
    assert energy(P, hit.q, hit.qd) <= energy(P, q, qd) + 1e-12


def test_impact_relabels_the_legs() -> None:
    q, qd = _pre_impact(0.12, 0.3, 0.1)
    hit = impact(P, q, qd)
    np.testing.assert_allclose(hit.q, [-q[0], -q[1]])  # new stance leg was the swing leg
    # the relabelled velocities describe the same motion: the old stance leg's absolute rate
    np.testing.assert_allclose(hit.qd[0] + hit.qd[1], hit.extended_velocity[2], atol=1e-14)


def test_impact_of_a_walking_step_is_physical(gait: Gait) -> None:
    q = gait.orbit_state[:2] * -1  # the pre-impact configuration mirrors the post-impact one
    _, dh, _ = gait.constraint(gait.phase_end)
    hit = impact(P, q, np.array([1.0, float(dh)]) * 0.3)
    assert hit.impulse[1] > 0, "normal impulse must push up"
    assert hit.lift_off_velocity[1] > 0, "the old stance foot must lift off"


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=4, max_size=8), st.floats(0.0, 1.0))
def test_bezier_derivatives_match_finite_differences(coef: list[float], tau: float) -> None:
    eps = 1e-6
    for order in (1, 2):
        fd = (
            bezier.evaluate(coef, [tau + eps], order - 1)
            - bezier.evaluate(coef, [tau - eps], order - 1)
        ) / (2 * eps)
        np.testing.assert_allclose(bezier.evaluate(coef, [tau], order), fd, rtol=1e-5, atol=1e-5)
    m = len(coef) - 1
    np.testing.assert_allclose(bezier.evaluate(coef, [0.0, 1.0]), [coef[0], coef[-1]], atol=1e-14)
    np.testing.assert_allclose(bezier.evaluate(coef, [0.0], 1), m * (coef[1] - coef[0]), atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    st.floats(0.05, 0.4),
    st.lists(st.floats(-1.5, 1.5), min_size=4, max_size=4),
    st.floats(0.05, 1.0),
)
def test_bezier_end_conditions_make_the_constraint_impact_invariant(
    step_length: float, shape: list[float], rate: float
) -> None:
    """A pre-impact state on the surface maps to a post-impact state on the surface."""
    geo = StepGeometry.create(P, step_length)
    alpha = geo.complete(np.asarray(shape) * geo.span)
    span, m = geo.span, alpha.size - 1
    h_end = bezier.evaluate(alpha, [1.0])[0]
    dh_end = bezier.evaluate(alpha, [1.0], 1)[0] / span
    # on the guard: swing foot on the ground, ahead of the stance foot
    assert abs(2 * geo.theta_end + h_end) < 1e-14
    hit = impact(P, np.array([geo.theta_end, h_end]), rate * np.array([1.0, dh_end]))
    h_start = bezier.evaluate(alpha, [0.0])[0]
    dh_start = bezier.evaluate(alpha, [0.0], 1)[0] / span
    np.testing.assert_allclose(hit.q, [geo.theta_start, h_start], atol=1e-14)
    if abs(hit.qd[0]) > 1e-9:
        np.testing.assert_allclose(hit.qd[1] / hit.qd[0], dh_start, rtol=1e-8, atol=1e-10)
    assert m == 6


def test_zero_dynamics_profile_obeys_the_full_equations(gait: Gait) -> None:
    geo = StepGeometry.create(P, gait.step_length)
    pr = step_profile(P, geo, gait.alpha[0], 1.0, 401)
    rate = np.sqrt(2 * pr.periodic_zeta_minus) / pr.inertia[-1]
    pr = step_profile(P, geo, gait.alpha[0], rate, 401)
    q = np.stack([pr.theta, pr.q2], -1)
    qd = np.stack([pr.thetad, pr.q2d], -1)
    _, dh, ddh = gait.constraint(pr.theta)
    qdd = np.stack([pr.thetadd, ddh * pr.thetad**2 + dh * pr.thetadd], -1)
    # the unactuated row holds, the torque is the actuated row's, the orbit is periodic
    scale = P.total_mass * P.gravity * P.leg_length
    assert np.abs(unactuated_residual(P, q, qd, qdd)).max() < 1e-9 * scale
    np.testing.assert_allclose(hip_torque(P, q, qd, qdd), pr.torque, atol=1e-12)
    assert abs(pr.periodicity_residual) < 1e-12
    # d(zeta)/dtheta = -I G1: finite differences of the quadrature against the integrand
    g1 = gravity_vector(P, q)[:, 0]
    slope = np.gradient(pr.zeta, pr.theta, edge_order=2)
    np.testing.assert_allclose(slope, -pr.inertia * g1, rtol=1e-4, atol=1e-5 * np.abs(slope).max())
