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

Ordinal ratings whose thresholds the config leaves unset have them fitted too, as ``t_1`` and
the log gaps ``log(t_(j+1) - t_j)`` (any value keeps them increasing): ``t_1`` normal, the gaps
log-normal (:class:`ThresholdPrior`), centred at the prior predictive's quantiles (the rating
likelihood's own thresholds, ``Ordinal.thresholds_for``); ``sd = 0.7`` on the log gaps and the
prior's utility sd on ``t_1`` by default, bounds at 3 sd.  The rating noise stays fixed (as
``sigma``: ``evidence.py``).

:func:`fit_hyperparameters` never fails silently: a fit that raises, produces non-finite values
or does not improve the objective keeps the previous hyperparameters, and the returned
:class:`HyperFit` says what happened (``accepted``, ``converged``, ``message``).

Notation: ``d`` features, ``T`` fitted thresholds; ``theta`` has ``d + 2`` (``+ T``) entries, of
which the free ones are optimised.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import LinAlgError
from scipy.optimize import minimize

from gaitpref.checks import check_evaluations, is_number
from gaitpref.errors import ConvergenceError, PriorNotPositiveDefiniteError
from gaitpref.model.evidence import Hyperparameters, PairData, laplace_evidence
from gaitpref.model.hypermix import Hypothesis
from gaitpref.model.singles import SingleData
from gaitpref.model.threads import one_blas_thread
from gaitpref.space import FloatArray, Space


@dataclass(frozen=True)
class LogNormal:
    """``log x ~ N(log median, sd^2)``; ``sd = 0`` holds the parameter fixed."""

    median: float
    sd: float

    def __post_init__(self) -> None:
        # is_number first: a string was a NumPy TypeError, True a median of 1
        if not (is_number(self.median) and np.isfinite(self.median) and self.median > 0):
            raise ValueError(f"a prior's median must be positive, got {self.median!r}")
        if not (is_number(self.sd) and np.isfinite(self.sd) and self.sd >= 0):
            raise ValueError(f"a prior's sd must be >= 0, got {self.sd!r}")
        object.__setattr__(self, "median", float(self.median))
        object.__setattr__(self, "sd", float(self.sd))


@dataclass(frozen=True)
class ThresholdPrior:
    """Ordinal thresholds: ``t_1 ~ N(c_1, first_sd^2)``, ``log(t_(j+1) - t_j) ~ N(log(c_(j+1) -
    c_j), gap_sd^2)``, centred at the rating likelihood's own thresholds ``c`` (the prior
    predictive's quantiles, ``Ordinal.thresholds_for``).  ``first_sd`` None: the prior's
    utility sd ``sqrt(s^2)`` (the variance prior's median).  ``sd = 0`` holds them."""

    first_sd: float | None = None
    gap_sd: float = 0.7

    def __post_init__(self) -> None:
        for name, sd in (("first_sd", self.first_sd), ("gap_sd", self.gap_sd)):
            if sd is not None and not (is_number(sd) and np.isfinite(sd) and sd >= 0):
                raise ValueError(f"the thresholds' prior {name} must be >= 0, got {sd!r}")


