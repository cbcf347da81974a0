"""How sure are we: the chance that the recommended gait is good enough, and when to stop.

From joint posterior samples ``f^(1..S)`` of the smooth utility (pathwise,
``model/posterior.py``, ``nugget=False``) and the recommended gait ``r`` (the posterior mean's
argmax, the gait blind validation calls "max"; with gaits made on demand, the argmax among the
gaits made, while ``max f`` is still over every gait: ``among`` in :func:`confidence`):

- the probability that ``r`` is within a tolerance of the subject's best,
  ``P(max f - f_r <= tol (max f - min f))``, with the tolerance a fraction of the utility's
  range (the same normalisation as the paper's normalised objective, Fig. 4);
- the expected shortfall (simple regret) of stopping now, ``E[max f - f_r]``, in utility units
  and as a fraction of the range.

The samples leave out the kernel's jitter (``kernels.py``: the paper's "noise variance", an
independent term per gait; 10% of the prior variance in the synthetic configs): the question is
about the subject's utility over the gait parameters, and with the jitter in every sampled gait
"the best" of a sample is the largest of many independent draws, a gait no answer could point
to, and the probability falls far below the observed frequency
(``docs/results/population/``).

Both are Monte Carlo averages over ``samples`` draws (their standard error is at most
``0.5 / sqrt(samples)``), computed in blocks so that no more than :data:`BLOCK_ELEMENTS` values
are held (the posterior's own sampling adds its bounded blocks).  Every draw covers every gait,
so the time grows with ``samples x gaits``: a :class:`StopRule` reads at most
:data:`CONFIDENCE_VALUES` sampled values (:meth:`StopRule.samples_for`: fewer samples on large
grids, never fewer than :data:`MIN_RULE_SAMPLES`).
A :class:`StopRule` (the config's ``[stop]`` table) says when a session has learnt enough:
once the probability reaches ``confidence``, or after ``max_trials`` executed trials.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from gaitpref.checks import check_mask, is_count, is_number
from gaitpref.model.posterior import Posterior
from gaitpref.model.share_mix import PosteriorMixture
from gaitpref.model.threads import one_blas_thread
from gaitpref.wording import plural

#: At most this many sampled values (``block x A``) are held at once: 32 MiB.
BLOCK_ELEMENTS = 1 << 22
#: The most samples one confidence reads (a config's ``[stop] samples`` too): each is a draw
#: over every gait, so 10**12 ran for days, one block at a time.
MAX_SAMPLES = 100_000
#: The most sampled values (``samples x gaits``) a session's confidence reads after an answer:
#: 2000 samples took 7.5 s over 57,750 gaits and 2 minutes over 2**20 (2 cores, nearly idle,
#: BLAS's default threads), after every answer and for every row of an export.  This budget
#: (290 samples over 57,750 gaits, 100 over 2**20) took 1.0 s and 5.9 s there; on one BLAS
#: thread, as the confidence runs now, 2.0 s and 5.2 s at load 4-5, where BLAS's default
#: threads took 3.7 s and 5.9 s (medians of 3; ``benchmarks/results/stopping.md``).
CONFIDENCE_VALUES = 1 << 24
#: The fewest samples a rule reads however large the grid (``[stop] samples``' least value):
#: the probability's standard error stays at most 0.05.
MIN_RULE_SAMPLES = 100


@dataclass(frozen=True)
class Confidence:
    """How sure the posterior is of its recommendation ``recommended`` (a grid index)."""

    recommended: int
    probability: float  # P(f_best - f_rec <= tolerance * range)
    regret: float  # E[f_best - f_rec], utility units
    relative_regret: float  # E[(f_best - f_rec) / range]
    tolerance: float
    samples: int

    def sentence(self, name: str) -> str:
        """``"88% that G95 is within 5% of the best"`` with ``name`` for the gait: the
        probability in whole percent rounded down (:func:`whole_percent`, never shown as
        reaching a ``[stop] confidence`` it has not reached), the tolerance as given
        (:func:`percent`)."""
        return (
            f"{whole_percent(self.probability)} that {name} is within "
            f"{percent(self.tolerance)} of the best"
        )

    def to_json(self) -> dict[str, object]:
        return {
            "recommended": self.recommended,
            "probability": self.probability,
            "regret": self.regret,
            "relative_regret": self.relative_regret,
            "tolerance": self.tolerance,
            "samples": self.samples,
        }


def whole_percent(fraction: float) -> str:
    """``fraction`` in whole percent, rounded down: 0.897 is ``"89%"``, not the ``"90%"``
    that rounding gave while a ``[stop] confidence = 0.9`` had not been reached (and 0.9995
    ``"100%"``); a hair below a whole percent (0.29 is 28.999... in floating point) is that
    percent."""
    return f"{math.floor(fraction * 100 + 1e-9):d}%"


def percent(fraction: float) -> str:
    """``fraction`` in percent as given, to four significant digits: 0.05 is ``"5%"``, 0.025
    ``"2.5%"`` (not ``"2%"``) and a ``[stop] confidence = 0.999`` ``"99.9%"`` (not
    ``"100%"``)."""
    return f"{fraction * 100:.4g}%"


def _check_samples(samples: object) -> None:
    if not is_count(samples) or not 1 <= samples <= MAX_SAMPLES:  # type: ignore[operator]
        raise ValueError(f"samples must be an integer in 1..{MAX_SAMPLES}, got {samples!r}")


def check_tolerance(tolerance: float) -> float:
    if not is_number(tolerance):
        raise ValueError(f"tolerance must be a fraction in [0, 1), got {tolerance!r}")
    value = float(tolerance)
    if not (np.isfinite(value) and 0.0 <= value < 1.0):
        raise ValueError(f"tolerance must be a fraction in [0, 1), got {tolerance!r}")
    return value


def recommendation(mean: ArrayLike, allowed: NDArray[np.bool_] | None = None) -> int:
    """The recommended gait: the posterior ``mean``'s argmax among the ``allowed`` gaits (None:
    all; at least one must be), the lowest index among exact ties."""
    masked = np.array(mean, dtype=float)
    if allowed is not None:
        masked[~allowed] = -np.inf
    return int(np.argmax(masked))


def preference_learned(mean: ArrayLike) -> bool:
    """Whether the posterior ``mean`` (over the gaits) tells any gait apart: False while it is
    the same everywhere (before any answer, or after ties only), when the recommendation
    (:func:`recommendation`) and the argmax name the first gait for no reason.  The console then
    says "No preference learned yet", ``session show`` the same, and the figures mark no gait."""
    values = np.asarray(mean, dtype=float)
    return bool(values.size) and bool(values.max() > values.min())


def confidence(
    posterior: Posterior,
    rng: np.random.Generator,
    *,
    tolerance: float = 0.05,
    samples: int = 2000,
    allowed: NDArray[np.bool_] | None = None,
    block: int | None = None,
    draws: PosteriorMixture | None = None,
    among: NDArray[np.bool_] | None = None,
) -> Confidence:
    """The :class:`Confidence` of ``posterior`` from ``samples`` joint draws with ``rng``.

    ``allowed`` restricts both the recommendation and "the best" to the gaits that may be
    proposed (a region of avoidance, unsafe flags); None: all.  ``among`` restricts the
    recommendation alone, further, to the gaits that may be recommended (gaits made on demand:
    the gaits made), while "the best" is still sought among all the ``allowed`` gaits: the
    probability is that of the best gait one may walk now being within the tolerance of the
    best anywhere (None: the recommendation is chosen among the ``allowed`` gaits, as "the
    best").  ``block`` samples are held at a time (default: as many as fit in
    :data:`BLOCK_ELEMENTS` values, at most 256).  ``draws``: a mixture the samples come from
    instead (a warm start's share hypotheses, ``model/share_mix.py``); the recommendation is
    still ``posterior``'s.
    """
    tolerance = check_tolerance(tolerance)
    if block is None:
        block = max(1, min(256, BLOCK_ELEMENTS // len(posterior.space)))
    _check_samples(samples)
    if not is_count(block) or block < 1:
        raise ValueError(f"block must be an integer >= 1, got {block!r}")
    gaits = len(posterior.space)
    if allowed is not None:
        empty = "no gait is allowed: there is nothing to recommend"
        allowed = check_mask(allowed, gaits, what="gaits", optional=True, empty=empty)
    chosen_from = allowed
    if among is not None:
        among = np.asarray(among)
        if among.dtype != np.bool_ or among.shape != (gaits,):
            raise ValueError(
                f"among must be None or a boolean mask over the {gaits} gaits, got dtype "
                f"{among.dtype} and shape {among.shape}"
            )
        chosen_from = among if allowed is None else among & allowed
        if not chosen_from.any():
            raise ValueError(
                "no gait of among is allowed: there is nothing to recommend"
                if among.any()
                else "among names no gait: there is nothing to recommend"
            )
    hits = 0
    shortfall = relative = 0.0
    done = 0
    with one_blas_thread():  # as ask and tell (model/threads.py): many times faster under load
        rec = recommendation(posterior.mean, chosen_from)
        while done < samples:
            size = min(block, samples - done)
            f = (posterior if draws is None else draws).sample(rng, size, nugget=False)
            if allowed is not None:
                f = f[:, allowed]
                at = int(np.count_nonzero(allowed[:rec]))
            else:
                at = rec
            best, worst = f.max(axis=1), f.min(axis=1)
            gap = best - f[:, at]
            span = best - worst
            hits += int(np.count_nonzero(gap <= tolerance * span))
            shortfall += float(gap.sum())
            relative += float(np.sum(np.divide(gap, span, out=np.zeros_like(gap), where=span > 0)))
            done += size
    return Confidence(rec, hits / samples, shortfall / samples, relative / samples, tolerance, done)


@dataclass(frozen=True)
class StopRule:
    """The config's ``[stop]``: stop once ``P(within tolerance) >= confidence`` or after
    ``max_trials`` executed trials (either None: not used; both None: no rule)."""

    confidence: float | None = None
    max_trials: int | None = None
    tolerance: float = 0.05
    samples: int = 2000

    def samples_for(self, actions: int) -> int:
        """The samples a confidence over ``actions`` gaits reads: :attr:`samples`, or fewer where
        they would pass :data:`CONFIDENCE_VALUES` sampled values, but never fewer than
        :data:`MIN_RULE_SAMPLES` (then its time grows with the grid, as one ask's does)."""
        if not is_count(actions) or actions < 1:
            raise ValueError(f"actions must be an integer >= 1, got {actions!r}")
        return min(self.samples, max(MIN_RULE_SAMPLES, CONFIDENCE_VALUES // actions))

    def __post_init__(self) -> None:
        if self.confidence is not None and not (
            is_number(self.confidence) and 0.0 < self.confidence <= 1.0
        ):
            raise ValueError(f"confidence must lie in (0, 1], got {self.confidence!r}")
        if self.max_trials is not None and not (is_count(self.max_trials) and self.max_trials >= 1):
            raise ValueError(f"max_trials must be an integer >= 1, got {self.max_trials!r}")
        check_tolerance(self.tolerance)
        _check_samples(self.samples)

    @property
    def active(self) -> bool:
        return self.confidence is not None or self.max_trials is not None

    def reason(self, trials: int, sure: Confidence | None, name: str | None = None) -> str | None:
        """Why to stop after ``trials`` executed trials with confidence ``sure`` (None: go on);
        ``name``: the recommended gait's, as its confidence sentence names it (default
        ``gait <index>``)."""
        if self.max_trials is not None and trials >= self.max_trials:
            return f"{plural(trials, 'trial')} reached max_trials = {self.max_trials}"
        if self.confidence is None or sure is None or sure.probability < self.confidence:
            return None
        gait = f"gait {sure.recommended}" if name is None else name
        return f"{sure.sentence(gait)} (confidence = {percent(self.confidence)})"


__all__ = [
    "CONFIDENCE_VALUES",
    "MIN_RULE_SAMPLES",
    "Confidence",
    "StopRule",
    "check_tolerance",
    "confidence",
    "preference_learned",
    "recommendation",
]
