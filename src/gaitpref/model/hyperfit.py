"""Hyperparameters from the data: maximise the Laplace evidence plus weakly informative priors.

Type-II maximum a posteriori (GPML Section 5.4.1, with priors): maximise
``log q(D | theta) + log p(theta)`` over ``theta = log (l_1, ..., l_d, s^2, band)``
(``evidence.py``) by L-BFGS-B (``scipy.optimize.minimize``) within bounds, warm-started from the
current values.  Each parameter has a log-normal prior ``log x ~ N(log median, sd^2)``; a
parameter with ``sd = 0`` is held at its current value.  Bounds are ``median * exp(+-3 sd)``,
and a lengthscale never goes below half its feature's smallest grid step (shorter ones make grid
neighbours independent, which no gait data can support).

Default priors (:func:`default_prior`), in each feature's own units: lengthscale median a quarter
of the feature's range, ``sd = 0.7`` (95% within a factor 4: 0.06-1.0 of the range); signal
variance median the config's, ``sd = 1``; band median the probit noise ``sigma``
(``P(no preference | equal utilities) = 0.52``), ``sd = 1``.

:func:`fit_hyperparameters` never fails silently: a fit that raises, produces non-finite values
or does not improve the objective keeps the previous hyperparameters, and the returned
:class:`HyperFit` says what happened (``accepted``, ``converged``, ``message``).

Notation: ``d`` features; ``theta`` has ``d + 2`` entries, of which the free ones are optimised.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import LinAlgError
from scipy.optimize import minimize

from gaitpref.model.evidence import Hyperparameters, PairData, laplace_evidence
from gaitpref.model.laplace import ConvergenceError, PriorNotPositiveDefiniteError
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
    variance_sd: float = 1.0,
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
        """A plain record for logs (sessions store it with the answer that triggered it)."""

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
            "objective_before": self.objective_before,
            "objective_after": self.objective_after,
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
    theta0 = start.log_vector()
    priors = prior.all()
    free = np.array([p is not None and p.sd > 0 for p in priors])
    if prior.band is not None and start.band <= 0:
        raise ValueError("fitting the band needs a positive starting band")
    if data.size == 0 or not np.any(free):
        return HyperFit(start, start, False, True, "nothing to fit", 0, 0, np.nan, np.nan, 0)
    bounds = [b for b, keep in zip(_bounds(space, prior), free, strict=True) if keep]
    centre = np.array([np.log(p.median) if p is not None else 0.0 for p in priors])[free]
    sd = np.array([p.sd if p is not None else 1.0 for p in priors])[free]
    x0 = np.clip(theta0[free], [b[0] for b in bounds], [b[1] for b in bounds])
    state: dict[str, object] = {"mode": None, "evals": 0, "failed": 0}

    def hyper_at(x: FloatArray) -> Hyperparameters:
        theta = theta0.copy()
        theta[free] = x
        return start.with_log_vector(theta)

    def negative(x: FloatArray) -> tuple[float, FloatArray]:
        state["evals"] = int(state["evals"]) + 1  # type: ignore[call-overload]
        mode = state["mode"]
        try:
            ev = laplace_evidence(space, hyper_at(x), data, mode)  # type: ignore[arg-type]
            if not (np.isfinite(ev.value) and np.all(np.isfinite(ev.gradient))):
                raise FloatingPointError("non-finite evidence")
        except _FAILURES:
            state["failed"] = int(state["failed"]) + 1  # type: ignore[call-overload]
            return 1e10, np.zeros_like(x)
        state["mode"] = ev.fit.mode
        z = (x - centre) / sd
        value = ev.value - 0.5 * float(z @ z)
        grad = ev.gradient[free] - z / sd
        return -value, -grad

    first, _ = negative(x0)
    before_value = -first
    if not np.isfinite(before_value) or int(state["failed"]) > 0:  # type: ignore[call-overload]
        return HyperFit(
            start, start, False, False, "the evidence cannot be evaluated at the start",
            1, 1, np.nan, np.nan, data.size,
        )  # fmt: skip
    start_value = -first
    res = minimize(
        negative,
        x0,
        jac=True,
        method="L-BFGS-B",
        bounds=bounds,
        options={"maxfun": max_evaluations, "maxiter": max_evaluations},
    )
    evals, failed = int(state["evals"]), int(state["failed"])  # type: ignore[call-overload]
    final, _ = negative(np.asarray(res.x)) if np.all(np.isfinite(res.x)) else (np.inf, None)
    after_value = -final
    message = str(res.message)
    if not np.isfinite(after_value) or after_value < start_value - 1e-9:
        reason = f"kept the previous hyperparameters: the fit did not improve ({message})"
        return HyperFit(
            start, start, False, False, reason, evals, failed, start_value, start_value, data.size
        )
    return HyperFit(
        start,
        hyper_at(np.asarray(res.x)),
        True,
        bool(res.success),
        message,
        evals,
        failed,
        start_value,
        after_value,
        data.size,
    )
