"""Hyperparameters from the data: maximise the Laplace evidence plus weakly informative priors.

Type-II maximum a posteriori (GPML Section 5.4.1, with priors): maximise
``log q(D | theta) + log p(theta)`` over ``theta = log (l_1, ..., l_d, s^2, band)``
(``evidence.py``) by L-BFGS-B (``scipy.optimize.minimize``) within bounds, warm-started from the
current values.  Each parameter has a log-normal prior ``log x ~ N(log median, sd^2)``; a
parameter with ``sd = 0`` is held at its current value.  Bounds are ``median * exp(+-3 sd)``,
and a lengthscale never goes below half its feature's smallest grid step (shorter ones make grid
neighbours independent, which no gait data can support).

Default priors (:func:`default_prior`), in each feature's own units: lengthscale median a quarter
of the feature's range, ``sd = 0.7`` (95% within a factor 4: 0.06-1.0 of the range); band median
the probit noise ``sigma`` (``P(no preference | equal utilities) = 0.52``), ``sd = 1``.  The
signal variance (that is, ``s / sigma``) is held at the config's value by default (``sd = 0``):
with consistent answers the evidence keeps raising ``s / sigma``, the posterior grows
overconfident and the loop explores too little; the study in ``docs/results/learning`` measured
it (``variance_sd = 1`` lost late in the session).

:func:`fit_hyperparameters` never fails silently: a fit that raises, produces non-finite values
or does not improve the objective keeps the previous hyperparameters, and the returned
:class:`HyperFit` says what happened (``accepted``, ``converged``, ``message``).

Notation: ``d`` features; ``theta`` has ``d + 2`` entries, of which the free ones are optimised.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import LinAlgError
from scipy.optimize import minimize

from gaitpref.errors import ConvergenceError, PriorNotPositiveDefiniteError
from gaitpref.model.evidence import Hyperparameters, PairData, laplace_evidence
from gaitpref.model.threads import one_blas_thread
from gaitpref.space import FloatArray, Space


@dataclass(frozen=True)
class LogNormal:
    """``log x ~ N(log median, sd^2)``; ``sd = 0`` holds the parameter fixed."""

    median: float
    sd: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.median) and self.median > 0):
            raise ValueError(f"a prior's median must be positive, got {self.median!r}")
        if not (np.isfinite(self.sd) and self.sd >= 0):
            raise ValueError(f"a prior's sd must be >= 0, got {self.sd!r}")


@dataclass(frozen=True)
class HyperPrior:
    """Priors of the lengthscales (one per feature), the signal variance and the band.

    ``band`` None: the band is not fitted (ties dropped, or a band fixed by the config).
    """

    lengthscale: tuple[LogNormal, ...]
    variance: LogNormal
    band: LogNormal | None = None

    def all(self) -> tuple[LogNormal | None, ...]:
        return (*self.lengthscale, self.variance, self.band)


def default_prior(
    space: Space,
    variance: float,
    noise: float,
    fit_band: bool = False,
    *,
    lengthscale_sd: float = 0.7,
    variance_sd: float = 0.0,
    band_sd: float = 1.0,
) -> HyperPrior:
    """The weakly informative defaults (module docstring); single-valued features are fixed."""
    scales = []
    for f in space.features:
        span = f.span
        scales.append(LogNormal(0.25 * span, lengthscale_sd) if span > 0 else LogNormal(1.0, 0.0))
    band = LogNormal(noise, band_sd) if fit_band else None
    return HyperPrior(tuple(scales), LogNormal(variance, variance_sd), band)


@dataclass(frozen=True)
class HyperFit:
    """The result of one hyperparameter fit (``after == before`` unless ``accepted``)."""

    before: Hyperparameters
    after: Hyperparameters
    accepted: bool
    converged: bool
    message: str
    evaluations: int
    failed_evaluations: int  # evaluations where the Laplace fit raised (treated as very bad)
    objective_before: float  # log evidence + log prior at ``before``
    objective_after: float  # ... at ``after``
    observations: int

    def to_json(self) -> dict[str, object]:
        """A plain JSON record for logs (sessions store it with the answer that triggered it);
        a non-finite objective (a failed evaluation) is ``None``: JSON has no inf or nan."""

        def finite(x: float) -> float | None:
            return x if math.isfinite(x) else None

        def values(h: Hyperparameters) -> dict[str, object]:
            return {
                "lengthscale": list(h.lengthscale),
                "signal_variance": h.variance,
                "jitter": h.jitter,
                "tie_band": h.band,
            }

        return {
            "before": values(self.before),
            "after": values(self.after),
            "accepted": self.accepted,
            "converged": self.converged,
            "message": self.message,
            "evaluations": self.evaluations,
            "failed_evaluations": self.failed_evaluations,
            "objective_before": finite(self.objective_before),
            "objective_after": finite(self.objective_after),
            "observations": self.observations,
        }


_FAILURES = (ConvergenceError, PriorNotPositiveDefiniteError, LinAlgError, FloatingPointError)


def _bounds(space: Space, prior: HyperPrior) -> list[tuple[float, float]]:
    out = []
    for k, p in enumerate(prior.all()):
        if p is None:
            out.append((-np.inf, np.inf))
            continue
        lo, hi = np.log(p.median) - 3 * p.sd, np.log(p.median) + 3 * p.sd
        if k < space.ndim and len(space.features[k]) > 1:
            step = float(np.min(np.diff(space.features[k].array)))
            lo = max(lo, float(np.log(0.5 * step)))
            hi = max(hi, lo)
        out.append((float(lo), float(hi)))
    return out


def fit_hyperparameters(
    space: Space,
    start: Hyperparameters,
    data: PairData,
    prior: HyperPrior,
    *,
    max_evaluations: int = 60,
) -> HyperFit:
    """MAP hyperparameters for ``data`` by L-BFGS-B from ``start`` (see the module docstring)."""
    free = np.array([p is not None and p.sd > 0 for p in prior.all()])
    if prior.band is not None and start.band <= 0:
        raise ValueError("fitting the band needs a positive starting band")
    if data.size == 0 or not np.any(free):
        return HyperFit(start, start, False, True, "nothing to fit", 0, 0, np.nan, np.nan, 0)
    with one_blas_thread():
        return _fit(space, start, data, prior, free, max_evaluations)


class _Objective:
    """``-(log evidence + log prior)`` over the free log-parameters, warm-starting each mode."""

    def __init__(
        self,
        space: Space,
        start: Hyperparameters,
        data: PairData,
        prior: HyperPrior,
        free: NDArray[np.bool_],
    ) -> None:
        self.space, self.start, self.data, self.free = space, start, data, free
        self.theta0 = start.log_vector()
        priors = prior.all()
        self.centre = np.array([np.log(p.median) if p else 0.0 for p in priors])[free]
        self.sd = np.array([p.sd if p else 1.0 for p in priors])[free]
        self.mode: FloatArray | None = None
        self.evaluations = 0
        self.failures = 0
        self.best: tuple[float, FloatArray] = (np.inf, self.theta0[free])

    def hyper(self, x: FloatArray) -> Hyperparameters:
        theta = self.theta0.copy()
        theta[self.free] = x
        return self.start.with_log_vector(theta)

    def __call__(self, x: FloatArray) -> tuple[float, FloatArray]:
        self.evaluations += 1
        try:
            ev = laplace_evidence(self.space, self.hyper(x), self.data, self.mode)
            if not (np.isfinite(ev.value) and np.all(np.isfinite(ev.gradient))):
                raise FloatingPointError("non-finite evidence")
        except _FAILURES:
            self.failures += 1
            return _FAILED, np.zeros_like(x)
        self.mode = ev.fit.mode
        z = (x - self.centre) / self.sd
        value = -(ev.value - 0.5 * float(z @ z))
        if value < self.best[0]:
            self.best = (value, np.array(x, dtype=np.float64))
        return value, -(ev.gradient[self.free] - z / self.sd)


_FAILED = 1e10  # what a failed evaluation reports to L-BFGS-B: far worse than any real value


def _fit(
    space: Space,
    start: Hyperparameters,
    data: PairData,
    prior: HyperPrior,
    free: NDArray[np.bool_],
    max_evaluations: int,
) -> HyperFit:
    bounds = [b for b, keep in zip(_bounds(space, prior), free, strict=True) if keep]
    objective = _Objective(space, start, data, prior, free)
    x0 = np.clip(objective.theta0[free], [b[0] for b in bounds], [b[1] for b in bounds])
    first, _ = objective(x0)
    if objective.failures:
        message = "kept the previous hyperparameters: the evidence cannot be evaluated at the start"
        return HyperFit(start, start, False, False, message, 1, 1, np.nan, np.nan, data.size)
    res = minimize(
        objective,
        x0,
        jac=True,
        method="L-BFGS-B",
        bounds=bounds,
        options={"maxfun": max_evaluations, "maxiter": max_evaluations},
    )
    # the best point evaluated (L-BFGS-B may stop elsewhere after a failed line search)
    best_value, best_x = objective.best
    before, after = -first, -best_value
    evals, failed = objective.evaluations, objective.failures
    if not after >= before:
        message = f"kept the previous hyperparameters: the fit did not improve ({res.message})"
        return HyperFit(
            start, start, False, False, message, evals, failed, before, before, data.size
        )
    message = str(res.message) + (f"; {failed} evaluations failed" if failed else "")
    return HyperFit(
        start, objective.hyper(best_x), True, bool(res.success) and not failed, message, evals,
        failed, before, after, data.size,
    )  # fmt: skip
