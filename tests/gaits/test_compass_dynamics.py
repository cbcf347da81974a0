"""The compass-gait equations against independent computations from the point masses."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from gaitpref.gaits import CompassGaitParams
from gaitpref.gaits.dynamics import (
    accelerations,
    coriolis,
    energy,
    gravity_vector,
    ground_reaction,
    mass_matrix,
    point_positions,
    swing_foot_height,
)
from gaitpref.gaits.impact import extended_mass_matrix

P = CompassGaitParams()
MASSES = {"hip": P.hip_mass, "stance_mass": P.leg_mass, "swing_mass": P.leg_mass}
angles = st.floats(-1.2, 1.2)
rates = st.floats(-3.0, 3.0)


def _velocities(q: np.ndarray, qd: np.ndarray, eps: float = 1e-6) -> dict[str, np.ndarray]:
    """Point-mass velocities by central differences of their positions along ``qd``."""
    ahead, behind = point_positions(P, q + eps * qd), point_positions(P, q - eps * qd)
    return {k: (ahead[k] - behind[k]) / (2 * eps) for k in MASSES}


def _kinetic(q: np.ndarray, qd: np.ndarray) -> float:
    vel = _velocities(q, qd)
    return 0.5 * sum(m * float(vel[k] @ vel[k]) for k, m in MASSES.items())


def _potential(q: np.ndarray) -> float:
    pos = point_positions(P, q)
    return P.gravity * sum(m * float(pos[k][1]) for k, m in MASSES.items())


@settings(max_examples=60, deadline=None)
@given(angles, angles)
def test_mass_matrix_is_symmetric_positive_definite(phi1: float, q2: float) -> None:
    d = mass_matrix(P, np.array([phi1, q2]))
    np.testing.assert_allclose(d, d.T, rtol=0, atol=1e-14)
    assert np.all(np.linalg.eigvalsh(d) > 0)


@settings(max_examples=40, deadline=None)
@given(angles, angles, rates, rates)
def test_mass_matrix_gives_the_point_masses_kinetic_energy(
    phi1: float, q2: float, w1: float, w2: float
) -> None:
    q, qd = np.array([phi1, q2]), np.array([w1, w2])
    expected = _kinetic(q, qd)
    np.testing.assert_allclose(0.5 * qd @ mass_matrix(P, q) @ qd, expected, rtol=1e-7, atol=1e-9)
    # and it is the angle block of the extended model built from the Jacobians
    np.testing.assert_allclose(extended_mass_matrix(P, q)[2:, 2:], mass_matrix(P, q), atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(angles, angles)
def test_gravity_vector_is_the_gradient_of_the_potential(phi1: float, q2: float) -> None:
    q, eps = np.array([phi1, q2]), 1e-6
    grad = [(_potential(q + eps * e) - _potential(q - eps * e)) / (2 * eps) for e in np.eye(2)]
    np.testing.assert_allclose(gravity_vector(P, q), grad, rtol=1e-6, atol=1e-7)


@settings(max_examples=40, deadline=None)
@given(angles, angles, rates, rates)
def test_coriolis_matches_the_lagrangian_identity(
    phi1: float, q2: float, w1: float, w2: float
) -> None:
    """``C qd = Ddot qd - 1/2 d/dq (qd^T D qd)``, derivatives by central differences."""
    q, qd, eps = np.array([phi1, q2]), np.array([w1, w2]), 1e-6
    d_dot = (mass_matrix(P, q + eps * qd) - mass_matrix(P, q - eps * qd)) / (2 * eps)
    grad = [
        (qd @ mass_matrix(P, q + eps * e) @ qd - qd @ mass_matrix(P, q - eps * e) @ qd) / (4 * eps)
        for e in np.eye(2)
    ]
    np.testing.assert_allclose(coriolis(P, q, qd), d_dot @ qd - np.array(grad), atol=1e-6)


def test_energy_is_conserved_without_torque() -> None:
    def rhs(_t: float, x: np.ndarray) -> np.ndarray:
        return np.concatenate([x[2:], accelerations(P, x[:2], x[2:], 0.0)])

    x0 = np.array([-0.2, 0.5, 0.8, -1.5])
    sol = solve_ivp(
        rhs, (0.0, 2.0), x0, method="DOP853", rtol=1e-11, atol=1e-12, t_eval=np.linspace(0, 2, 50)
    )
    e = energy(P, sol.y[:2].T, sol.y[2:].T)
    assert np.ptp(e) < 1e-8 * abs(e[0])
    # the independent energy (point masses) agrees along the way
    for x in sol.y.T[::10]:
        total = _kinetic(x[:2], x[2:]) + _potential(x[:2])
        np.testing.assert_allclose(total, e[0], rtol=1e-7)


def test_ground_reaction_is_the_rate_of_linear_momentum_plus_weight() -> None:
    def rhs(_t: float, x: np.ndarray) -> np.ndarray:
        return np.concatenate([x[2:], accelerations(P, x[:2], x[2:], 3.0)])

    sol = solve_ivp(rhs, (0.0, 0.3), np.array([0.1, -0.3, 0.6, -1.0]), method="DOP853",
                    rtol=1e-11, atol=1e-12, dense_output=True)  # fmt: skip

    def momentum(t: float) -> np.ndarray:
        x = sol.sol(t)
        vel = _velocities(x[:2], x[2:])
        return sum((m * vel[k] for k, m in MASSES.items()), np.zeros(2))

    t, eps = 0.15, 1e-5
    x = sol.sol(t)
    qdd = accelerations(P, x[:2], x[2:], 3.0)
    expected = (momentum(t + eps) - momentum(t - eps)) / (2 * eps) + np.array(
        [0.0, P.total_mass * P.gravity]
    )
    np.testing.assert_allclose(
        ground_reaction(P, x[:2], x[2:], qdd), expected, rtol=1e-5, atol=1e-4
    )


def test_swing_foot_height_is_zero_on_the_guard_and_matches_the_foot_position() -> None:
    q = np.array([0.07, -0.14])
    assert abs(swing_foot_height(P, q)) < 1e-15
    q = np.array([0.03, -0.2])
    np.testing.assert_allclose(swing_foot_height(P, q), point_positions(P, q)["swing_foot"][1])
