"""The new subject's shared fraction as a mixture: share hypotheses weighted by evidence x prior.

Instead of one type-II MAP ``share`` (``share_fit.py``), the posterior over the new subject's
shared fraction (``population.py``: their covariance with the others is ``sqrt(share rho) k``)
is approximated on a small grid of hypotheses ``share_k = c_k rho`` (``c_k`` in ``[0, 1]``,
:data:`SHARE_FACTORS`) with prior masses ``pi_k`` that put real mass on ``share = 0``, the
subject alone (:func:`share_prior`): Bayesian model averaging over a discrete set of models
(GPML Section 5.2; Rasmussen and Williams 2006) with the Laplace approximation of each marginal
likelihood (GPML eq. (3.32), ``evidence.py``, through :func:`population_evidence`):

    w_k  proportional to  q(D | share_k) pi_k,

normalised over ``k``.  The earlier subjects' evidence does not depend on ``share``, so only the
new subject's answers move the weights; with none, the weights are the prior.  A hypothesis whose
Laplace fit fails gets weight 0; if every one fails, ``share = 0`` (else the first) keeps weight 1.
The hypotheses' fits are independent; on a clinic's data they run side by side in threads
(:data:`PARALLEL_OBSERVATIONS`), the value only (no gradient).

:class:`PosteriorMixture` is the mixture of the posteriors under the hypotheses: its mean is the
weighted mean, and each of its joint samples draws a hypothesis by weight and then a sample of
that hypothesis' Laplace posterior (``loop/stopping.py`` reads it as it reads one posterior).
A warm-started loop keeps as its own posterior the one under the mixture's mean share
``sum_k w_k share_k`` (``loop/cospar.py``).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from scipy.linalg import LinAlgError

from gaitpref.errors import ConvergenceError, PriorNotPositiveDefiniteError
from gaitpref.model.evidence import Hyperparameters, PairData
from gaitpref.model.hypermix import normalised
from gaitpref.model.laplace import LaplaceMode
from gaitpref.model.population import check_rho, population_evidence
from gaitpref.model.posterior import Posterior, check_generator, check_nugget, check_sample_size
from gaitpref.model.singles import SingleData, UnsupportedLikelihoodError
from gaitpref.model.threads import in_threads
from gaitpref.space import FloatArray, Space

_FAILURES = (
    ConvergenceError,
    PriorNotPositiveDefiniteError,
    LinAlgError,
    FloatingPointError,
    UnsupportedLikelihoodError,
)

#: The hypotheses' shares as fractions of the earlier subjects' ``rho``.
SHARE_FACTORS: tuple[float, ...] = (0.0, 0.25, 0.5, 0.75, 1.0)
#: The prior mass of ``share = 0`` (alone); the other hypotheses share the rest equally (0.2:
#: uniform over the five; 0.5 held back subjects who share, ``docs/results/population``).
ALONE_PRIOR = 0.2
#: From this many observations (the earlier subjects' and the new one's) the hypotheses are
#: weighed in threads, one per hypothesis up to the CPUs (``threads.in_threads``): each fit is
#: then tens of milliseconds to seconds of ``m x m`` work; below it, a thread costs more than it
#: saves.  The numbers are the same either way.
PARALLEL_OBSERVATIONS = 256


@dataclass(frozen=True)
class ShareHypothesis:
    """One share hypothesis: the share, its prior mass, its log evidence plus log prior mass
    (None: its Laplace fit failed, or not evaluated) and its normalised weight."""

    share: float
    prior: float
    objective: float | None
    weight: float

    def to_json(self) -> dict[str, object]:
        return dataclasses.asdict(self)

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> ShareHypothesis:
        """The hypothesis as :meth:`to_json` wrote it."""
        objective = data["objective"]
        return cls(
            float(data["share"]),
            float(data["prior"]),
            None if objective is None else float(objective),
            float(data["weight"]),
        )


def share_prior(
    rho: float, factors: Sequence[float] = SHARE_FACTORS, alone: float = ALONE_PRIOR
) -> tuple[tuple[float, float], ...]:
    """The hypotheses ``(c rho, pi)``: ``alone`` on ``c = 0`` and the rest split equally over
    the other factors (every factor must lie in ``[0, 1]``, each once)."""
    rho = check_rho(rho)
    if not factors or len(set(factors)) != len(factors):
        raise ValueError(f"share factors must be distinct, got {tuple(factors)!r}")
    if any(not (math.isfinite(c) and 0.0 <= c <= 1.0) for c in factors):
        raise ValueError(f"share factors must lie in [0, 1], got {tuple(factors)!r}")
    if not 0.0 <= alone <= 1.0:
        raise ValueError(f"the prior mass of share = 0 must lie in [0, 1], got {alone!r}")
    others = [c for c in factors if c != 0.0]
    if 0.0 not in factors:
        return tuple((c * rho, 1.0 / len(others)) for c in others)
    if not others:
        return ((0.0, 1.0),)
    rest = (1.0 - alone) / len(others)
    return tuple((c * rho, alone if c == 0.0 else rest) for c in factors)


def weigh_shares(
    space: Space,
    hyper: Hyperparameters,
    rho: float,
    hypotheses: Sequence[tuple[float, float]],
    data: PairData,
    singles: SingleData | None = None,
    *,
    fits: dict[float, LaplaceMode] | None = None,
) -> tuple[ShareHypothesis, ...]:
    """The hypotheses ``(share, prior mass)`` weighted by Laplace evidence x prior mass, given
    population data (node codes; the new subject is subject 0), ``rho`` and ``hyper`` held
    (fitted thresholds are dropped: the evidence holds them).  ``fits``, when given, receives
    each evaluated hypothesis' Laplace fit by its share (the posterior under that share is built
    on it: ``loop/cospar.py`` reuses them rather than fitting each again)."""
    if not hypotheses:
        raise ValueError("weigh_shares needs at least one hypothesis")
    if hyper.thresholds is not None:
        hyper = Hyperparameters(hyper.lengthscale, hyper.variance, hyper.jitter, hyper.band)
    observations = data.size + (singles.size if singles else 0)

    def objective(share: float, prior: float) -> tuple[float | None, LaplaceMode | None]:
        if prior <= 0:
            return None, None
        if observations == 0:
            return math.log(prior), None
        try:
            ev = population_evidence(
                space, hyper, rho, data, singles=singles, share=share, gradient=False
            )
        except _FAILURES:
            return None, None
        value = float(ev.value)
        return (value + math.log(prior) if math.isfinite(value) else None), ev.fit

    results = in_threads(
        [functools.partial(objective, s, p) for s, p in hypotheses],
        parallel=observations >= PARALLEL_OBSERVATIONS,
    )
    objectives = [o for o, _ in results]
    if fits is not None:
        for (share, _), (_, fit) in zip(hypotheses, results, strict=True):
            if fit is not None:
                fits[share] = fit
    shares = [s for s, _ in hypotheses]
    weights = normalised(objectives, shares.index(0.0) if 0.0 in shares else 0)
    return tuple(
        ShareHypothesis(s, p, o, w)
        for (s, p), o, w in zip(hypotheses, objectives, weights, strict=True)
    )


def heaviest(hypotheses: Sequence[ShareHypothesis]) -> ShareHypothesis:
    """The hypothesis of largest weight (the first of equals)."""
    return max(hypotheses, key=lambda h: h.weight)


@dataclass(frozen=True, eq=False)
class PosteriorMixture:
    """Posteriors over the same space with weights (summing to 1): the mean is the weighted
    mean; :meth:`sample` draws each sample's component by weight, then from that component."""

    components: tuple[tuple[float, Posterior], ...]

    def __post_init__(self) -> None:
        if not self.components:
            raise ValueError("a posterior mixture needs at least one component")
        weights = np.array([w for w, _ in self.components])
        if np.any(weights < 0) or not math.isclose(float(weights.sum()), 1.0, abs_tol=1e-9):
            raise ValueError(f"mixture weights must be >= 0 and sum to 1, got {weights!r}")

    @property
    def space(self) -> Space:
        return self.components[0][1].space

    @property
    def weights(self) -> FloatArray:
        return np.array([w for w, _ in self.components])

    @cached_property
    def mean(self) -> FloatArray:
        out: FloatArray = np.sum([w * np.asarray(p.mean) for w, p in self.components], axis=0)
        return out

    def sample(self, rng: np.random.Generator, size: int = 1, *, nugget: bool = True) -> FloatArray:
        """``size x A`` joint samples: the components by weight from ``rng`` (one draw of
        ``size`` indices), then each chosen component's samples in component order.  ``size``
        is checked as :meth:`Posterior.sample` checks it, before the components are drawn."""
        size = check_sample_size(size, len(self.space))
        check_generator(rng)  # an integer seed was an AttributeError in rng.choice
        check_nugget(nugget)
        if len(self.components) == 1:  # one component: its own samples, the generator as its
            return self.components[0][1].sample(rng, size, nugget=nugget)
        which = rng.choice(len(self.components), size=size, p=self.weights)
        out = np.empty((size, len(self.space)))
        for k, (_, posterior) in enumerate(self.components):
            rows = np.flatnonzero(which == k)
            if rows.size:
                out[rows] = posterior.sample(rng, rows.size, nugget=nugget)
        return out


__all__ = [
    "ALONE_PRIOR",
    "SHARE_FACTORS",
    "PosteriorMixture",
    "ShareHypothesis",
    "heaviest",
    "share_prior",
    "weigh_shares",
]
