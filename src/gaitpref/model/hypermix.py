"""Lengthscale hypotheses weighted by their Laplace evidence and prior (issue 16, item 2).

Instead of one type-II MAP kernel (``hyperfit.py``), the posterior over the lengthscales is
approximated on a small log-grid of hypotheses ``l_k = c_k * l_MAP`` (every feature's
lengthscale scaled together): Bayesian model averaging over a discrete set of kernels (GPML
Section 5.2; Rasmussen and Williams 2006), with the Laplace approximation of each marginal
likelihood (GPML Eq. 3.32, ``evidence.py``).  With the grid equally spaced in ``log l`` and
the prior log-normal in ``log l`` (``hyperfit.py``), the quadrature weights are equal and

    w_k  proportional to  q(D | l_k) * p(log l_k),

normalised over ``k``.  A hypothesis whose Laplace fit fails gets weight 0; if every one fails,
the centre (``c = 1`` when present, else the first) keeps weight 1.  The fits are warm-started
in turn from the previous hypothesis' mode.  The loop (``loop/cospar.py``) draws a hypothesis
by weight before each Thompson draw and recommends the argmax of the mixture's mean.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.linalg import LinAlgError

from gaitpref.errors import ConvergenceError, PriorNotPositiveDefiniteError
from gaitpref.model.evidence import Hyperparameters, PairData, laplace_evidence
from gaitpref.model.singles import SingleData
from gaitpref.space import FloatArray, Space

if TYPE_CHECKING:  # hyperfit.py records the hypotheses on its fits
    from gaitpref.model.hyperfit import HyperPrior

_FAILURES = (ConvergenceError, PriorNotPositiveDefiniteError, LinAlgError, FloatingPointError)


@dataclass(frozen=True)
class Hypothesis:
    """One lengthscale hypothesis: ``factor`` times the centre's lengthscales, its log evidence
    plus log lengthscale prior (None: its Laplace fit failed) and its normalised weight."""

    factor: float
    hyper: Hyperparameters
    objective: float | None
    weight: float

    def to_json(self) -> dict[str, object]:
        return {
            "factor": self.factor,
            "lengthscale": list(self.hyper.lengthscale),
            "objective": self.objective,
            "weight": self.weight,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any], centre: Hyperparameters) -> Hypothesis:
        """The hypothesis as :meth:`to_json` wrote it (its lengthscales on ``centre``)."""
        objective = data["objective"]
        return cls(
            float(data["factor"]),
            replace(centre, lengthscale=tuple(float(v) for v in data["lengthscale"])),
            None if objective is None else float(objective),
            float(data["weight"]),
        )


def log_lengthscale_prior(hyper: Hyperparameters, prior: HyperPrior) -> float:
    """``sum_i log N(log l_i; log median_i, sd_i^2)`` up to a constant (held entries skipped)."""
    out = 0.0
    for value, p in zip(hyper.lengthscale, prior.lengthscale, strict=True):
        if p.sd > 0:
            z = (math.log(value) - math.log(p.median)) / p.sd
            out -= 0.5 * z * z
    return out


def normalised(objectives: Sequence[float | None], fallback: int) -> list[float]:
    """``exp(objective)`` normalised over the hypotheses (None: weight 0); when every one is
    None, weight 1 at index ``fallback``."""
    finite = [o for o in objectives if o is not None]
    if not finite:
        return [1.0 if k == fallback else 0.0 for k in range(len(objectives))]
    top = max(finite)
    raw = np.array([0.0 if o is None else math.exp(o - top) for o in objectives])
    return [float(w) for w in raw / raw.sum()]


def weigh_hypotheses(
    space: Space,
    centre: Hyperparameters,
    factors: tuple[float, ...],
    data: PairData,
    prior: HyperPrior,
    *,
    singles: SingleData | None = None,
) -> tuple[Hypothesis, ...]:
    """The hypotheses ``factor * centre.lengthscale``, weighted by Laplace evidence x prior."""
    if not factors or any(not (math.isfinite(c) and c > 0) for c in factors):
        raise ValueError(f"hypotheses must be positive factors, got {factors!r}")
    hypers = [
        replace(centre, lengthscale=tuple(c * v for v in centre.lengthscale)) for c in factors
    ]
    objectives: list[float | None] = []
    mode: FloatArray | None = None
    for hyper in hypers:
        try:
            ev = laplace_evidence(space, hyper, data, mode, singles=singles)
            if not math.isfinite(ev.value):
                raise FloatingPointError("non-finite evidence")
        except _FAILURES:
            objectives.append(None)
            continue
        mode = ev.fit.mode
        objectives.append(ev.value + log_lengthscale_prior(hyper, prior))
    weights = normalised(objectives, factors.index(1.0) if 1.0 in factors else 0)
    return tuple(
        Hypothesis(c, h, o, w)
        for c, h, o, w in zip(factors, hypers, objectives, weights, strict=True)
    )
