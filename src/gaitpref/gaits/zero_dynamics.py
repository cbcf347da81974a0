"""Hybrid zero dynamics of the compass gait under a Bezier virtual constraint on the hip angle.

Westervelt, Grizzle et al. (2007), ch. 5-6 (``docs/gaits.md``, "The HZD formulation").  The
phase is the stance angle, ``theta = phi1``, ``tau = (theta - theta_s) / (theta_e - theta_s)``,
and the output ``y = q2 - h(theta)``, ``h(theta) = B(alpha, tau)``.  On ``y = 0`` the unactuated
row of the dynamics reduces to one degree of freedom.  Its generalized momentum is the angular
momentum about the stance foot, ``sigma = I(theta) thetad`` with ``I = d11 + d12 h'``, and
``dsigma/dt = -G1`` because ``D`` does not depend on ``phi1``.  Hence, with ``zeta = sigma^2 / 2``::

    d zeta / d theta = -I(theta) G1(theta)        (a quadrature: "single-point shooting")
    zeta(theta) = zeta_+ - W(theta),   W(theta) = int_{theta_s}^{theta} I G1

At impact ``sigma_+ = delta sigma_-`` (the impact map restricted to the surface), so the periodic
orbit has ``zeta_- = -W(theta_e) / (1 - delta^2)``; it exists and is exponentially stable when
``0 < delta^2 < 1``, ``W(theta_e) < 0`` and ``zeta > 0`` along the whole step.

Impact invariance (``Delta(S cap Z) subset Z``) fixes ``alpha_0 = 2 theta_0 = -alpha_M`` (the
guard at ``phi1 = theta_0 = asin(L / 2l)``, the legs swap) and ``alpha_1`` from ``alpha_{M-1}``:
with ``(a, b) = P (1, h'(theta_e))`` (``P`` the impact's velocity map) the post-impact velocity is
tangent to the surface when ``h'(theta_s) = b / a``, i.e. ``alpha_1 = alpha_0 + Dtheta b / (a M)``.

Along the orbit everything else follows from ``theta`` and ``zeta``: ``thetad = sqrt(2 zeta) / I``,
``thetadd = -(I' thetad^2 + G1) / I``, the hip torque from the actuated row, the ground reaction,
the time ``t = int dtheta / thetad`` and the mechanical cost of transport (Reher et al. 2016,
eqs. 17-18) ``COT = int |u q2d| dt / (m_total g L) = int |u h'| dtheta / (m_total g L)``.

Notation: ``N`` phase grid points (uniform in ``theta``); ``M`` Bezier degree; profiles are
``(N,)`` arrays over ``theta``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from gaitpref.gaits import bezier
from gaitpref.gaits.dynamics import (
    gravity_vector,
    ground_reaction,
    hip_torque,
    mass_matrix,
    swing_foot_height,
)
from gaitpref.gaits.impact import impact
from gaitpref.gaits.params import CompassGaitParams
from gaitpref.space import FloatArray

_ZETA_FLOOR = 1e-6


def _cumulative(f: FloatArray, h: float) -> FloatArray:
    """Cumulative integral on a uniform grid, 0 at the start, fourth order: each interval
    integrates the cubic through four neighbouring nodes (one-sided at the ends)."""
    inner = -f[:-3] + 13.0 * (f[1:-2] + f[2:-1]) - f[3:]
    first = 9.0 * f[0] + 19.0 * f[1] - 5.0 * f[2] + f[3]
    last = f[-4] - 5.0 * f[-3] + 19.0 * f[-2] + 9.0 * f[-1]
    pieces = np.concatenate([[0.0, first], inner, [last]]) * (h / 24.0)
    return np.cumsum(pieces)


def guard_angle(p: CompassGaitParams, step_length: float) -> float:
    """``theta_0 = asin(L / 2l)``: the stance angle at heel strike for step length ``L``."""
    ratio = step_length / (2.0 * p.leg_length)
    if not 0.0 < ratio < 1.0:
        raise ValueError(
            f"step length must be in (0, {2 * p.leg_length}) m for leg length "
            f"{p.leg_length} m, got {step_length}"
        )
    return math.asin(ratio)


@dataclass(frozen=True, eq=False)
class StepGeometry:
    """What a step length fixes: the phase interval and the impact's velocity map."""

    step_length: float
    theta_start: float  # -theta_0
    theta_end: float  # +theta_0
    velocity_map: FloatArray  # (2, 2) P: relabelled qd+ = P qd-
    impulse_map: FloatArray  # (2, 2) ground impulse = F qd-
    lift_off_map: FloatArray  # (2, 2) old stance foot's velocity = V qd-

    @classmethod
    def create(cls, p: CompassGaitParams, step_length: float) -> StepGeometry:
        """The impact is linear in ``qd-``: its maps are built from the basis vectors."""
        th0 = guard_angle(p, step_length)
        hits = [impact(p, np.array([th0, -2.0 * th0]), e) for e in np.eye(2)]
        return cls(
            step_length,
            -th0,
            th0,
            np.column_stack([h.qd for h in hits]),
            np.column_stack([h.impulse for h in hits]),
            np.column_stack([h.lift_off_velocity for h in hits]),
        )

    @property
    def span(self) -> float:
        return self.theta_end - self.theta_start

    def complete(self, inner: ArrayLike) -> FloatArray:
        """Full coefficients ``alpha_0..alpha_M`` from the free ones ``alpha_2..alpha_{M-1}``."""
        free = np.asarray(inner, dtype=np.float64)
        degree = free.size + 2
        first, last = -2.0 * self.theta_start, -2.0 * self.theta_end
        slope_end = degree * (last - free[-1]) / self.span
        a, b = self.velocity_map @ np.array([1.0, slope_end])
        second = first + self.span * (b / a) / degree
        return np.concatenate([[first, second], free, [last]])


