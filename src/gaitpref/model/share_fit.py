"""The new subject's shared fraction from the evidence: a 1-D type-II MAP fit of ``share``.

The population kernel with the new subject's own loading (``population.py``): subject 0's
covariance with every earlier subject is ``sqrt(share rho) k(x, x')``, the earlier subjects'
``rho`` and the kernel held.  As the new subject answers, ``share`` is re-learned by maximising
the Laplace evidence (GPML eq. (3.32), ``evidence.py``) plus a logit-normal log prior over
``logit share`` (bounded at 3 prior sd), by Brent's bounded method on values only (no gradient:
one coordinate; ``scipy.optimize.minimize_scalar``).  Only the new subject's data can move it:
the earlier subjects' evidence does not depend on ``share``.  A fit that fails or does not improve
the objective keeps the starting value and says so (:class:`ShareFit`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import LinAlgError
from scipy.optimize import minimize_scalar

from gaitpref.checks import check_evaluations
from gaitpref.errors import ConvergenceError, PriorNotPositiveDefiniteError
from gaitpref.model.evidence import Hyperparameters, PairData
from gaitpref.model.laplace import LaplaceMode
from gaitpref.model.population import check_rho, logit, population_evidence
from gaitpref.model.population_fit import LogitNormal
from gaitpref.model.share_mix import ShareHypothesis, heaviest, share_prior, weigh_shares
from gaitpref.model.singles import SingleData, UnsupportedLikelihoodError
from gaitpref.model.threads import one_blas_thread
from gaitpref.space import Space

_FAILURES = (
    ConvergenceError,
    PriorNotPositiveDefiniteError,
    LinAlgError,
    FloatingPointError,
    UnsupportedLikelihoodError,  # a kind without third(): the evidence is not available
)
_EDGE = 1e-6


@dataclass(frozen=True)
class ShareFit:
    """One fit of the new subject's shared fraction: before and after (equal unless
    ``accepted``), with the objective (log evidence plus log prior) at both; or one weighing of
    share hypotheses (``hypotheses``; :func:`share_mixture_fit`)."""

    before: float
    after: float
    accepted: bool
    message: str
    evaluations: int
    objective_before: float
    objective_after: float
    #: with the share averaged (``share_mix.py``): the weighted hypotheses, ``after`` the
    #: heaviest one's share; empty for a MAP fit
    hypotheses: tuple[ShareHypothesis, ...] = ()
    #: each weighed hypothesis' Laplace fit by its share (not logged, not compared: what the
    #: posteriors under the hypotheses are built on, ``loop/cospar.py``); empty for a MAP fit
    fits: Mapping[float, LaplaceMode] = field(default_factory=dict, compare=False, repr=False)


def _sigmoid(x: float) -> float:
    return float(1.0 / (1.0 + np.exp(-x)))


def share_objective(
    space: Space,
    hyper: Hyperparameters,
    rho: float,
    share: float,
    data: PairData,
    prior: LogitNormal,
    singles: SingleData | None = None,
) -> float:
    """Log evidence plus the log prior of ``logit share`` (up to a constant)."""
    ev = population_evidence(space, hyper, rho, data, singles=singles, share=share, gradient=False)
    z = (logit(min(max(share, _EDGE), 1 - _EDGE)) - logit(prior.median)) / prior.sd
    return float(ev.value - 0.5 * z * z)


def fit_share(
    space: Space,
    hyper: Hyperparameters,
    rho: float,
    share: float,
    data: PairData,
    prior: LogitNormal,
    singles: SingleData | None = None,
    *,
    gate: float | None = None,
    max_evaluations: int = 25,
) -> ShareFit:
    """MAP ``share`` of subject 0 given population data (node codes), ``rho`` and ``hyper``
    held; from ``share`` (the start, also what is kept on failure).  With a ``gate`` (nats) the
    MAP is taken only where its log evidence exceeds that of ``share = 0`` (the subject alone)
    by more than ``gate``; otherwise ``share = 0``."""
    rho, share = check_rho(rho), check_rho(share)
    max_evaluations = check_evaluations(max_evaluations)
    if prior.sd <= 0 or not 0.0 < rho < 1.0 or data.size + (singles.size if singles else 0) == 0:
        return ShareFit(share, share, False, "nothing to fit", 0, np.nan, np.nan)
    if hyper.thresholds is not None:
        hyper = Hyperparameters(hyper.lengthscale, hyper.variance, hyper.jitter, hyper.band)
    centre = logit(prior.median)
    lo, hi = centre - 3 * prior.sd, centre + 3 * prior.sd
    evaluations = 0

    def negative(x: float) -> float:
        nonlocal evaluations
        evaluations += 1
        try:
            value = share_objective(space, hyper, rho, _sigmoid(x), data, prior, singles)
        except _FAILURES:
            return 1e10
        return -value if np.isfinite(value) else 1e10

    with one_blas_thread():
        start = float(np.clip(logit(min(max(share, _EDGE), 1 - _EDGE)), lo, hi))
        first = negative(start)
        if first >= 1e10:
            message = "kept the starting value: the evidence cannot be evaluated there"
            return ShareFit(share, share, False, message, 1, np.nan, np.nan)
        res = minimize_scalar(
            negative, bounds=(lo, hi), method="bounded",
            options={"maxiter": max_evaluations, "xatol": 0.05},
        )  # fmt: skip
    x, value = float(res.x), float(res.fun)
    if gate is not None:
        return _gated(space, hyper, rho, share, data, singles, _sigmoid(x), gate, evaluations)
    if not value < first:
        message = f"kept the starting value: the fit did not improve ({res.message})"
        return ShareFit(share, share, False, message, evaluations, -first, -first)
    return ShareFit(share, _sigmoid(x), True, str(res.message), evaluations, -first, -value)


def _gated(
    space: Space,
    hyper: Hyperparameters,
    rho: float,
    share: float,
    data: PairData,
    singles: SingleData | None,
    best: float,
    gate: float,
    evaluations: int,
) -> ShareFit:
    """``best`` if its log evidence beats the subject alone (``share = 0``) by ``gate``, else 0."""
    try:
        with one_blas_thread():
            alone = population_evidence(
                space, hyper, rho, data, singles=singles, share=0.0, gradient=False
            )
            shared = population_evidence(
                space, hyper, rho, data, singles=singles, share=best, gradient=False
            )
    except _FAILURES:
        message = "kept the starting value: the evidence cannot be evaluated at the gate"
        return ShareFit(share, share, False, message, evaluations + 2, np.nan, np.nan)
    margin = shared.value - alone.value
    if margin > gate:
        message = f"shares: the evidence favours {best:.3g} over 0 by {margin:.3g} nats"
        return ShareFit(share, best, True, message, evaluations + 2, alone.value, shared.value)
    message = f"alone: the evidence favours {best:.3g} over 0 by {margin:.3g} nats only"
    return ShareFit(share, 0.0, True, message, evaluations + 2, alone.value, shared.value)


def share_mixture_fit(
    space: Space,
    hyper: Hyperparameters,
    rho: float,
    share: float,
    data: PairData,
    singles: SingleData | None = None,
    hypotheses: Sequence[tuple[float, float]] | None = None,
) -> ShareFit:
    """The share ``hypotheses`` (``(share, prior mass)``; default ``share_mix.share_prior(rho)``)
    weighted by the evidence of the population data, as a :class:`ShareFit` from ``share`` to
    the mixture's mean share (the posterior in force is the one under it).  Its objectives: the
    alone hypothesis' log evidence plus log prior mass (before; NaN without one) and the log of
    their sum over the hypotheses, the mixture's (after)."""
    rho, share = check_rho(rho), check_rho(share)
    given = share_prior(rho) if hypotheses is None else tuple(hypotheses)
    fits: dict[float, LaplaceMode] = {}
    with one_blas_thread():
        weighed = weigh_shares(space, hyper, rho, given, data, singles, fits=fits)
    mean = min(sum(h.weight * h.share for h in weighed), 1.0)
    top = heaviest(weighed)
    alone = next((h.objective for h in weighed if h.share == 0.0), None)
    finite = np.array([h.objective for h in weighed if h.objective is not None])
    total = (
        float(finite.max() + np.log(np.exp(finite - finite.max()).sum())) if finite.size else np.nan
    )
    weight0 = sum(h.weight for h in weighed if h.share == 0.0)
    message = (
        f"mixture: mean share {mean:.3g}, weight {weight0:.3g} alone, heaviest {top.share:.3g} "
        f"({top.weight:.3g})"
    )
    return ShareFit(
        share, mean, True, message, len(weighed), np.nan if alone is None else alone, total,
        weighed, fits,
    )  # fmt: skip


__all__ = ["ShareFit", "fit_share", "share_mixture_fit", "share_objective"]
