"""Continuous-phase dynamics of the compass-gait biped in single support.

Lagrangian model (Westervelt et al. 2007, ch. 3; ``docs/gaits.md``, "The model") in the
coordinates ``q = (phi1, q2)``: ``phi1`` is the stance leg's angle from the vertical (positive
when the hip is ahead of the stance foot) and ``q2 = phi2 - phi1`` the hip angle, ``phi2`` the
swing leg's absolute angle.  With the stance foot at the origin, ``x`` forward and ``y`` up::

    hip        p_H = l (sin phi1, cos phi1)
    stance m   p_1 = a (sin phi1, cos phi1)
    swing m    p_2 = p_H - b (sin phi2, cos phi2)
    swing foot p_f = p_H - l (sin phi2, cos phi2)

and ``D(q2) qdd + C(q, qd) qd + G(q) = (0, u)`` with ``k = m l b sin q2``::

    d11 = m a^2 + m_H l^2 + m l^2 + m b^2 - 2 m l b cos q2
    d12 = m b^2 - m l b cos q2,         d22 = m b^2
    C qd = (2 k qd1 qd2 + k qd2^2, -k qd1^2)
    G    = (-g [(m a + m_H l + m l) sin phi1 - m b sin phi2],  g m b sin phi2)

The ground reaction at the stance foot is Newton's law for the point masses,
``F = sum_i m_i pdd_i + m_total g e_y``.

Notation: every function broadcasts over leading axes; ``q``, ``qd``, ``qdd`` are ``(..., 2)``,
``D`` is ``(..., 2, 2)``, positions and forces ``(..., 2)`` as ``(x, y)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from gaitpref.gaits.params import CompassGaitParams
from gaitpref.space import FloatArray


def _split(q: ArrayLike) -> tuple[FloatArray, FloatArray]:
    arr = np.asarray(q, dtype=np.float64)
    return arr[..., 0], arr[..., 1]


def mass_matrix(p: CompassGaitParams, q: ArrayLike) -> FloatArray:
    """``D(q2)``, symmetric positive definite, ``(..., 2, 2)``."""
    _, q2 = _split(q)
    m, mh, l, a, b = p.leg_mass, p.hip_mass, p.leg_length, p.foot_to_com, p.leg_com
    c = np.cos(q2)
    d11 = m * a**2 + mh * l**2 + m * l**2 + m * b**2 - 2.0 * m * l * b * c
    d12 = m * b**2 - m * l * b * c
    d22 = np.full_like(d11, m * b**2)
    return np.stack([np.stack([d11, d12], -1), np.stack([d12, d22], -1)], -2)


def coriolis(p: CompassGaitParams, q: ArrayLike, qd: ArrayLike) -> FloatArray:
    """The vector ``C(q, qd) qd``, ``(..., 2)``."""
    _, q2 = _split(q)
    w1, w2 = _split(qd)
    k = p.leg_mass * p.leg_length * p.leg_com * np.sin(q2)
    return np.stack([2.0 * k * w1 * w2 + k * w2**2, -k * w1**2], -1)


def gravity_vector(p: CompassGaitParams, q: ArrayLike) -> FloatArray:
    """``G(q) = dV/dq``, ``(..., 2)``."""
    phi1, q2 = _split(q)
    phi2 = phi1 + q2
    m, mh, l, a, b, g = (p.leg_mass, p.hip_mass, p.leg_length, p.foot_to_com, p.leg_com, p.gravity)
    g1 = -g * ((m * a + mh * l + m * l) * np.sin(phi1) - m * b * np.sin(phi2))
    g2 = g * m * b * np.sin(phi2)
    return np.stack([g1, g2], -1)


def potential_energy(p: CompassGaitParams, q: ArrayLike) -> FloatArray:
    """``V(q) = g sum_i m_i y_i`` with the stance foot at height 0."""
    phi1, q2 = _split(q)
    phi2 = phi1 + q2
    m, mh, l, a, b = p.leg_mass, p.hip_mass, p.leg_length, p.foot_to_com, p.leg_com
    return p.gravity * ((m * a + mh * l + m * l) * np.cos(phi1) - m * b * np.cos(phi2))


def energy(p: CompassGaitParams, q: ArrayLike, qd: ArrayLike) -> FloatArray:
    """Total mechanical energy ``qd^T D qd / 2 + V``."""
    w = np.asarray(qd, dtype=np.float64)
    kinetic = 0.5 * np.einsum("...i,...ij,...j->...", w, mass_matrix(p, q), w)
    return np.asarray(kinetic + potential_energy(p, q))


def accelerations(p: CompassGaitParams, q: ArrayLike, qd: ArrayLike, u: ArrayLike) -> FloatArray:
    """``qdd`` solving ``D qdd = (0, u) - C qd - G``, ``(..., 2)``."""
    rhs = -coriolis(p, q, qd) - gravity_vector(p, q)
    rhs[..., 1] += np.asarray(u, dtype=np.float64)
    return np.asarray(np.linalg.solve(mass_matrix(p, q), rhs[..., None])[..., 0])


def hip_torque(p: CompassGaitParams, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
    """Inverse dynamics of the actuated row: ``u = (D qdd + C qd + G)_2``."""
    lhs = np.einsum("...ij,...j->...i", mass_matrix(p, q), np.asarray(qdd, dtype=np.float64))
    return np.asarray((lhs + coriolis(p, q, qd) + gravity_vector(p, q))[..., 1])


def unactuated_residual(
    p: CompassGaitParams, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike
) -> FloatArray:
    """``(D qdd + C qd + G)_1``, zero along any motion of the model."""
    lhs = np.einsum("...ij,...j->...i", mass_matrix(p, q), np.asarray(qdd, dtype=np.float64))
    return np.asarray((lhs + coriolis(p, q, qd) + gravity_vector(p, q))[..., 0])


def _unit(angle: FloatArray) -> FloatArray:
    return np.stack([np.sin(angle), np.cos(angle)], -1)


def _unit_dot(angle: FloatArray) -> FloatArray:
    return np.stack([np.cos(angle), -np.sin(angle)], -1)


def _unit_ddot(angle: FloatArray) -> FloatArray:
    return -_unit(angle)


def point_positions(p: CompassGaitParams, q: ArrayLike) -> dict[str, FloatArray]:
    """Positions of the hip, the two leg masses and the swing foot (stance foot at 0)."""
    phi1, q2 = _split(q)
    phi2 = phi1 + q2
    hip = p.leg_length * _unit(phi1)
    return {
        "hip": hip,
        "stance_mass": p.foot_to_com * _unit(phi1),
        "swing_mass": hip - p.leg_com * _unit(phi2),
        "swing_foot": hip - p.leg_length * _unit(phi2),
    }


def swing_foot_height(p: CompassGaitParams, q: ArrayLike) -> FloatArray:
    """``l (cos phi1 - cos phi2)``: zero at a heel strike, negative when the foot is underground."""
    phi1, q2 = _split(q)
    return np.asarray(p.leg_length * (np.cos(phi1) - np.cos(phi1 + q2)))


def _point_accelerations(
    p: CompassGaitParams, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike
) -> dict[str, FloatArray]:
    phi1, q2 = _split(q)
    w1, w2 = _split(qd)
    a1, a2 = _split(qdd)
    phi2, w_sw, a_sw = phi1 + q2, w1 + w2, a1 + a2

    def rot(angle: FloatArray, w: FloatArray, acc: FloatArray) -> FloatArray:
        # second derivative of (sin, cos)(angle)
        return acc[..., None] * _unit_dot(angle) + (w**2)[..., None] * _unit_ddot(angle)

    hip = p.leg_length * rot(phi1, w1, a1)
    return {
        "hip": hip,
        "stance_mass": p.foot_to_com * rot(phi1, w1, a1),
        "swing_mass": hip - p.leg_com * rot(phi2, w_sw, a_sw),
    }


def ground_reaction(
    p: CompassGaitParams, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike
) -> FloatArray:
    """Force of the ground on the stance foot, ``(..., 2)`` as (tangential, normal)."""
    acc = _point_accelerations(p, q, qd, qdd)
    force = (
        p.hip_mass * acc["hip"] + p.leg_mass * acc["stance_mass"] + p.leg_mass * acc["swing_mass"]
    )
    force[..., 1] += p.total_mass * p.gravity
    return force