@dataclass(frozen=True)
class HyperPrior:
    """Priors of the lengthscales (one per feature), the signal variance, the band and the
    ordinal thresholds.

    ``band`` None: the band is not fitted (ties dropped, or a band fixed by the config).  The
    thresholds are fitted only when there are ratings whose thresholds the config leaves unset.
    """

    lengthscale: tuple[LogNormal, ...]
    variance: LogNormal
    band: LogNormal | None = None
    thresholds: ThresholdPrior = ThresholdPrior()

    def __post_init__(self) -> None:
        # a float in place of a LogNormal was an AttributeError ('median') mid-fit
        scales = self.lengthscale
        if isinstance(scales, LogNormal) or not isinstance(scales, tuple | list):
            raise TypeError(
                f"lengthscale must be a tuple of LogNormal priors (one per feature), got {scales!r}"
            )
        for k, p in enumerate(scales):
            if not isinstance(p, LogNormal):
                raise TypeError(f"lengthscale[{k}] must be a LogNormal prior, got {p!r}")
        object.__setattr__(self, "lengthscale", tuple(scales))
        if not isinstance(self.variance, LogNormal):
            raise TypeError(f"variance must be a LogNormal prior, got {self.variance!r}")
        if self.band is not None and not isinstance(self.band, LogNormal):
            raise TypeError(f"band must be a LogNormal prior or None, got {self.band!r}")
        if not isinstance(self.thresholds, ThresholdPrior):
            raise TypeError(f"thresholds must be a ThresholdPrior, got {self.thresholds!r}")

    def all(self) -> tuple[LogNormal | None, ...]:
        return (*self.lengthscale, self.variance, self.band)

    def threshold_priors(self, centre: tuple[float, ...]) -> list[tuple[float, float]]:
        """``(centre, sd)`` of each threshold entry of ``theta`` (``t_1``, then log gaps)."""
        first = self.thresholds.first_sd
        first = float(np.sqrt(self.variance.median)) if first is None else first
        gaps = np.log(np.diff(np.asarray(centre, dtype=np.float64)))
        return [(centre[0], first), *((float(g), self.thresholds.gap_sd) for g in gaps)]


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
    #: lengthscale hypotheses around ``after`` and their weights (``hypermix.py``); empty when
    #: the loop keeps the one MAP kernel
    hypotheses: tuple[Hypothesis, ...] = ()

    def to_json(self) -> dict[str, object]:
        """A plain JSON record for logs (sessions store it with the answer that triggered it);
        a non-finite objective (a failed evaluation) is ``None``: JSON has no inf or nan."""

        def finite(x: float) -> float | None:
            return x if math.isfinite(x) else None

        def values(h: Hyperparameters) -> dict[str, object]:
            out: dict[str, object] = {
                "lengthscale": list(h.lengthscale),
                "signal_variance": h.variance,
                "jitter": h.jitter,
                "tie_band": h.band,
            }
            if h.thresholds is not None:  # only when fitted: older records stay as they were
                out["thresholds"] = list(h.thresholds)
            return out

        out: dict[str, object] = {
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
        if self.hypotheses:  # only when averaged: older records stay as they were
            out["hypotheses"] = [h.to_json() for h in self.hypotheses]
        return out


_FAILURES = (ConvergenceError, PriorNotPositiveDefiniteError, LinAlgError, FloatingPointError)


@dataclass(frozen=True)
class _Entries:
    """Per entry of ``theta``: prior centre and sd (in ``theta``'s coordinates), free or held,
    and bounds."""

    centre: FloatArray
    sd: FloatArray
    free: NDArray[np.bool_]
    bounds: list[tuple[float, float]]


def prior_bounds(
    space: Space, priors: list[tuple[float, float] | None]
) -> list[tuple[float, float]]:
    """Bounds of each entry of ``theta`` from its prior ``(centre, sd)`` (None: unbounded):
    3 sd either side, and a log lengthscale (the first ``d`` entries) never below half its
    feature's grid step."""
    bounds = []
    for k, p in enumerate(priors):
        if p is None:
            bounds.append((-np.inf, np.inf))
            continue
        lo, hi = p[0] - 3 * p[1], p[0] + 3 * p[1]
        step = space.features[k].step if k < space.ndim else None
        if step is not None:
            lo = max(lo, float(np.log(0.5 * step)))
            hi = max(hi, lo)
        bounds.append((float(lo), float(hi)))
    return bounds


def _entries(
    space: Space, prior: HyperPrior, start: Hyperparameters, singles: SingleData | None
) -> _Entries:
    priors: list[tuple[float, float] | None] = [
        None if p is None else (float(np.log(p.median)), p.sd) for p in prior.all()
    ]
    if start.thresholds is not None:
        centre = None if singles is None else singles.thresholds
        if centre is None:  # fitted before; no ratings to fit them now: held
            priors += [None] * len(start.thresholds)
        else:
            priors += prior.threshold_priors(centre)
    free = np.array([p is not None and p[1] > 0 for p in priors])
    bounds = prior_bounds(space, priors)
    return _Entries(
        np.array([p[0] if p else 0.0 for p in priors]),
        np.array([p[1] if p else 1.0 for p in priors]),
        free,
        bounds,
    )


def _with_thresholds(start: Hyperparameters, singles: SingleData | None) -> Hyperparameters:
    """``start`` with the thresholds to fit (the likelihood's own when not fitted before)."""
    own = None if singles is None else singles.thresholds
    if own is None:
        return start
    if start.thresholds is None:
        return replace(start, thresholds=own)
    if len(start.thresholds) != len(own):
        raise ValueError(
            f"the ratings have {len(own)} thresholds; the hyperparameters {len(start.thresholds)}"
        )
    return start


def fit_hyperparameters(
    space: Space,
    start: Hyperparameters,
    data: PairData,
    prior: HyperPrior,
    *,
    singles: SingleData | None = None,
    max_evaluations: int = 60,
) -> HyperFit:
    """MAP hyperparameters for ``data`` (and single-action terms ``singles``) by L-BFGS-B from
    ``start`` (see the module docstring).  Ratings whose thresholds are not fixed have them
    fitted too; ``after.thresholds`` then holds them (``start``'s, or the likelihood's own the
    first time, are the starting values)."""
    max_evaluations = check_evaluations(max_evaluations)
    # one prior and one starting lengthscale a feature (a prior short of one was a NumPy
    # "boolean index did not match" IndexError)
    if not isinstance(prior, HyperPrior):
        raise TypeError(f"prior must be a HyperPrior, got {prior!r}")
    if not len(prior.lengthscale) == len(start.lengthscale) == space.ndim:
        raise ValueError(
            f"the space has {space.ndim} features; the prior has {len(prior.lengthscale)} "
            f"lengthscale priors and the start {len(start.lengthscale)} lengthscales"
        )
    if singles is not None and singles.size == 0:
        singles = None
    if prior.band is not None and start.band <= 0:
        raise ValueError("fitting the band needs a positive starting band")
    used = _with_thresholds(start, singles)
    entries = _entries(space, prior, used, singles)
    size = data.size + (0 if singles is None else singles.size)
    if size == 0 or not np.any(entries.free):
        return HyperFit(start, start, False, True, "nothing to fit", 0, 0, np.nan, np.nan, 0)
    with one_blas_thread():
        return _fit(space, start, used, data, singles, entries, max_evaluations)


class _Objective:
    """``-(log evidence + log prior)`` over the free log-parameters, warm-starting each mode."""

    def __init__(
        self,
        space: Space,
        start: Hyperparameters,
        data: PairData,
        singles: SingleData | None,
        entries: _Entries,
    ) -> None:
        self.space, self.start, self.data, self.singles = space, start, data, singles
        self.free = free = entries.free
        self.theta0 = start.log_vector()
        self.centre, self.sd = entries.centre[free], entries.sd[free]
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
            ev = laplace_evidence(
                self.space, self.hyper(x), self.data, self.mode, singles=self.singles
            )
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
    used: Hyperparameters,
    data: PairData,
    singles: SingleData | None,
    entries: _Entries,
    max_evaluations: int,
) -> HyperFit:
    free = entries.free
    size = data.size + (0 if singles is None else singles.size)
    bounds = [b for b, keep in zip(entries.bounds, free, strict=True) if keep]
    objective = _Objective(space, used, data, singles, entries)
    x0 = np.clip(objective.theta0[free], [b[0] for b in bounds], [b[1] for b in bounds])
    first, _ = objective(x0)
    if objective.failures:
        message = "kept the previous hyperparameters: the evidence cannot be evaluated at the start"
        return HyperFit(start, start, False, False, message, 1, 1, np.nan, np.nan, size)
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
        return HyperFit(start, start, False, False, message, evals, failed, before, before, size)
    message = str(res.message) + (f"; {failed} evaluations failed" if failed else "")
    return HyperFit(
        start, objective.hyper(best_x), True, bool(res.success) and not failed, message, evals,
        failed, before, after, size,
    )  # fmt: skip


def hyper_from_json(values: Mapping[str, Any], like: Hyperparameters) -> Hyperparameters:
    """Hyperparameters as :meth:`HyperFit.to_json` logged them (its ``before`` or ``after``); a
    value the log leaves out (``tie_band`` None, ``thresholds`` absent: not fitted) stays as in
    ``like``."""
    band = values.get("tie_band")
    thresholds = values.get("thresholds")
    return Hyperparameters(
        tuple(float(v) for v in values["lengthscale"]),
        float(values["signal_variance"]),
        float(values["jitter"]),
        like.band if band is None else float(band),
        like.thresholds if thresholds is None else tuple(float(t) for t in thresholds),
    )
