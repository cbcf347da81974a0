"""Warm starts: earlier subjects' answers in a new subject's model, through the population kernel.

A :class:`WarmStart` holds the earlier subjects' observations as population data (node codes
``subject * A + gait``, ``model/population.py``; the new subject is subject 0, the earlier ones
1, 2, ...) and the shared fraction ``rho``.  :func:`warm_start` builds it from each earlier
subject's observations and learns ``rho`` by the evidence when two or more earlier subjects are
given (how alike they are to each other); with one, ``rho`` is the prior's median.

An earlier subject is either their preferences alone (what warm starts carried first, kept for
the sessions that recorded it) or an :class:`Earlier`: every registered kind's terms in force,
pair terms (preferences, and ties when the new loop models them) and single-action terms
(ratings), each made with the new loop's likelihood (:func:`warm_terms`), as its own answers
are, except that a preference keeps the probit noise it carries (its own session's).  The new
subject's answers join those data in every fit (``CoSpar.warm_start``): with ``rho = 0`` their
posterior is the one they would have had alone.

Re-learning the new subject's share (``relearn_every = k > 0``, what sessions created now
record): every ``k`` of the new subject's answers, the new subject's own shared fraction
``share`` (``model/population.py``: their covariance with the others is ``sqrt(share rho) k``)
is refitted by the evidence of all the data, the others' ``rho`` and the kernel held
(:func:`relearn_share`, ``model/share_fit.py``), under a logit-normal prior centred on ``rho``:
the others' data set where it starts, the new subject's answers move it, and a subject unlike
the others is let go of them.  With ``average`` (the loop's ``[model] share = "average"``) the
share is not one value but a mixture over share hypotheses weighted by evidence x prior
(``model/share_mix.py``, :func:`~gaitpref.model.share_fit.share_mixture_fit`): ``share`` is
then the mixture's mean share, and the hypotheses ride on the
:class:`~gaitpref.model.share_fit.ShareFit`.
``relearn_every = 0`` (warm starts recorded before) holds ``share = rho`` for the whole session,
as they were run.

A new subject who starts alone would walk a blind first trial; with ``Learning.warm_first =
"recommended"`` (configs' default since defaults version 0.8) the loop walks the population's
recommendation first, the argmax of the new subject's posterior mean at ``share = rho``
(``CoSpar._warm_first``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gaitpref.checks import is_count, is_number
from gaitpref.feedback import ActionObservation, ModelContext, Preference, Tie, kinds
from gaitpref.loop.learning import pair_data
from gaitpref.model.evidence import Hyperparameters, PairData
from gaitpref.model.gp import PreferenceGP
from gaitpref.model.hyperfit import HyperPrior
from gaitpref.model.laplace import LaplaceMode
from gaitpref.model.likelihood import ActionLikelihood, StackedActionLikelihood
from gaitpref.model.population import PopulationModel, check_rho
from gaitpref.model.population_fit import LogitNormal, fit_population
from gaitpref.model.posterior import Posterior
from gaitpref.model.share_fit import ShareFit, fit_share, share_mixture_fit
from gaitpref.model.singles import SingleData
from gaitpref.space import IntArray, Space

# warm starts made now: the new subject starts alone (share 0) and, after every answer, shares
# as much as the evidence says if it favours sharing over being alone (SHARE_GATE nats)
RELEARN_EVERY = 1
SHARE_GATE = 0.0


@dataclass(frozen=True)
class WarmStart:
    """Earlier subjects' observations (node codes; the new subject is 0) and ``rho``; the new
    subject's own ``share`` (None: ``rho``), re-learned every ``relearn_every`` answers (0:
    never) under ``share_prior`` (default: centred on ``rho``, sd 1.5)."""

    data: PairData
    rho: float
    subjects: int  # earlier subjects
    singles: SingleData | None = None  # their single-action terms (node codes), if any
    share: float | None = None
    relearn_every: int = 0
    share_prior: LogitNormal | None = None
    gate: float | None = None  # nats the evidence must favour sharing by (None: plain MAP)

    def __post_init__(self) -> None:
        if not isinstance(self.data, PairData):
            raise TypeError(f"data must be a PairData (node codes), got {self.data!r}")
        if self.singles is not None and not isinstance(self.singles, SingleData):
            raise TypeError(f"singles must be a SingleData or None, got {self.singles!r}")
        object.__setattr__(self, "rho", check_rho(self.rho))
        if self.share is not None:
            object.__setattr__(self, "share", check_rho(self.share))
        # 2.5 re-learned every 5 answers (answers % 2.5), -1 or "2" failed at an answer
        for name in ("subjects", "relearn_every"):
            value = getattr(self, name)
            if not is_count(value) or value < 0:
                raise ValueError(f"{name} must be an integer >= 0, got {value!r}")
            object.__setattr__(self, name, int(value))
        if self.share_prior is not None and not isinstance(self.share_prior, LogitNormal):
            raise TypeError(f"share_prior must be a LogitNormal or None, got {self.share_prior!r}")
        gate = self.gate
        if gate is not None and not (is_number(gate) and np.isfinite(gate) and gate >= 0):
            # NaN never let the evidence favour sharing: the share was 0, silently
            raise ValueError(f"gate must be None or a number of nats >= 0, got {gate!r}")

    @property
    def prior_of_share(self) -> LogitNormal:
        """The prior of the new subject's share: the given one, else centred on ``rho``."""
        if self.share_prior is not None:
            return self.share_prior
        return LogitNormal(min(max(self.rho, 1e-3), 1 - 1e-3), 1.5)

    def relearns(self, answers: int) -> bool:
        """Whether the share is refitted after the new subject's ``answers``-th answer."""
        return self.relearn_every > 0 and answers > 0 and answers % self.relearn_every == 0


