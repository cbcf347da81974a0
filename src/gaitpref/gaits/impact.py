"""Heel strike: rigid plastic impact in extended coordinates, then the legs swap roles.

Westervelt et al. (2007), Section 3.4.2 (``docs/gaits.md``, "The model").  In extended coordinates
``q_e = (x, y, phi1, q2)`` (``(x, y)`` the stance foot) every point mass ``i`` sits at
``(x, y) + r_i(q)``, so ``D_e = sum_i m_i J_i^T J_i`` with ``J_i = [I_2, dr_i/dq]``.  With ``J`` the
swing foot's Jacobian, the impulsive force ``F`` and the post-impact velocity solve::

    [ D_e  -J^T ] [ qd_e+ ]   [ D_e qd_e- ]
    [ J     0   ] [ F     ] = [ 0         ]

(the swing foot sticks; the old stance foot is free).  The relabelling that follows makes the
old swing leg the new stance leg: ``phi1+ = phi1 + q2``, ``q2+ = -q2`` and likewise for velocities.
A physical impact needs a positive normal impulse ``F_y``, ``|F_x| <= mu F_y`` and an upward
velocity ``yd+`` of the old stance foot (it lifts off).

Notation: ``q``, ``qd`` are ``(2,)``; ``D_e`` is ``(4, 4)``; ``J`` is ``(2, 4)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from gaitpref.gaits.dynamics import point_positions
from gaitpref.gaits.params import CompassGaitParams
from gaitpref.space import FloatArray


def _du(angle: float) -> FloatArray:
    return np.array([np.cos(angle), -np.sin(angle)])


def point_jacobians(p: CompassGaitParams, q: ArrayLike) -> dict[str, FloatArray]:
    """``J_i`` (``2 x 4``) of the hip, both leg masses and the swing foot in ``q_e``."""
    phi1, q2 = (float(v) for v in np.asarray(q, dtype=np.float64))
    phi2 = phi1 + q2
    eye = np.eye(2)
    zero = np.zeros(2)

    def jac(d_phi1: FloatArray, d_q2: FloatArray) -> FloatArray:
        return np.column_stack([eye, d_phi1, d_q2])

    hip = p.leg_length * _du(phi1)
    swing_mass = -p.leg_com * _du(phi2)
    swing_foot = -p.leg_length * _du(phi2)
    return {
        "hip": jac(hip, zero),
        "stance_mass": jac(p.foot_to_com * _du(phi1), zero),
        "swing_mass": jac(hip + swing_mass, swing_mass),
        "swing_foot": jac(hip + swing_foot, swing_foot),
    }


def extended_mass_matrix(p: CompassGaitParams, q: ArrayLike) -> FloatArray:
    """``D_e(q)``, ``4 x 4``; its lower-right block is the single-support ``D(q)``."""
    jac = point_jacobians(p, q)
    masses = {"hip": p.hip_mass, "stance_mass": p.leg_mass, "swing_mass": p.leg_mass}
    return sum((m * jac[k].T @ jac[k] for k, m in masses.items()), np.zeros((4, 4)))


def relabel(q: ArrayLike, qd: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Swap the legs' roles: ``(phi1 + q2, -q2)`` for positions and for velocities."""
    swap = np.array([[1.0, 1.0], [0.0, -1.0]])
    return swap @ np.asarray(q, dtype=np.float64), swap @ np.asarray(qd, dtype=np.float64)


@dataclass(frozen=True, eq=False)
class ImpactResult:
    """State right after a heel strike (already relabelled) and the impact's diagnostics."""

    q: FloatArray  # (2,) relabelled positions
    qd: FloatArray  # (2,) relabelled velocities
    impulse: FloatArray  # (2,) ground impulse on the striking foot, (tangential, normal)
    lift_off_velocity: FloatArray  # (2,) velocity of the old stance foot just after impact
    extended_velocity: FloatArray  # (4,) qd_e+ before relabelling

    @property
    def friction_ratio(self) -> float:
        """``|F_x| / F_y`` of the impulse (infinite unless ``F_y > 0``)."""
        fx, fy = float(self.impulse[0]), float(self.impulse[1])
        return abs(fx) / fy if fy > 0 else float("inf")


def impact(p: CompassGaitParams, q: ArrayLike, qd: ArrayLike) -> ImpactResult:
    """Apply the plastic impact at configuration ``q`` (on the guard) to velocity ``qd``."""
    q_arr = np.asarray(q, dtype=np.float64)
    qd_e_minus = np.concatenate([np.zeros(2), np.asarray(qd, dtype=np.float64)])
    d_e = extended_mass_matrix(p, q_arr)
    j = point_jacobians(p, q_arr)["swing_foot"]
    lhs = np.block([[d_e, -j.T], [j, np.zeros((2, 2))]])
    rhs = np.concatenate([d_e @ qd_e_minus, np.zeros(2)])
    sol = np.linalg.solve(lhs, rhs)
    qd_e_plus, impulse = sol[:4], sol[4:]
    q_new, qd_new = relabel(q_arr, qd_e_plus[2:])
    return ImpactResult(
        q=q_new,
        qd=qd_new,
        impulse=impulse,
        lift_off_velocity=qd_e_plus[:2].copy(),
        extended_velocity=qd_e_plus,
    )


def angular_momentum(
    p: CompassGaitParams, q: ArrayLike, qd_e: ArrayLike, about: ArrayLike
) -> float:
    """Angular momentum of the point masses about ``about`` (world frame, stance foot at 0).

    ``qd_e`` is the extended velocity ``(xd, yd, phi1d, q2d)``; the stance foot is at the origin.
    """
    pos = point_positions(p, q)
    jac = point_jacobians(p, q)
    masses = {"hip": p.hip_mass, "stance_mass": p.leg_mass, "swing_mass": p.leg_mass}
    centre = np.asarray(about, dtype=np.float64)
    w = np.asarray(qd_e, dtype=np.float64)
    total = 0.0
    for name, m in masses.items():
        r = pos[name] - centre
        v = jac[name] @ w
        total += m * float(r[0] * v[1] - r[1] * v[0])
    return total