@dataclass(frozen=True, eq=False)
class StepProfile:
    """One step on the zero dynamics for a given pre-impact phase velocity ``thetad_-``.

    The step starts from the impact of that velocity (``zeta_+ = delta^2 zeta_-``), so the
    profile is the periodic orbit exactly when ``periodicity_residual`` is zero.
    """

    theta: FloatArray
    tau: FloatArray
    q2: FloatArray
    dh: FloatArray  # h'(theta)
    inertia: FloatArray  # I(theta)
    zeta: FloatArray  # sigma^2 / 2
    thetad: FloatArray
    thetadd: FloatArray
    q2d: FloatArray
    torque: FloatArray
    force: FloatArray  # (N, 2) ground reaction (tangential, normal)
    swing_height: FloatArray
    time: FloatArray
    delta: float
    zeta_minus: float
    work_integral: float  # W(theta_e)
    impact_impulse: FloatArray  # (2,) per unit thetad_minus
    lift_off_speed: float  # old stance foot's vertical speed per unit thetad_minus
    abs_work: float  # int |u q2d| dt (exact)
    smooth_work: float  # int sqrt((u h')^2 + eps^2) - eps dtheta

    @property
    def periodicity_residual(self) -> float:
        """``(zeta(theta_e) - zeta_-) / zeta_-``: zero on the periodic orbit."""
        return float((self.zeta[-1] - self.zeta_minus) / self.zeta_minus)

    @property
    def duration(self) -> float:
        return float(self.time[-1])

    @property
    def periodic_zeta_minus(self) -> float:
        """The fixed point ``-W(theta_e) / (1 - delta^2)`` (``nan`` when none exists)."""
        d2 = self.delta**2
        value = -self.work_integral / (1.0 - d2) if d2 < 1.0 else math.nan
        return value if value > 0 else math.nan


def step_profile(
    p: CompassGaitParams,
    geometry: StepGeometry,
    alpha: ArrayLike,
    thetad_minus: float,
    n_points: int = 201,
    smoothing: float = 1e-3,
) -> StepProfile:
    """Evaluate one step of the zero dynamics on a uniform grid of ``n_points`` phases.

    ``alpha`` must be impact invariant (made by :meth:`StepGeometry.complete`): the step starts
    where the impact of the previous one lands, on the surface ``q2 = h(theta)``.
    """
    if n_points < 5:
        raise ValueError(f"n_points must be >= 5, got {n_points}")
    coef = np.asarray(alpha, dtype=np.float64)
    degree = coef.size - 1
    tau = np.linspace(0.0, 1.0, n_points)
    span = geometry.span
    theta = geometry.theta_start + span * tau
    h = bezier.basis(degree, tau, 0) @ coef
    dh = bezier.basis(degree, tau, 1) @ coef / span
    ddh = bezier.basis(degree, tau, 2) @ coef / span**2
    q = np.stack([theta, h], -1)
    dmat = mass_matrix(p, q)
    d11, d12 = dmat[:, 0, 0], dmat[:, 0, 1]
    inertia = d11 + d12 * dh
    g1 = gravity_vector(p, q)[:, 0]
    k = p.leg_mass * p.leg_length * p.leg_com * np.sin(h)
    inertia_prime = 2.0 * k * dh + k * dh**2 + d12 * ddh

    # impact restricted to the surface: per unit pre-impact phase velocity
    pre = np.array([1.0, dh[-1]])
    post = geometry.velocity_map @ pre
    delta = float((d11[0] * post[0] + d12[0] * post[1]) / inertia[-1])
    zeta_minus = 0.5 * (inertia[-1] * thetad_minus) ** 2
    work = _cumulative(inertia * g1, theta[1] - theta[0])
    zeta = delta**2 * zeta_minus - work

    # a floor keeps times finite where the orbit stalls (zeta <= 0); callers check zeta itself
    thetad = np.sqrt(2.0 * np.maximum(zeta, _ZETA_FLOOR * zeta_minus)) / inertia
    thetadd = -(inertia_prime * thetad**2 + g1) / inertia
    q2d = dh * thetad
    q2dd = ddh * thetad**2 + dh * thetadd
    qd = np.stack([thetad, q2d], -1)
    qdd = np.stack([thetadd, q2dd], -1)
    torque = hip_torque(p, q, qd, qdd)
    force = ground_reaction(p, q, qd, qdd)
    time = _cumulative(1.0 / thetad, theta[1] - theta[0])
    power = torque * dh  # u q2d / thetad: per unit phase
    return StepProfile(
        theta=theta,
        tau=tau,
        q2=h,
        dh=dh,
        inertia=inertia,
        zeta=zeta,
        thetad=thetad,
        thetadd=thetadd,
        q2d=q2d,
        torque=torque,
        force=force,
        swing_height=swing_foot_height(p, q),
        time=time,
        delta=delta,
        zeta_minus=zeta_minus,
        work_integral=float(work[-1]),
        impact_impulse=geometry.impulse_map @ pre,
        lift_off_speed=float((geometry.lift_off_map @ pre)[1]),
        abs_work=float(_cumulative(np.abs(power), theta[1] - theta[0])[-1]),
        smooth_work=float(
            _cumulative(np.sqrt(power**2 + smoothing**2) - smoothing, span / (n_points - 1))[-1]
        ),
    )