@dataclass(frozen=True)
class Earlier:
    """One earlier subject's terms in force: preferences, ties and single-action observations."""

    preferences: Sequence[Preference]
    ties: Sequence[Tie] = ()
    singles: Sequence[ActionObservation] = ()


def warm_terms(
    context: ModelContext, model_ties: bool, earlier: Sequence[Earlier]
) -> tuple[PairData, SingleData | None]:
    """The earlier subjects' terms as population data (subject ``k + 1`` for the k-th), made as
    the new loop makes its own (``context``: its noise and rating scale; ties modelled or not):
    pair terms by :func:`~gaitpref.loop.learning.pair_data`, single-action terms by each
    registered kind's likelihood."""
    size = len(context.space)
    offsets = [(k + 1) * size for k in range(len(earlier))]
    parts = [pair_data(e.preferences, e.ties, context.noise, model_ties) for e in earlier]
    shifted = list(zip(parts, offsets, strict=True))
    data = PairData(
        np.concatenate([np.zeros(0, np.intp)] + [d.first + o for d, o in shifted]),
        np.concatenate([np.zeros(0, np.intp)] + [d.second + o for d, o in shifted]),
        np.concatenate([np.zeros(0)] + [d.sigma for d in parts]),
        np.concatenate([np.zeros(0, bool)] + [d.banded for d in parts]),
        np.concatenate([np.zeros(0, bool)] + [d.tie for d in parts]),
    )
    codes: list[int] = []
    likelihoods: list[tuple[int, ActionLikelihood]] = []
    for kind in kinds():
        mine = [(o, k) for k, e in enumerate(earlier) for o in e.singles if o.kind == kind.name]
        if mine:
            codes += [offsets[k] + o.action for o, k in mine]
            likelihoods.append((len(mine), kind.action_likelihood([o for o, _ in mine], context)))
    if not codes:
        return data, None
    stacked = StackedActionLikelihood(tuple(likelihoods))
    return data, SingleData(np.asarray(codes, dtype=np.intp), stacked)


def warm_data(space: Space, earlier: Sequence[Sequence[Preference]]) -> PairData:
    """The earlier subjects' preferences as population data (subject ``k + 1`` for the k-th)."""
    size = len(space)
    first = [(k + 1) * size + p.winner for k, prefs in enumerate(earlier) for p in prefs]
    second = [(k + 1) * size + p.loser for k, prefs in enumerate(earlier) for p in prefs]
    sigma = [p.noise for prefs in earlier for p in prefs]
    n = len(sigma)
    return PairData(
        np.array(first, dtype=np.intp), np.array(second, dtype=np.intp),
        np.array(sigma, dtype=np.float64), np.zeros(n, dtype=bool), np.zeros(n, dtype=bool),
    )  # fmt: skip


def warm_start(
    space: Space,
    hyper: Hyperparameters,
    prior: HyperPrior,
    earlier: Sequence[Sequence[Preference]] | Sequence[Earlier],
    rho_prior: LogitNormal | None = None,
    *,
    context: ModelContext | None = None,
    model_ties: bool = False,
) -> WarmStart:
    """The warm start from the earlier subjects: their preferences (one sequence per subject),
    or every term of theirs (:class:`Earlier`, made with the new loop's ``context`` and
    ``model_ties``; :func:`warm_terms`)."""
    rho_prior = LogitNormal() if rho_prior is None else rho_prior
    singles = None
    terms = [e for e in earlier if isinstance(e, Earlier)]
    if terms:
        if context is None or len(terms) != len(earlier):
            raise ValueError("earlier subjects' terms (Earlier) need the new loop's context")
        data, singles = warm_terms(context, model_ties, terms)
        counts = [len(e.preferences) + len(e.ties) + len(e.singles) for e in terms]
    else:
        prefs = [e for e in earlier if not isinstance(e, Earlier)]
        data = warm_data(space, prefs)
        counts = [len(p) for p in prefs]
    rho = rho_prior.median
    with_data = sum(1 for c in counts if c)
    if with_data >= 2 and rho_prior.sd > 0:
        held = HyperPrior(
            tuple(type(p)(p.median, 0.0) for p in prior.lengthscale),
            type(prior.variance)(prior.variance.median, 0.0),
        )  # only rho: the kernel stays the config's (the new subject's refits move it)
        rho = fit_population(space, hyper, rho, data, held, rho_prior, singles=singles).rho_after
    return WarmStart(data, rho, len(earlier), singles)


