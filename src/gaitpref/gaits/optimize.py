"""HZD gait optimization for the compass gait: minimise mechanical COT with SLSQP.

The paper's problem (Section "Gait Generation for Bipedal Robots", eqs. (3)-(5)):
``alpha* = argmin J(alpha)`` subject to impact invariance and physical constraints.  Here
(``docs/gaits.md``, "The HZD formulation"):

* decision ``x = (alpha_2..alpha_{M-1}) / (2 theta_0), thetad_-``; impact invariance is built in
  (:meth:`StepGeometry.complete` fixes ``alpha_0, alpha_1, alpha_M``);
* objective: mechanical COT (Reher et al. 2016, eqs. 17-18) with ``|.|`` smoothed;
* equalities: periodic orbit of the zero dynamics, step duration ``T`` (or ``L / v``);
* inequalities on ``n_c`` phase nodes: ``0 < delta``, ``delta^2 <= max``, forward progress
  (``thetad`` bounded below, ``I(theta) > 0``), normal force ``>= f_min m g``,
  ``|F_t| <= mu F_n``, swing-foot clearance for ``tau >= clearance_start`` and a physical impact
  (positive normal impulse inside the friction cone, the old stance foot lifting off).

Each gait is checked again after the solver stops (:func:`_violations`); the verdict and every
violated constraint go into :class:`Gait`'s ``feasible`` and ``message``.  The reported COT and
orbit come from a 4x finer phase grid, with ``thetad_-`` set to the exact fixed point.

Notation: ``M`` Bezier degree, ``N`` phase grid points, ``n_c`` constraint nodes; ``x`` has
``M - 1`` entries.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq, minimize

from gaitpref.gaits.gait import Gait, GaitRequest, HZDSettings
from gaitpref.gaits.params import CompassGaitParams
from gaitpref.gaits.zero_dynamics import StepGeometry, StepProfile, step_profile
from gaitpref.space import FloatArray


@dataclass
class _Problem:
    p: CompassGaitParams
    geo: StepGeometry
    duration: float
    s: HZDSettings

    def __post_init__(self) -> None:
        self.scale = self.geo.span  # 2 theta_0
        self.weight = self.p.total_mass * self.p.gravity
        self.mean_rate = self.geo.span / self.duration
        # a Python float's ** raises OverflowError (past ~1e154: a step of ~1e-155 s) where
        # NumPy's gives inf; such a request is infeasible, not an exception
        self.mean_rate_sq = self.mean_rate**2 if self.mean_rate < 1e154 else math.inf
        n, nc = self.s.n_points, self.s.n_constraint_points
        self.nodes = np.unique(np.linspace(0, n - 1, nc).round().astype(int))
        tau = self.nodes / (n - 1)
        self.late = self.nodes[(tau >= self.s.clearance_start) & (tau < 1.0)]
        self._cache: dict[bytes, StepProfile] = {}

    def alpha(self, x: FloatArray) -> FloatArray:
        return self.geo.complete(x[:-1] * self.scale)

    def profile(self, x: FloatArray) -> StepProfile:
        # SLSQP differentiates objective and constraints at the same points: keep a few profiles
        key = x.tobytes()
        found = self._cache.get(key)
        if found is None:
            found = step_profile(
                self.p, self.geo, self.alpha(x), float(x[-1]), self.s.n_points, self.s.smoothing
            )
            if len(self._cache) >= 4 * self.s.degree:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = found
        return found

    def objective(self, x: FloatArray) -> float:
        return 100.0 * self.profile(x).smooth_work / (self.weight * self.geo.step_length)

    def equalities(self, x: FloatArray) -> FloatArray:
        pr = self.profile(x)
        return np.array([pr.periodicity_residual, (pr.duration - self.duration) / self.duration])

    def clearance_needed(self, pr: StepProfile) -> FloatArray:
        tau = pr.tau[self.late]
        ramp = (1.0 - tau) / (1.0 - self.s.clearance_start)
        return np.asarray(self.s.clearance * self.geo.step_length * ramp)

    def inequality_groups(self, x: FloatArray) -> dict[str, FloatArray]:
        """Named, scaled inequality constraints (``>= 0`` when satisfied)."""
        pr, s, i = self.profile(x), self.s, self.nodes
        fn, ft = pr.force[i, 1] / self.weight, pr.force[i, 0] / self.weight
        imp = pr.impact_impulse / (self.p.total_mass * self.p.leg_length)
        rate_sq = 2.0 * pr.zeta[i] / pr.inertia[i] ** 2 / self.mean_rate_sq
        mu = s.friction_coefficient
        return {
            "delta^2": np.array([s.max_delta_squared - pr.delta**2, pr.delta]),
            "forward progress": rate_sq - s.min_phase_speed**2,
            "momentum inertia": pr.inertia[i] / pr.inertia[0] - 0.2,
            "normal force": fn - s.min_normal_force,
            "friction": np.concatenate([mu * fn - ft, mu * fn + ft]),
            "swing-foot clearance": (pr.swing_height[self.late] - self.clearance_needed(pr))
            / (0.01 * self.geo.step_length),
            "impact impulse": np.array([imp[1] - 0.01, mu * imp[1] - imp[0], mu * imp[1] + imp[0]]),
            "lift-off": np.array([pr.lift_off_speed / self.p.leg_length]),
        }

    def inequalities(self, x: FloatArray) -> FloatArray:
        return np.concatenate(list(self.inequality_groups(x).values()))

    def initial_guess(self, shape: FloatArray | None) -> FloatArray:
        """``x0`` from a normalised coefficient shape (or a default), speed matched to ``T``."""
        m = self.s.degree
        if shape is None:
            lin = np.linspace(1.0, -1.0, m + 1)
            shape = lin[2:m].copy()
            shape[-1] = lin[-1] + 0.5 * (lin[-2] - lin[-1])  # swing leg slows before the strike
        alpha = self.geo.complete(shape * self.scale)

        def excess(rate: float) -> float:
            pr = step_profile(self.p, self.geo, alpha, rate, self.s.n_points, self.s.smoothing)
            return pr.duration - self.duration

        lo, hi = 1e-3 * self.mean_rate, 50.0 * self.mean_rate
        f_lo, f_hi = excess(lo), excess(hi)
        if math.isfinite(f_lo) and math.isfinite(f_hi) and f_lo > 0 > f_hi:
            rate = brentq(excess, lo, hi, xtol=1e-6 * self.mean_rate)
        else:
            rate = self.mean_rate
        return np.concatenate([shape, [rate]])


def _describe(group: str, problem: _Problem, pr: StepProfile) -> str:
    """A violated inequality group in physical terms."""
    s, i = problem.s, problem.nodes
    fn, ft = pr.force[i, 1], pr.force[i, 0]
    if group == "delta^2":
        return f"delta = {pr.delta:.4f}, needs 0 < delta and delta^2 <= {s.max_delta_squared}"
    if group == "forward progress":
        ratio = np.sqrt(np.maximum(2.0 * pr.zeta[i], 0.0)) / pr.inertia[i] / problem.mean_rate
        return (
            f"forward progress: stance-leg speed falls to {ratio.min():.3f} of its mean "
            f"(needs >= {s.min_phase_speed})"
        )
    if group == "normal force":
        least = fn.min() / problem.weight
        return f"normal force falls to {least:.2f} m g (needs >= {s.min_normal_force} m g)"
    if group == "friction":
        ratio = np.abs(ft) / np.where(fn > 0, fn, np.nan)
        worst = np.nanmax(ratio) if np.isfinite(ratio).any() else math.inf
        return f"friction ratio reaches {worst:.2f} (limit {s.friction_coefficient})"
    if group == "swing-foot clearance":
        gap = pr.swing_height[problem.late] - problem.clearance_needed(pr)
        k = int(np.argmin(gap))
        return (
            f"swing-foot clearance short by {-1000 * gap[k]:.2f} mm at "
            f"tau = {pr.tau[problem.late][k]:.2f}"
        )
    if group == "impact impulse":
        imp = pr.impact_impulse
        return f"impact impulse not physical (tangential {imp[0]:.3g}, normal {imp[1]:.3g})"
    if group == "lift-off":
        return "the old stance foot does not lift off at impact"
    return f"{group} violated"


def _violations(problem: _Problem, x: FloatArray) -> list[str]:
    """Every violated constraint at ``x``, with the offending value, in words."""
    tol = problem.s.feasibility_tolerance
    out: list[str] = []
    pr = problem.profile(x)
    if not np.all(np.isfinite(problem.equalities(x))) or not np.isfinite(pr.zeta).all():
        return ["the zero dynamics could not be evaluated (non-finite values)"]
    res, dur = problem.equalities(x)
    if abs(res) > tol:
        out.append(f"no periodic orbit (relative residual {res:.2e})")
    if abs(dur) > tol:
        out.append(f"step duration {pr.duration:.4f} s, requested {problem.duration:.4f} s")
    for name, values in problem.inequality_groups(x).items():
        if values.size and values.min() < -tol:
            out.append(_describe(name, problem, pr))
    if pr.zeta.min() <= 0:
        out.append("the stance leg stops or falls back")
    if pr.force[:, 1].min() <= 0:
        out.append(f"normal force {pr.force[:, 1].min():.1f} N <= 0: the stance foot lifts off")
    return out


def _finish(problem: _Problem, x: FloatArray, status: int, message: str) -> Gait:
    """Evaluate ``x`` on a finer grid at the exact fixed point and wrap it as a :class:`Gait`."""
    violations = _violations(problem, x)
    p, geo, s = problem.p, problem.geo, problem.s
    alpha = problem.alpha(x)
    fine_n = 4 * (s.n_points - 1) + 1
    pr = step_profile(p, geo, alpha, float(x[-1]), fine_n, s.smoothing)
    zeta_star = pr.periodic_zeta_minus
    if math.isfinite(zeta_star):
        rate = math.sqrt(2.0 * zeta_star) / pr.inertia[-1]
        pr = step_profile(p, geo, alpha, rate, fine_n, s.smoothing)
    feasible = status == 0 and not violations
    if feasible:
        text = f"optimal: {message}"
    else:
        reasons = violations or [f"the solver did not converge ({message})"]
        text = "infeasible: " + "; ".join(reasons)
        if violations:
            text += f" [SLSQP: {message}]"
    fn, ft = pr.force[:, 1], pr.force[:, 0]
    ratio_path = float(np.max(np.abs(ft) / fn)) if fn.min() > 0 else math.inf
    imp = pr.impact_impulse
    ratio_impact = abs(imp[0]) / imp[1] if imp[1] > 0 else math.inf
    return Gait(
        step_length=geo.step_length,
        step_duration=pr.duration,
        alpha=alpha[None, :].copy(),
        phase_start=geo.theta_start,
        phase_end=geo.theta_end,
        orbit_state=np.array([pr.theta[0], pr.q2[0], pr.thetad[0], pr.q2d[0]]),
        cot=pr.abs_work / (p.total_mass * p.gravity * geo.step_length),
        delta_squared=pr.delta**2,
        feasible=feasible,
        status=int(status),
        message=text,
        min_normal_force=float(fn.min()),
        max_friction_ratio=max(ratio_path, ratio_impact),
    )


def _solve(problem: _Problem, x0: FloatArray, max_iterations: int) -> tuple[Gait, int]:
    """SLSQP from ``x0`` for at most ``max_iterations`` iterations: the gait and the iterations
    it took (a solver error counts as none)."""
    n_free = problem.s.degree - 2
    bounds = [(-3.0, 3.0)] * n_free + [(1e-4 * problem.mean_rate, 100.0 * problem.mean_rate)]
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            res = minimize(
                problem.objective,
                x0,
                method="SLSQP",
                bounds=bounds,
                constraints=[
                    {"type": "eq", "fun": problem.equalities},
                    {"type": "ineq", "fun": problem.inequalities},
                ],
                options={"maxiter": max_iterations, "ftol": problem.s.tolerance},
            )
        except (ValueError, np.linalg.LinAlgError) as exc:
            return _finish(problem, x0, 99, f"solver error: {exc}"), 0
        x = np.asarray(res.x, dtype=np.float64)
        return _finish(problem, x, int(res.status), res.message), int(res.nit)


def _better(a: Gait, b: Gait | None) -> bool:
    if b is None:
        return True
    if a.feasible != b.feasible:
        return a.feasible
    return a.cot < b.cot if a.feasible else False


def optimize_gait(
    request: GaitRequest,
    params: CompassGaitParams | None = None,
    settings: HZDSettings | None = None,
    warm_start: Gait | None = None,
    max_iterations: int | None = None,
) -> Gait:
    """The minimum-COT HZD gait for ``request``; infeasible requests come back flagged.

    ``warm_start`` (a neighbour in a grid) lends its coefficient shape; the default start is
    tried as well when the warm start does not give a feasible gait.

    ``max_iterations`` bounds the SLSQP iterations of all starts together (the warm start's
    first, the default start gets what is left): the cost of a request is then bounded and,
    being counted in iterations rather than seconds, the verdict does not depend on the
    machine's speed or load (only, as any verdict, on its floating-point rounding).
    A gait not found feasible within them is infeasible, and its message says so first
    ("no feasible gait within N iterations"). ``None``: each start may take
    ``settings.max_iterations`` (what gaits on demand did before the budget, and libraries do).
    """
    p = params or CompassGaitParams()
    s = settings or HZDSettings()
    if max_iterations is not None and (
        isinstance(max_iterations, bool)
        or not isinstance(max_iterations, int)
        or max_iterations < 1
    ):
        raise ValueError(f"max_iterations must be an integer >= 1 or None, got {max_iterations!r}")
    geo = StepGeometry.create(p, request.step_length)
    problem = _Problem(p, geo, request.target_duration, s)
    shapes: list[FloatArray | None] = []
    if warm_start is not None:
        if warm_start.degree != s.degree:
            raise ValueError(
                f"warm start has Bezier degree {warm_start.degree}, settings ask for {s.degree}"
            )
        span = warm_start.phase_end - warm_start.phase_start
        shapes.append(warm_start.alpha[0, 2 : s.degree] / span)
    shapes.append(None)
    left = max_iterations
    best: Gait | None = None
    spent: list[tuple[str, int]] = []  # (start, iterations)
    for shape in shapes:
        if left is not None and left < 1:
            break
        with np.errstate(all="ignore"):
            x0 = problem.initial_guess(shape)
        gait, used = _solve(problem, x0, s.max_iterations if left is None else left)
        spent.append(("default start" if shape is None else "warm start", used))
        if left is not None:
            left -= used
        if _better(gait, best):
            best = gait
        if best is not None and best.feasible:
            break
    assert best is not None
    if max_iterations is not None and not best.feasible and left is not None and left < 1:
        return _over_budget(best, max_iterations, spent)
    return best


def _over_budget(gait: Gait, budget: int, spent: list[tuple[str, int]]) -> Gait:
    """``gait`` with its message led by the budget that ran out (and what each start took)."""
    starts = ", ".join(f"{name} {used}" for name, used in spent)
    reasons = gait.message.removeprefix("infeasible: ")
    text = f"infeasible: no feasible gait within {budget} iterations ({starts}); {reasons}"
    return replace(gait, message=text)
