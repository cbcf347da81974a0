"""The population's hyperparameters from the data: the evidence with ``rho`` and the kernel's.

Type-II MAP as ``hyperfit.py`` (GPML Section 5.4.1, with priors) over
``theta = (log l_1, ..., log l_d, log s^2, log band, logit rho)`` with the population evidence
(``population.py``): the same log-normal priors and bounds for the single-subject entries (a
:class:`~gaitpref.model.hyperfit.HyperPrior`), and a logit-normal prior on the shared fraction,
``logit rho ~ N(logit median, sd^2)``, bounded at 3 sd.  The default (median 0.5, sd 1.5) puts
95% of its mass on ``rho`` in (0.05, 0.95): a new subject unlike the others is not pulled towards
them unless their data say so.  Ordinal thresholds are held (not fitted here).

As :func:`~gaitpref.model.hyperfit.fit_hyperparameters`, a fit that fails or does not improve the
objective keeps the starting values and says so (:class:`PopulationFit`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import LinAlgError
from scipy.optimize import minimize

from gaitpref.checks import check_evaluations, is_number
from gaitpref.errors import ConvergenceError, PriorNotPositiveDefiniteError
from gaitpref.model.evidence import Hyperparameters, PairData
from gaitpref.model.hyperfit import HyperPrior, prior_bounds
from gaitpref.model.population import check_rho, logit, population_evidence
from gaitpref.model.singles import SingleData
from gaitpref.model.threads import one_blas_thread
from gaitpref.space import FloatArray, Space


@dataclass(frozen=True)
class LogitNormal:
    """``logit rho ~ N(logit median, sd^2)``; ``sd = 0`` holds ``rho`` fixed."""

    median: float = 0.5
    sd: float = 1.5

    def __post_init__(self) -> None:
        # is_number first: a string was a NumPy TypeError, True a median of 1
        if not (is_number(self.median) and np.isfinite(self.median) and 0.0 < self.median < 1.0):
            raise ValueError(f"rho's prior median must lie in (0, 1), got {self.median!r}")
        if not (is_number(self.sd) and np.isfinite(self.sd) and self.sd >= 0):
            raise ValueError(f"rho's prior sd must be >= 0, got {self.sd!r}")


@dataclass(frozen=True)
class PopulationFit:
    """One population fit: hyperparameters and ``rho`` before and after (equal unless
    ``accepted``)."""

    before: Hyperparameters
    rho_before: float
    after: Hyperparameters
    rho_after: float
    accepted: bool
    message: str
    evaluations: int
    failed_evaluations: int
    objective_before: float
    objective_after: float


_FAILURES = (ConvergenceError, PriorNotPositiveDefiniteError, LinAlgError, FloatingPointError)
_FAILED = 1e10


def _priors(
    space: Space, prior: HyperPrior, rho_prior: LogitNormal
) -> tuple[FloatArray, FloatArray, list[tuple[float, float]]]:
    """Centre, sd and bounds of every entry of ``theta`` (sd 0: held)."""
    entries = [None if p is None else (float(np.log(p.median)), p.sd) for p in prior.all()]
    entries.append((logit(rho_prior.median), rho_prior.sd))
    bounds = prior_bounds(space, entries)
    centre = np.array([p[0] if p else 0.0 for p in entries])
    sd = np.array([p[1] if p else 0.0 for p in entries])
    return centre, sd, bounds


def fit_population(
    space: Space,
    start: Hyperparameters,
    rho: float,
    data: PairData,
    prior: HyperPrior,
    rho_prior: LogitNormal | None = None,
    *,
    singles: SingleData | None = None,
    max_evaluations: int = 60,
) -> PopulationFit:
    """MAP lengthscales (and whatever else ``prior`` frees) and ``rho`` for population data
    (node codes, ``population.py``) by L-BFGS-B from ``start`` and ``rho``."""
    rho = check_rho(rho)
    max_evaluations = check_evaluations(max_evaluations)
    rho_prior = LogitNormal() if rho_prior is None else rho_prior
    if start.thresholds is not None:
        start = Hyperparameters(start.lengthscale, start.variance, start.jitter, start.band)
    centre, sd, bounds = _priors(space, prior, rho_prior)
    free = sd > 0
    if prior.band is not None and start.band <= 0:
        raise ValueError("fitting the band needs a positive starting band")
    edge = 1e-6
    theta0 = np.concatenate([start.log_vector(), [logit(min(max(rho, edge), 1 - edge))]])
    size = data.size + (0 if singles is None else singles.size)
    if size == 0 or not np.any(free):
        return PopulationFit(start, rho, start, rho, False, "nothing to fit", 0, 0, np.nan, np.nan)
    free_bounds = [b for b, keep in zip(bounds, free, strict=True) if keep]
    lo, hi = np.array(free_bounds).T
    mode: FloatArray | None = None
    evaluations = failures = 0
    best: list[tuple[float, FloatArray]] = []

    def point(x: FloatArray) -> tuple[Hyperparameters, float]:
        theta = theta0.copy()
        theta[free] = x
        return start.with_log_vector(theta[:-1]), float(1.0 / (1.0 + np.exp(-theta[-1])))

    def objective(x: FloatArray) -> tuple[float, FloatArray]:
        nonlocal mode, evaluations, failures
        evaluations += 1
        hyper, r = point(x)
        try:
            ev = population_evidence(space, hyper, r, data, mode, singles=singles)
            if not (np.isfinite(ev.value) and np.all(np.isfinite(ev.gradient))):
                raise FloatingPointError("non-finite evidence")
        except _FAILURES:
            failures += 1
            return _FAILED, np.zeros_like(x)
        mode = ev.fit.mode
        z = (x - centre[free]) / sd[free]
        value = -(ev.value - 0.5 * float(z @ z))
        if not best or value < best[0][0]:
            best[:] = [(value, np.array(x, dtype=np.float64))]
        return value, -(ev.gradient[free] - z / sd[free])

    with one_blas_thread():
        x0 = np.clip(theta0[free], lo, hi)
        first, _ = objective(x0)
        if failures:
            message = "kept the starting values: the evidence cannot be evaluated there"
            return PopulationFit(start, rho, start, rho, False, message, 1, 1, np.nan, np.nan)
        res = minimize(
            objective, x0, jac=True, method="L-BFGS-B", bounds=free_bounds,
            options={"maxfun": max_evaluations, "maxiter": max_evaluations},
        )  # fmt: skip
    value, x = best[0]
    evals = evaluations
    if not -value >= -first:
        message = f"kept the starting values: the fit did not improve ({res.message})"
        kept = (start, rho, start, rho, False, message)
        return PopulationFit(*kept, evals, failures, -first, -first)
    hyper, r = point(x)
    return PopulationFit(
        start, rho, hyper, r, True, str(res.message), evals, failures, -first, -value
    )


__all__ = ["LogitNormal", "PopulationFit", "fit_population"]