def relearning(warm: WarmStart, every: int = RELEARN_EVERY) -> WarmStart:
    """``warm`` as warm starts are made now: the new subject starts alone (``share = 0``) and
    their share is re-learned every ``every`` answers, gated by :data:`SHARE_GATE` nats."""
    return dataclasses.replace(warm, share=0.0, relearn_every=every, gate=SHARE_GATE)


def _parts(size: int, likelihood: ActionLikelihood) -> tuple[tuple[int, ActionLikelihood], ...]:
    """A likelihood's blocks, a stacked one's flattened (the evidence needs flat parts)."""
    if isinstance(likelihood, StackedActionLikelihood):
        return likelihood.parts
    return ((size, likelihood),)


def _held(likelihood: ActionLikelihood) -> ActionLikelihood:
    """The likelihood with its thresholds held (the share fit fits ``share`` alone)."""
    if getattr(likelihood, "thresholds_fixed", True) is False and dataclasses.is_dataclass(
        likelihood
    ):
        held: ActionLikelihood = dataclasses.replace(likelihood, thresholds_fixed=True)
        return held
    return likelihood


def _joined(
    warm: WarmStart,
    own: PairData,
    single: IntArray | None,
    single_likelihood: ActionLikelihood | None,
) -> tuple[PairData, IntArray | None, ActionLikelihood | None]:
    """The new subject's observations first, then the earlier subjects'."""
    data = PairData(
        np.concatenate([own.first, warm.data.first]),
        np.concatenate([own.second, warm.data.second]),
        np.concatenate([own.sigma, warm.data.sigma]),
        np.concatenate([own.banded, warm.data.banded]),
        np.concatenate([own.tie, warm.data.tie]),
    )
    if warm.singles is not None:  # the new subject's single-action terms first, then theirs
        theirs = warm.singles
        if single is None or single_likelihood is None:
            single, single_likelihood = theirs.actions, theirs.likelihood
        else:
            single_likelihood = StackedActionLikelihood(
                (
                    *_parts(single.shape[0], single_likelihood),
                    *_parts(theirs.size, theirs.likelihood),
                )
            )
            single = np.concatenate([single, theirs.actions])
    return data, single, single_likelihood


def warm_posterior(
    warm: WarmStart,
    gp: PreferenceGP,
    own: PairData,
    band: float,
    single: IntArray | None = None,
    single_likelihood: ActionLikelihood | None = None,
    fit: LaplaceMode | None = None,
) -> Posterior:
    """The new subject's posterior given their own observations ``own`` (grid indices) and the
    earlier subjects' (``warm``), in one population fit (``fit``: that fit, already made)."""
    data, single, single_likelihood = _joined(warm, own, single, single_likelihood)
    model = PopulationModel(
        gp.space, gp.kernel, warm.rho, gp.noise, gp.sampler, gp.ordinal, warm.share
    )
    return model.posterior(
        data.first, data.second, data.likelihood(band), 0,
        single=single, single_likelihood=single_likelihood, fit=fit,
    )  # fmt: skip


def relearn_share(
    warm: WarmStart,
    space: Space,
    hyper: Hyperparameters,
    own: PairData,
    single: IntArray | None = None,
    single_likelihood: ActionLikelihood | None = None,
    *,
    average: bool = False,
) -> ShareFit:
    """The new subject's share refitted by the evidence of all the data (theirs and the earlier
    subjects'), from the current one (``model/share_fit.py``); with ``average``, the share
    hypotheses weighed instead (``model/share_mix.py``), the heaviest one's share kept."""
    data, single, single_likelihood = _joined(warm, own, single, single_likelihood)
    singles = None
    if single is not None and single_likelihood is not None:
        parts = tuple((n, _held(p)) for n, p in _parts(single.shape[0], single_likelihood))
        singles = SingleData(single, StackedActionLikelihood(parts))
    start = warm.rho if warm.share is None else warm.share
    if average:
        return share_mixture_fit(space, hyper, warm.rho, start, data, singles)
    prior = warm.prior_of_share
    return fit_share(space, hyper, warm.rho, start, data, prior, singles, gate=warm.gate)


__all__ = [
    "RELEARN_EVERY",
    "Earlier",
    "WarmStart",
    "relearn_share",
    "relearning",
    "warm_data",
    "warm_posterior",
    "warm_start",
    "warm_terms",
]
