"""The CoSpar loop (the paper's Algorithm 1) behind an ask/tell interface.

Each iteration: draw ``n`` joint posterior samples and propose their argmaxes (exact ties broken at
random with the loop's generator); the user compares the new actions with each other and with the
``b`` previously executed ones and may suggest an improvement per executed action; suggestions
``a~ > a`` enter the data with noise ``sigma / beta`` (``beta``: the coactive weight); "no
preference" is stored and not modelled; the posterior is refitted, warm-started from the last one.

    loop = CoSpar(space, kernel, noise, n=1, buffer=1)
    query = loop.ask()              # query.actions: run these; query.buffer: compare with these
    a = query.actions[0]
    loop.tell(query, [Comparison(a, query.buffer[0], "first"),
                      Suggestion(a, "step_length", "+small")])
    loop.tell(query, [(a, query.buffer[0], "first")], [(a, "step_length", "+small")])  # the same

``tell`` takes feedback records of any registered kind (``gaitpref.feedback``); each kind checks
its records against the query and turns them into likelihood terms (on pairs of actions or on
single actions), all fitted together.  The paper's form ``tell(query, comparisons, suggestions)``
with ``(i, j, outcome)`` and ``(action, feature, move)`` tuples is a thin convenience over it.
``tell`` checks everything first and changes nothing when it raises.  ``exclude`` takes chosen
preferences of earlier answers out of the model (their records stay in ``answers``), as a session
does for a trial spoiled by a device fault or a stumble.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Collection, Hashable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from gaitpref.checks import is_count, is_noise, is_number
from gaitpref.errors import FeedbackError, NoSafeGaitError, QueryError
from gaitpref.feedback import (
    ActionObservation,
    Comparison,
    FeedbackKind,
    ModelContext,
    Observations,
    Preference,
    QueryPair,
    Suggestion,
    Tie,
    compared_actions,
    comparison_pairs,
    kind_named,
    kind_of,
    kinds,
)
from gaitpref.loop.learning import Learning, pair_data
from gaitpref.loop.lines import Line
from gaitpref.loop.safety import Safety, near
from gaitpref.loop.warm import WarmStart, relearn_share, warm_posterior
from gaitpref.model.engines import GRID_LIMIT_ACTIONS as MODEL_GRID_LIMIT
from gaitpref.model.engines import PointEngine
from gaitpref.model.evidence import Hyperparameters, PairData
from gaitpref.model.gp import PreferenceGP
from gaitpref.model.hyperfit import (
    HyperFit,
    HyperPrior,
    default_prior,
    fit_hyperparameters,
    hyper_from_json,
)
from gaitpref.model.hypermix import Hypothesis, weigh_hypotheses
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.laplace import LaplaceMode
from gaitpref.model.likelihood import ActionLikelihood, Probit, StackedActionLikelihood
from gaitpref.model.ordinal import Ordinal
from gaitpref.model.posterior import Posterior
from gaitpref.model.share_fit import ShareFit
from gaitpref.model.share_mix import PosteriorMixture, ShareHypothesis
from gaitpref.model.singles import SingleData, UnsupportedLikelihoodError
from gaitpref.model.threads import one_blas_thread
from gaitpref.pointset import PointSet
from gaitpref.space import Space
from gaitpref.strategies.base import AskContext, SelfSparring, Strategy


@dataclass(frozen=True)
class Query:
    """One iteration's proposal: run ``actions`` now; compare with the buffered ``buffer``."""

    id: int
    actions: tuple[int, ...]
    buffer: tuple[int, ...]
    #: the actions' feature values (features' units), one row per action; what a gait
    #: generator makes a gait for
    points: tuple[tuple[float, ...], ...] = dataclasses.field(default=(), compare=False)
    #: on the line path, the subspace the actions were chosen along (``loop/lines.py``)
    line: Line | None = dataclasses.field(default=None, compare=False)

    @property
    def members(self) -> tuple[int, ...]:
        """Every action a comparison of this query may name (executed, then buffered)."""
        return self.actions + self.buffer

    @property
    def pairs(self) -> tuple[QueryPair, ...]:
        """The pairs of members it asks to compare, and those it does not (and why):
        :func:`~gaitpref.feedback.comparison_pairs`."""
        return comparison_pairs(self.actions, self.buffer)

    @property
    def compared(self) -> tuple[tuple[int, int], ...]:
        """The pairs of actions it asks to compare, ``(executed, other)``, in order."""
        return compared_actions(self.actions, self.buffer)


@dataclass(frozen=True)
class Answer:
    """A told query: what the user said and what entered the model.

    ``records``: every feedback record, grouped by kind in registration order (comparisons,
    then suggestions, then other kinds), each kind's in the order given.  ``preferences`` and
    ``ties`` are the pair terms, ``singles`` the single-action terms; ``ignored`` the records
    that added no term (a suggestion whose move clips back to the same point, a comparison of
    a gait with itself).
    """

    query: Query
    records: tuple[Hashable, ...]
    preferences: tuple[Preference, ...]
    ties: tuple[Tie, ...]
    singles: tuple[ActionObservation, ...]
    ignored: tuple[Hashable, ...]
    posterior_before: Posterior = dataclasses.field(repr=False, compare=False)
    refit: HyperFit | None = None  # the hyperparameter fit this answer triggered, if any
    share_refit: ShareFit | None = None  # the warm start's share refit it triggered, if any

    @property
    def comparisons(self) -> tuple[Comparison, ...]:
        return tuple(r for r in self.records if isinstance(r, Comparison))

    @property
    def suggestions(self) -> tuple[Suggestion, ...]:
        return tuple(r for r in self.records if isinstance(r, Suggestion))

    @property
    def ignored_suggestions(self) -> tuple[Suggestion, ...]:
        """Suggestions whose move clips back to the same point (stored, not modelled)."""
        return tuple(r for r in self.ignored if isinstance(r, Suggestion))

    @property
    def ignored_comparisons(self) -> tuple[Comparison, ...]:
        """Comparisons of a gait with itself (stored, not modelled: ``docs/model.md``)."""
        return tuple(r for r in self.ignored if isinstance(r, Comparison))


#: An answer keeps the posterior before it for undo without its fit's two ``m x m`` factors
#: from this many visited actions (2 MiB of them), and undo remakes them, the same to the bit:
#: a warm start from 1,500 (gait, subject) pairs held 34 MB an answer, 2 GB in 60 answers.
STRIP_FROM_VISITED = 256


def _light(posterior: Posterior) -> Posterior:
    """The same posterior without its cached ``A``-sized arrays, and on large visited sets
    without its fit's factors (:data:`STRIP_FROM_VISITED`): cheap to keep for undo.

    On the line path also without its engine's caches: a :class:`PointEngine` is made for each
    table and holds the table's ``A x A`` prior covariance, its square root and its ``K``
    (jitter included) once read, and until then the engine it started from; kept by every
    answer they grew with the square of the table (400 trials on 12 features, a suggestion
    each: a peak of 808 MB, 275 MB without them).  A fresh engine over the same points remakes
    them, the same to the bit (``PointEngine.plain``), should undo need them."""
    engine = posterior.engine
    if isinstance(engine, PointEngine):
        posterior = dataclasses.replace(posterior, engine=PointEngine(engine.space, engine.kernel))
    fit = posterior.fit
    if fit is not None and fit.visited.size >= STRIP_FROM_VISITED:
        return dataclasses.replace(posterior, fit=fit.stripped)
    return dataclasses.replace(posterior)


def _restored(posterior: Posterior) -> Posterior:
    """:func:`_light`'s posterior holding its factors again (remade once, one BLAS thread as
    every fit of :meth:`CoSpar.tell`, so the same bits)."""
    fit = posterior.fit
    if fit is None or fit.factors is not None:
        return posterior
    with one_blas_thread():
        return dataclasses.replace(posterior, fit=fit.restored)


class CoSpar:
    """The CoSpar loop over ``space``: ``n`` actions per query, a buffer of ``buffer`` trials.

    ``sampler`` ("auto", "dense" or "scalable") picks how posterior samples reach every action
    (:mod:`gaitpref.model.engines`); for a given seed all choices propose the same actions up to
    floating-point rounding.
    """

    def __init__(
        self,
        space: Space,
        kernel: SquaredExponential,
        noise: float,
        n: int = 1,
        buffer: int = 0,
        coactive_weight: float = 1.0,
        seed: int | np.random.Generator = 0,
        strategy: Strategy | None = None,
        learning: Learning | None = None,
        sampler: str = "auto",
        ordinal: Ordinal | None = None,
        safety: Safety | None = None,
    ) -> None:
        if not isinstance(space, Space):
            raise TypeError(f"space must be a gaitpref.Space, got {space!r}")
        if not is_count(n) or n < 1:
            raise ValueError(f"n (actions per query) must be an integer >= 1, got {n!r}")
        if not is_count(buffer) or buffer < 0:
            raise ValueError(f"buffer must be an integer >= 0, got {buffer!r}")
        for key, value in (("n (actions per query)", n), ("buffer", buffer)):
            if value > QUERY_LIMIT:  # as a config's [cospar] n and buffer
                raise ValueError(f"{key} must be at most {QUERY_LIMIT}, got {value!r}")
        if not (
            is_number(coactive_weight) and np.isfinite(coactive_weight) and coactive_weight > 0
        ):
            raise ValueError(f"coactive_weight must be positive, got {coactive_weight!r}")
        if is_noise(noise) and not is_noise(noise / coactive_weight):
            # a suggestion's noise squared to inf in the likelihood: every suggestion was a
            # flat term, silently (1e-300), or a ConvergenceError at the first one
            raise ValueError(
                f"a suggestion's noise, noise / coactive_weight = {noise!r} / "
                f"{coactive_weight!r}, must be positive with a finite square"
            )
        if not isinstance(seed, np.random.Generator) and not (is_count(seed) and seed >= 0):
            raise ValueError(
                f"seed must be an integer >= 0 or a numpy.random.Generator, got {seed!r} (every "
                "random choice comes from it: None would draw from the operating system)"
            )
        _check_parts(strategy=strategy, learning=learning, ordinal=ordinal, safety=safety)
        n, buffer = int(n), int(buffer)
        _check_grid(space)
        if not isinstance(space, PointSet) and n > len(space):  # failed at every ask before
            raise ValueError(
                f"n (actions per query) must be at most the grid's size, {len(space)}, got {n}"
            )
        self.space = space
        self.gp = PreferenceGP(space, kernel, noise, sampler=sampler, ordinal=ordinal)
        self.learning = Learning() if learning is None else learning
        band = self.learning.tie_band
        if self.learning.learns_band:
            band = noise  # the starting band of the fit (the default prior's median)
        self.hyper = Hyperparameters.from_kernel(kernel, space.ndim, band or 0.0)
        self.prior: HyperPrior = self.learning.prior or default_prior(
            space, kernel.variance, noise, fit_band=self.learning.learns_band
        )
        if len(self.prior.lengthscale) != space.ndim:
            raise ValueError(
                f"the hyperparameter prior has {len(self.prior.lengthscale)} lengthscales; "
                f"the space has {space.ndim} features"
            )
        self.n = n
        self.buffer_size = buffer
        self.coactive_weight = float(coactive_weight)
        self.strategy: Strategy = SelfSparring() if strategy is None else strategy
        self.rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        self.safety = Safety() if safety is None else safety
        if self.safety.avoid:
            if ordinal is None:
                raise ValueError("a region of avoidance needs a rating scale (ordinal=...)")
            self.safety.threshold(ordinal, kernel.variance)  # checks avoid < categories
        for k, a in enumerate(self.safety.start):
            try:
                space.check_index(a)
            except IndexError as exc:
                raise IndexError(f"safety.start[{k}]: {exc}") from None
        self.unsafe: set[int] = set()  # actions flagged unsafe (flag_unsafe)
        self.avoided: dict[int, float] = {}  # action -> radius never proposed again (avoid)
        self._avoided_mask: NDArray[np.bool_] | None = None
        self.posterior: Posterior = self.gp.prior()
        self.answers: list[Answer] = []
        self.pending: Query | None = None
        self._next_id = 1
        self._buffer: tuple[int, ...] = ()
        self._rng_before_pending: Mapping[str, Any] | None = None
        self._rng_before: dict[int, Mapping[str, Any]] = {}  # answered query id -> RNG before ask
        self._dropped: dict[int, frozenset[int]] = {}  # query id -> excluded preference indices
        self._dropped_singles: dict[int, frozenset[int]] = {}  # ... and single-action terms
        self._stale_before: set[int] = set()  # answers whose posterior_before predates an exclude
        self.warm: WarmStart | None = None  # earlier subjects' answers (warm_start)
        self._gps: dict[Hyperparameters, PreferenceGP] = {}  # the hypotheses' (hyper="average")
        # the posteriors under the share hypotheses (share = "average"), for one posterior
        self._shared: tuple[Posterior | None, dict[float, Posterior]] = (None, {})

    # -- state -------------------------------------------------------------------------------
    @property
    def preferences(self) -> list[Preference]:
        """The preferences in the model (every answer's, less the excluded ones)."""
        return [p for a in self.answers for p in self._kept(a)]

    @property
    def excluded(self) -> dict[int, frozenset[int]]:
        """Query id -> indices into that answer's ``preferences`` taken out by :meth:`exclude`."""
        return dict(self._dropped)

    @property
    def excluded_singles(self) -> dict[int, frozenset[int]]:
        """Query id -> indices into that answer's ``singles`` taken out by :meth:`exclude`."""
        return dict(self._dropped_singles)

    @property
    def ties(self) -> list[Tie]:
        return [t for a in self.answers for t in a.ties]

    @property
    def singles(self) -> list[ActionObservation]:
        """The single-action terms in the model (ratings: every answer's, less the excluded)."""
        return [o for a in self.answers for o in self._kept_singles(a)]

    @property
    def executed(self) -> list[int]:
        """Every executed action, in order (one entry per trial)."""
        return [x for a in self.answers for x in a.query.actions]

    @property
    def refits(self) -> list[HyperFit]:
        """Every hyperparameter fit so far, in order (each also on its :class:`Answer`)."""
        return [a.refit for a in self.answers if a.refit is not None]

    @property
    def hypotheses(self) -> tuple[Hypothesis, ...]:
        """The lengthscale hypotheses and weights of the last refit (``hyper = "average"``;
        empty otherwise or before the first refit)."""
        refits = self.refits
        return refits[-1].hypotheses if refits else ()

    @property
    def share_hypotheses(self) -> tuple[ShareHypothesis, ...]:
        """The warm start's share hypotheses and weights after the last answer that weighed
        them (``share = "average"``; empty otherwise or before the first answer)."""
        fits = [a.share_refit for a in self.answers if a.share_refit is not None]
        return fits[-1].hypotheses if fits else ()

    def share_mixture(self) -> PosteriorMixture | None:
        """The mixture of the posteriors under the share hypotheses of positive weight (the
        heaviest one's is the loop's own posterior); None without share hypotheses."""
        hypotheses = [h for h in self.share_hypotheses if h.weight > 0]
        if not hypotheses:
            return None
        with one_blas_thread():
            parts = tuple((h.weight, self._posterior_sharing(h.share)) for h in hypotheses)
        total = sum(w for w, _ in parts)
        return PosteriorMixture(tuple((w / total, p) for w, p in parts))

    def _weighed_posteriors(
        self,
        share: ShareFit | None,
        answers: list[Answer],
        gp: PreferenceGP,
        hyper: Hyperparameters,
        warm: WarmStart | None,
    ) -> dict[float, Posterior]:
        """The posteriors under the share hypotheses just weighed, built on the Laplace fits
        the weighing made (:meth:`_posterior_sharing` would make the same fits again: the same
        data, kernel, ``rho`` and share, so the same numbers).  Only where those fits are of
        exactly what the posterior reads: pair terms alone (the weighing holds ratings'
        thresholds apart) and the weighing's kernel; else none (each is then fitted when
        needed, as before)."""
        if share is None or not share.fits or warm is None:
            return {}
        single, _ = self._singles(answers, hyper.thresholds)
        if single is not None or not gp.kernel.same_covariances(hyper.kernel(), self.space.ndim):
            return {}
        return {
            s: self._fit(answers, gp, hyper, dataclasses.replace(warm, share=s), fit)
            for s, fit in share.fits.items()
            if s != warm.share
        }

    def _posterior_sharing(self, share: float) -> Posterior:
        """The posterior with the new subject's share ``share`` (the loop's own at its share)."""
        warm = self.warm
        if warm is None or warm.share == share:
            return self.posterior
        key, cache = self._shared
        if key is not self.posterior:
            cache = {}
            self._shared = (self.posterior, cache)
        if share not in cache:
            cache[share] = self._fit(self.answers, warm=dataclasses.replace(warm, share=share))
        return cache[share]

    def mixture_mean(self) -> NDArray[np.float64]:
        """The posterior mean at every action, averaged over the hypotheses by weight (the
        posterior's own mean without hypotheses); its argmax is the recommendation."""
        hypotheses = self.hypotheses
        if not hypotheses:
            mixture = self.share_mixture()
            mean = self.posterior.mean if mixture is None else mixture.mean
            return np.asarray(mean, dtype=np.float64)
        with one_blas_thread():
            means = [h.weight * self._posterior_under(h).mean for h in hypotheses if h.weight > 0]
        return np.asarray(np.sum(means, axis=0), dtype=np.float64)

    def _posterior_under(self, hypothesis: Hypothesis) -> Posterior:
        """The posterior under ``hypothesis`` (the loop's own under the fitted kernel)."""
        if hypothesis.hyper == self.hyper:
            return self.posterior
        gp = self._gps.get(hypothesis.hyper)
        if gp is None:
            if len(self._gps) > 4 * len(self.learning.hypotheses):
                self._gps.clear()
            gp = self._gps[hypothesis.hyper] = self._gp(hypothesis.hyper)
        return self._fit(self.answers, gp, hypothesis.hyper)

    def _ask_posterior(self) -> Posterior:
        """The posterior a query is proposed under: with hypotheses, one drawn by weight from
        the loop's generator (the first step of a Thompson draw from the mixture); the
        lengthscale hypotheses if any, else the warm start's share hypotheses."""
        hypotheses = self.hypotheses
        if len(hypotheses) >= 2:
            k = int(self.rng.choice(len(hypotheses), p=[h.weight for h in hypotheses]))
            return self._posterior_under(hypotheses[k])
        shares = self.share_hypotheses
        if len(shares) < 2:
            return self.posterior
        k = int(self.rng.choice(len(shares), p=[h.weight for h in shares]))
        with one_blas_thread():
            return self._posterior_sharing(shares[k].share)

    @property
    def buffer(self) -> tuple[int, ...]:
        """The ``b`` most recently executed actions, oldest first."""
        return self._buffer

    def allowed(self) -> NDArray[np.bool_] | None:
        """The actions the next query may propose (None: all; ``loop/safety.py``).  On one BLAS
        thread, as ask and tell: the region of avoidance reads the posterior's variance, and
        sessions ask for this after every answer (the recommendation, the confidence): 16 ms
        on default threads against 0.4 ms on one for exo-2d-rated at 60 answers, same masks."""
        with one_blas_thread():
            if self._avoided_mask is None:
                return self.safety.allowed(self.posterior, self.gp.ordinal, self.unsafe)
            makeable = ~self._avoided_mask
            mask = self.safety.allowed(self.posterior, self.gp.ordinal, self.unsafe, makeable)
            return makeable if mask is None else mask & makeable

    def flag_unsafe(self, action: int) -> bool:
        """Never propose ``action`` again, nor the actions within ``safety.unsafe_radius``.

        A pending query that proposes such an action is withdrawn (the generator goes back to
        before it was drawn, so the next :meth:`ask` proposes again under the flag); returns
        whether it was.
        """
        self.unsafe.add(self.space.check_index(action))
        return self._withdraw_if(lambda: near(self.space, self.unsafe, self.safety.unsafe_radius))

    def avoid(self, action: int, radius: float) -> bool:
        """Never propose ``action`` again, nor the actions within ``radius`` of it (features
        scaled to ``[0, 1]``, as for unsafe flags): e.g. a gait that cannot be made.  Unlike an
        unsafe flag it is never taken back.  A pending query that proposes such an action is
        withdrawn as by :meth:`flag_unsafe`; returns whether it was."""
        check_radius(radius)
        index = self.space.check_index(action)
        self.avoided[index] = max(float(radius), self.avoided.get(index, 0.0))
        banned = near(self.space, [index], self.avoided[index])
        if self._avoided_mask is not None:
            banned |= self._avoided_mask
        self._avoided_mask = banned
        return self._withdraw_if(lambda: banned)

    def avoid_all(self, actions: Sequence[int], radius: float) -> bool:
        """:meth:`avoid` each of ``actions`` (actions of the pending query, say: all named
        before any is withdrawn); returns whether the pending query was withdrawn."""
        check_radius(radius)
        actions = list(actions)  # read twice below (an iterator too)
        for action in actions:  # all checked before any is avoided: nothing changes on a bad one
            self.space.check_index(action)
        withdrawn = False
        for action in actions:
            withdrawn |= self.avoid(action, radius)
        return withdrawn

    def _withdraw_if(self, banned_now: Callable[[], NDArray[np.bool_]]) -> bool:
        """Withdraw the pending query if it proposes an action ``banned_now()`` bans."""
        pending = self.pending
        if pending is None:
            return False
        banned = banned_now()
        if not any(banned[a] for a in pending.actions):
            return False
        if self._rng_before_pending is not None:
            self.rng.bit_generator.state = self._rng_before_pending
        self.pending = None
        self._rng_before_pending = None
        return True

    def unflag_unsafe(self, action: int) -> None:
        """Take an unsafe flag back (the flag's undo)."""
        if not is_count(action):
            raise TypeError(f"action index must be an integer, got {action!r}")
        self.unsafe.discard(int(action))

    def warm_start(self, warm: WarmStart) -> None:
        """Include earlier subjects' answers in every fit from now on (``loop/warm.py``);
        only before the first answer."""
        if not isinstance(warm, WarmStart):
            raise TypeError(f"warm must be a WarmStart (loop.warm), got {warm!r}")
        if self.answers or self.pending is not None:
            raise QueryError("a warm start must come before the first query")
        self.warm = warm
        with one_blas_thread():
            self.posterior = self._fit([])

    # -- ask / tell --------------------------------------------------------------------------
    def ask(self) -> Query:
        """The next query; the same pending query again until it is told."""
        if self.pending is not None:
            return self.pending
        with one_blas_thread():
            allowed = self.allowed()
        if allowed is not None and not allowed.any():
            raise NoSafeGaitError(
                "no gait may be proposed: every gait is in the region of avoidance or near a gait "
                f"flagged unsafe ({len(self.unsafe)} flagged) or avoided ({len(self.avoided)}, "
                "e.g. gaits that cannot be made); nothing was proposed"
            )
        self._rng_before_pending = self.rng.bit_generator.state
        actions = self._start_actions(allowed)
        if len(actions) < self.n:
            with one_blas_thread():
                posterior = self._ask_posterior()
            context = AskContext(
                posterior,
                self.n - len(actions),
                self._buffer + actions,
                len(self.executed),
                self.rng,
                allowed,
                self._rescaled,
            )
            with one_blas_thread():
                actions += proposed(self.strategy, context)
        points = tuple(tuple(row) for row in self.space.points_of(actions).tolist())
        self.pending = Query(self._next_id, actions, self._buffer, points)
        self._next_id += 1
        return self.pending

    def _start_actions(self, allowed: NDArray[np.bool_] | None) -> tuple[int, ...]:
        """The declared-safe gaits (``safety.start``) this query executes, in order: while fewer
        trials than start gaits have run, those not yet executed and still allowed (an unsafe
        flag or an avoided gait is skipped), at most ``n``; the strategy fills the rest of the
        query, comparing with them as with the buffer."""
        start = self.safety.start
        executed = self.executed
        if not start and not executed:
            return self._warm_first(allowed)
        if len(executed) >= len(start):
            return ()
        done = set(executed)
        todo = [a for a in start if a not in done and (allowed is None or allowed[a])]
        return tuple(todo[: self.n])

    def _warm_first(self, allowed: NDArray[np.bool_] | None) -> tuple[int, ...]:
        """A warm start's first trial (``learning.warm_first = "recommended"``): the earlier
        subjects' recommendation, the argmax among the allowed gaits of the new subject's
        posterior mean with their share at ``rho``; none (the strategy chooses) without a warm
        start, with ``"strategy"``, or when that mean is flat (``rho = 0``, no data)."""
        warm = self.warm
        if warm is None or self.learning.warm_first != "recommended" or warm.rho <= 0.0:
            return ()
        with one_blas_thread():
            mean = np.asarray(self._posterior_sharing(warm.rho).mean, dtype=np.float64)
        if allowed is not None:
            mean = np.where(allowed, mean, -np.inf)
        finite = mean[np.isfinite(mean)]
        if finite.size == 0 or np.ptp(finite) <= 0.0:
            return ()
        return (int(np.argmax(mean)),)

    def tell(
        self,
        query: Query | int,
        answers: Iterable[object] = (),
        suggestions: Iterable[object] = (),
        *,
        comparisons: Iterable[object] = (),
    ) -> Answer:
        """Record the answer to ``query`` and refit the posterior.

        ``answers``: feedback records of any registered kind (:class:`Comparison`,
        :class:`Suggestion`, ...).  The paper's convenience form also works: raw ``(i, j,
        outcome)`` items of ``answers`` are comparisons (``i``, ``j`` grid indices of actions in
        the query, ``outcome`` one of ``"first"``, ``"second"``, ``"none"``) and ``suggestions``
        holds ``(action, feature, move)`` for executed actions; a move that clips back to the same
        point is ignored; ``comparisons=`` (a keyword, as 0.1 named the argument) is the same as
        giving the comparisons in ``answers``.  Raises :class:`QueryError` /
        :class:`FeedbackError` and changes nothing on bad input.
        """
        q = self._check_query(query)
        given = {"answers": answers, "suggestions": suggestions, "comparisons": comparisons}
        items = {name: as_records(name, value) for name, value in given.items()}
        with self._all_or_nothing():
            return self._tell(
                q,
                [*items["answers"], *_as_comparisons(items["comparisons"])],
                items["suggestions"],
            )

    @contextmanager
    def _all_or_nothing(self) -> Iterator[None]:
        """Where :meth:`tell` keeps its promise to change nothing when it raises: nothing to
        undo here (the loop's state changes only at the end); the line path's point set
        grows before the fit and goes back (``line.py``)."""
        yield

    def _tell(self, q: Query, answers: Iterable[object], suggestions: Iterable[object]) -> Answer:
        records = self._parse(q, answers, suggestions)
        context = self.context()
        prefs: list[Preference] = []
        ties: list[Tie] = []
        singles: list[ActionObservation] = []
        ignored: list[Hashable] = []
        for kind, record in records:
            terms = kind.observations(record, context, q.id)
            self._check_terms(kind.name, terms)
            prefs += terms.preferences
            ties += terms.ties
            singles += terms.singles
            if terms.empty:  # a suggestion that clips back, a self-comparison
                ignored.append(record)
        if singles and self.learning.fit == "evidence":
            self._check_evidence(singles)
        answer = Answer(
            q,
            tuple(r for _, r in records),
            tuple(prefs),
            tuple(ties),
            tuple(singles),
            tuple(ignored),
            _light(self.posterior),
        )
        answers_now = [*self.answers, answer]
        with one_blas_thread():  # may raise: nothing changed yet
            refit = self._refit(answers_now)
            hyper = self.hyper if refit is None else refit.after
            gp = self.gp if hyper == self.hyper else self._gp(hyper)
            share = self._relearn_share(answers_now, hyper)
            warm = self.warm
            if share is not None and warm is not None:
                warm = dataclasses.replace(warm, share=share.after)
            new_posterior = self._fit(answers_now, gp, hyper, warm)
            sharing = self._weighed_posteriors(share, answers_now, gp, hyper, warm)
        if share is not None and share.fits:  # held by the posteriors above while they are
            share = dataclasses.replace(share, fits={})  # current, never by the answers: m x m
        self.warm = warm
        if refit is not None or share is not None:
            answer = dataclasses.replace(answer, refit=refit, share_refit=share)
        self.answers.append(answer)
        self.posterior = new_posterior
        self._shared = (new_posterior, sharing)
        self.gp, self.hyper = gp, hyper
        if self._rng_before_pending is not None:
            self._rng_before[q.id] = self._rng_before_pending
        self.pending = None
        self._rng_before_pending = None
        recent = self._buffer + q.actions
        self._buffer = recent[max(0, len(recent) - self.buffer_size) :]
        return answer

    def _parse(
        self, query: Query, answers: Iterable[object], suggestions: Iterable[object]
    ) -> list[tuple[FeedbackKind[Any], Hashable]]:
        """Every record checked by its kind, grouped by kind in registration order."""
        comparison, suggestion = kind_named("comparison"), kind_named("suggestion")
        context = self.context()
        given: list[tuple[FeedbackKind[Any], object]] = []
        for item in answers:
            given.append((kind_of(item) or comparison, item))
        for item in suggestions:
            kind = kind_of(item) or suggestion
            if kind is not suggestion:
                raise FeedbackError(f"suggestions: expected (action, feature, move), got {item!r}")
            given.append((kind, item))
        out: list[tuple[FeedbackKind[Any], Hashable]] = []
        for kind in kinds():
            raw = [item for k, item in given if k is kind]
            if not raw:
                continue
            parsed = [
                kind.parse(item, query, context, f"{kind.name} {n}") for n, item in enumerate(raw)
            ]
            kind.check_all(parsed, query)
            out += [(kind, r) for r in parsed]
        return out

    def undo(self, *, region: bool = True) -> Answer:
        """Take back the last answer: its query is pending again, as it was before the answer;
        unless one of the gaits it proposes (its ``actions``, not the buffered gaits already
        walked) may not be proposed now, when it is withdrawn as by :meth:`flag_unsafe`
        (``pending`` is None and the next :meth:`ask` proposes anew): a gait flagged unsafe or
        avoided since it was asked, or in the region of avoidance of the model as the undo
        leaves it (an :meth:`exclude` made after the answer changes that model, and so the
        region).  The rule is the one every ask keeps (:meth:`allowed`).

        ``region=False`` checks the flags and avoided gaits only, as undo did before the region
        was checked: what a session's undo events of payload version 1 replay with, and what
        taking back a tell that was never recorded needs (its query pending again as it was)."""
        answer = self._take_back()
        if region:
            self._withdraw_if(self._not_proposable_now)
        else:
            self._withdraw_if(self._hard_banned)
        return answer

    def proposable(self) -> NDArray[np.bool_]:
        """The actions a query could propose now: none near a gait flagged unsafe, avoided, or
        in the region of avoidance (what blind validation may show)."""
        with one_blas_thread():
            allowed = self.allowed()
        banned = self._hard_banned()
        return ~banned if allowed is None else allowed & ~banned

    def _not_proposable_now(self) -> NDArray[np.bool_]:
        """The actions the pending query (restored by :meth:`undo`, or kept through an
        :meth:`exclude`) may not propose now: what an ask now could not propose
        (:meth:`proposable`)."""
        return ~self.proposable()

    def _hard_banned(self) -> NDArray[np.bool_]:
        """The actions an unsafe flag (with its radius) or :meth:`avoid` bans now."""
        banned = near(self.space, self.unsafe, self.safety.unsafe_radius)
        if self._avoided_mask is not None:
            banned |= self._avoided_mask
        return banned

    def _take_back(self) -> Answer:
        """:meth:`undo` up to the check of the restored query against the flags."""
        if not self.answers:
            raise QueryError("nothing to undo: no query has been answered")
        if self.pending is not None and self._rng_before_pending is not None:
            self.rng.bit_generator.state = self._rng_before_pending
            self._next_id = self.pending.id
        answer = self.answers.pop()
        if answer.share_refit is not None and self.warm is not None:
            self.warm = dataclasses.replace(self.warm, share=answer.share_refit.before)
        if answer.refit is not None and answer.refit.before != self.hyper:
            self.hyper = answer.refit.before  # the hyperparameters from before its refit
            self.gp = self._gp(self.hyper)
        self._dropped.pop(answer.query.id, None)
        self._dropped_singles.pop(answer.query.id, None)
        self.posterior = _restored(answer.posterior_before)  # the warm start of a refit below
        if answer.query.id in self._stale_before:
            # an exclusion in an earlier answer came after this one: refit what remains
            self._stale_before.discard(answer.query.id)
            with one_blas_thread():
                self.posterior = self._fit(self.answers)
        self.pending = answer.query
        # so that a further undo can put the generator back to before this query was drawn
        self._rng_before_pending = self._rng_before.pop(answer.query.id, None)
        self._buffer = answer.query.buffer
        return answer

    def adopt_recorded(
        self,
        refit: Mapping[str, Any] | None = None,
        share: float | None = None,
        share_hypotheses: Sequence[Mapping[str, Any]] | None = None,
    ) -> Answer:
        """Replay on another machine: take the last answer's refitted values as the log has them.

        ``refit`` is a logged ``hyperparameters_refit`` payload (its ``after`` values and, with
        ``hyper = "average"``, its ``hypotheses``), ``share`` a logged ``share_refit``'s
        ``after`` (and ``share_hypotheses`` its ``hypotheses``, with ``share = "average"``).
        The session's replay calls this only after checking that they equal what this machine
        derived up to rounding (``sessions/events.py``, :func:`same_value`):
        everything after is then derived from the log's numbers, and the replay cannot drift
        from the recording one rounding at a time.  Returns the answer with those values.
        When they are this machine's to the bit (a replay where the log was written) nothing
        changes, and the posterior is not fitted again: it is the one the answer made, as the
        recording session had it.
        """
        if not self.answers:
            raise QueryError("nothing to adopt: no query has been answered")
        answer = self.answers[-1]
        fit, share_fit = answer.refit, answer.share_refit
        if refit is not None and fit is not None:
            after = hyper_from_json(refit["after"], fit.after)
            hypotheses = fit.hypotheses
            if refit.get("hypotheses"):
                hypotheses = tuple(Hypothesis.from_json(h, after) for h in refit["hypotheses"])
            fit = dataclasses.replace(fit, after=after, hypotheses=hypotheses)
            self.hyper, self.gp = after, self._gp(after)
        if share is not None and share_fit is not None and self.warm is not None:
            shares = share_fit.hypotheses
            if share_hypotheses:
                shares = tuple(ShareHypothesis.from_json(h) for h in share_hypotheses)
            share_fit = dataclasses.replace(share_fit, after=float(share), hypotheses=shares)
            self.warm = dataclasses.replace(self.warm, share=float(share))
        if fit == answer.refit and share_fit == answer.share_refit:
            return answer  # the same values, to the bit: the posterior is the answer's own
        self.answers[-1] = dataclasses.replace(answer, refit=fit, share_refit=share_fit)
        with one_blas_thread():
            self.posterior = self._fit(self.answers)
        return self.answers[-1]

    def exclude(
        self,
        drops: Mapping[int, Collection[int]],
        singles: Mapping[int, Collection[int]] | None = None,
        *,
        region: bool = True,
    ) -> Posterior:
        """Take preferences out of the model and refit; the answers themselves stay recorded.

        ``drops`` maps an answered query's id to indices into that answer's ``preferences``,
        ``singles`` to indices into its ``singles`` (single-action terms).
        Exclusions add up (excluding twice is harmless) and are dropped with their answer by
        :meth:`undo`.  Raises :class:`QueryError` / ``IndexError`` and changes nothing on bad
        input.

        The refit moves the region of avoidance: a pending query one of whose gaits (its
        ``actions``, not the buffered gaits already walked) may not be proposed now is
        withdrawn as by :meth:`flag_unsafe` (``pending`` is None and the next :meth:`ask`
        proposes anew), the rule :meth:`undo` and every ask keep (:meth:`proposable`).
        ``region=False`` keeps the pending query as it is, as exclusions did before: what a
        session's exclusion events of payload version 1 replay with.
        """
        position = {a.query.id: k for k, a in enumerate(self.answers)}
        new = _merged(self._dropped, drops, position, self.answers, "preferences")
        new_singles = _merged(
            self._dropped_singles, singles or {}, position, self.answers, "singles"
        )
        if new == self._dropped and new_singles == self._dropped_singles:
            return self.posterior
        old, old_singles = self._dropped, self._dropped_singles
        old_posterior = self.posterior
        self._dropped, self._dropped_singles = new, new_singles
        try:
            with one_blas_thread():
                posterior = self._fit(self.answers)
            self.posterior = posterior
            # read before anything else moves, so that nothing changes should it fail
            banned = self._not_proposable_now() if region and self.pending is not None else None
        except Exception:
            self._dropped, self._dropped_singles = old, old_singles
            self.posterior = old_posterior
            raise
        touched = [
            position[q]
            for q in {*drops, *(singles or {})}
            if new.get(q) != old.get(q) or new_singles.get(q) != old_singles.get(q)
        ]
        if touched:
            self._stale_before.update(a.query.id for a in self.answers[min(touched) + 1 :])
        if banned is not None:
            self._withdraw_if(lambda: banned)
        return posterior

    # -- internals ---------------------------------------------------------------------------
    def _kept(self, answer: Answer) -> tuple[Preference, ...]:
        dropped = self._dropped.get(answer.query.id)
        if not dropped:
            return answer.preferences
        return tuple(p for k, p in enumerate(answer.preferences) if k not in dropped)

    def _kept_singles(self, answer: Answer) -> tuple[ActionObservation, ...]:
        dropped = self._dropped_singles.get(answer.query.id)
        if not dropped:
            return answer.singles
        return tuple(o for k, o in enumerate(answer.singles) if k not in dropped)

    def _check_terms(self, kind: str, terms: Observations) -> None:
        """A kind's likelihood terms name actions of the grid, with a positive noise: a kind
        registered outside the package is held to it (a term on action -1 was fitted on the
        last gait)."""
        size = len(self.space)
        actions = [a for p in terms.preferences for a in (p.winner, p.loser)]
        actions += [a for t in terms.ties for a in (t.first, t.second)]
        actions += [o.action for o in terms.singles]
        for a in actions:
            if not is_count(a) or not 0 <= a < size:
                raise FeedbackError(
                    f"feedback kind {kind!r} made a term on {a!r}, not an action (0..{size - 1})"
                )
        for p in terms.preferences:
            if not (is_number(p.noise) and np.isfinite(p.noise) and p.noise > 0):
                raise FeedbackError(
                    f"feedback kind {kind!r} made a preference with noise {p.noise!r} "
                    "(it must be positive)"
                )

    def _check_evidence(self, singles: list[ActionObservation]) -> None:
        """Refuse, naming the kind, single-action terms the evidence fit cannot differentiate."""
        context = self.context()
        for kind in kinds():
            mine = [o for o in singles if o.kind == kind.name]
            if mine:
                try:
                    SingleData(
                        np.array([o.action for o in mine], dtype=np.intp),
                        kind.action_likelihood(mine, context),
                    )
                except UnsupportedLikelihoodError as exc:
                    raise FeedbackError(
                        f"feedback kind {kind.name!r}: {exc}; use [model] fit = 'fixed'"
                    ) from None

    def _singles(
        self, answers: list[Answer], thresholds: tuple[float, ...] | None = None
    ) -> tuple[Any, ActionLikelihood | None]:
        """The kept single-action terms: their actions and one likelihood over them (by kind),
        with fitted ordinal ``thresholds`` in place of the kind's own when given."""
        kept = [o for a in answers for o in self._kept_singles(a)]
        if not kept:
            return None, None
        context = self.context()
        actions: list[int] = []
        parts: list[tuple[int, ActionLikelihood]] = []
        for kind in kinds():
            mine = [o for o in kept if o.kind == kind.name]
            if mine:
                actions += [o.action for o in mine]
                parts.append((len(mine), kind.action_likelihood(mine, context)))
        single = np.asarray(actions, dtype=np.intp)
        stacked = StackedActionLikelihood(tuple(parts))
        if thresholds is None:
            return single, stacked
        return single, SingleData(single, stacked).at(thresholds).likelihood

    def context(self) -> ModelContext:
        """What feedback kinds see of this loop: its space, noises and rating scale."""
        return ModelContext(
            self.space,
            self.gp.noise,
            self.coactive_weight,
            self.gp.ordinal,
            self.gp.kernel.variance,
        )

    def _check_query(self, query: Query | int) -> Query:
        qid = query.id if isinstance(query, Query) else query
        if isinstance(qid, bool) or not isinstance(qid, int | np.integer):
            raise QueryError(f"query must be a Query or its integer id, got {query!r}")
        if any(a.query.id == qid for a in self.answers):
            raise QueryError(f"query {qid} was already answered")
        if self.pending is None or self.pending.id != qid:
            pending = "none is pending" if self.pending is None else f"pending is {self.pending.id}"
            raise QueryError(f"unknown query id {qid} ({pending})")
        if isinstance(query, Query) and query != self.pending:
            raise QueryError(f"query {qid} does not match the pending query {self.pending}")
        return self.pending

    def _rescaled(self, factor: float) -> Posterior:
        """The posterior of the answers so far with every lengthscale times ``factor`` (a
        strategy's view, ``AskContext.rescaled``; the loop's own posterior is unchanged)."""
        if not (np.isfinite(factor) and factor > 0):
            raise ValueError(f"a lengthscale factor must be positive, got {factor!r}")
        if factor == 1.0:
            return self.posterior
        scaled = tuple(ell * factor for ell in self.hyper.lengthscale)
        hyper = dataclasses.replace(self.hyper, lengthscale=scaled)
        return self._fit(self.answers, gp=self._gp(hyper), hyper=hyper)

    def _gp(self, hyper: Hyperparameters) -> PreferenceGP:
        return PreferenceGP(
            self.space,
            hyper.kernel(),
            self.gp.noise,
            sampler=self.gp.sampler,
            ordinal=self.gp.ordinal,
        )

    def _data(self, answers: list[Answer]) -> PairData:
        prefs = [p for a in answers for p in self._kept(a)]
        ties = [t for a in answers for t in a.ties]
        return pair_data(prefs, ties, self.gp.noise, self.learning.ties == "model")

    def _refit(self, answers: list[Answer]) -> HyperFit | None:
        """A hyperparameter fit when the schedule says so (every ``refit_every`` answers)."""
        if self.learning.fit != "evidence" or len(answers) % self.learning.refit_every:
            return None
        data = self._data(answers)
        single, single_likelihood = self._singles(answers)
        if data.size == 0 and single is None:
            return None
        singles = None
        if single is not None and single_likelihood is not None:
            singles = SingleData(single, single_likelihood)
        fit = fit_hyperparameters(self.space, self.hyper, data, self.prior, singles=singles)
        if self.learning.hyper != "average":
            return fit
        factors = self.learning.hypotheses
        hypotheses = weigh_hypotheses(
            self.space, fit.after, factors, data, self.prior, singles=singles
        )
        return dataclasses.replace(fit, hypotheses=hypotheses)

    def _relearn_share(self, answers: list[Answer], hyper: Hyperparameters) -> ShareFit | None:
        """The warm start's share refit when its schedule says so (``loop/warm.py``)."""
        if self.warm is None or not self.warm.relearns(len(answers)):
            return None
        single, single_likelihood = self._singles(answers, hyper.thresholds)
        own = self._data(answers)
        return relearn_share(
            self.warm, self.space, hyper, own, single, single_likelihood,
            average=self.learning.share == "average",
        )  # fmt: skip

    def _fit(
        self,
        answers: list[Answer],
        gp: PreferenceGP | None = None,
        hyper: Hyperparameters | None = None,
        warm: WarmStart | None = None,
        fit: LaplaceMode | None = None,
    ) -> Posterior:
        """The posterior given ``answers`` (default model: the current kernel, band, thresholds
        and warm start).  With fitted ordinal thresholds, the posterior's rating scale carries
        them, so its rating probabilities and the region of avoidance use what the fit used.
        ``fit``: a warm start's population fit of the same data, already made (a share
        hypothesis' from its weighing), taken instead of fitting again."""
        gp = self.gp if gp is None else gp
        hyper = self.hyper if hyper is None else hyper
        warm = self.warm if warm is None else warm
        posterior = self._fit_model(answers, gp, hyper, warm, fit)
        scale = gp.ordinal
        if hyper.thresholds is None or scale is None:
            return posterior
        fitted = Ordinal(scale.categories, hyper.thresholds, scale.noise)
        return dataclasses.replace(posterior, ordinal=fitted)

    def _fit_model(
        self,
        answers: list[Answer],
        gp: PreferenceGP,
        hyper: Hyperparameters,
        warm: WarmStart | None,
        fit: LaplaceMode | None = None,
    ) -> Posterior:
        band = hyper.band
        if fit is not None and warm is None:
            raise ValueError("a fit already made is a warm start's population fit")
        single, single_likelihood = self._singles(answers, hyper.thresholds)
        if self.learning.ties == "drop" and warm is None:  # the paper's likelihood, bit for bit
            prefs = [p for a in answers for p in self._kept(a)]
            winners = np.array([p.winner for p in prefs], dtype=np.intp)
            losers = np.array([p.loser for p in prefs], dtype=np.intp)
            noise = np.array([p.noise for p in prefs], dtype=np.float64)
            if single is None and not prefs:
                return gp.prior()
            # posterior_from, not posterior: the same fit (posterior builds this Probit), and it
            # takes a feedback kind's term of an action against itself as it always has (a
            # registered kind may make one; posterior refuses one from a caller)
            return gp.posterior_from(
                winners,
                losers,
                Probit(noise),
                init=self.posterior,
                single=single,
                single_likelihood=single_likelihood,
            )
        if warm is not None:
            return warm_posterior(
                warm, gp, self._data(answers), band, single, single_likelihood, fit
            )
        data = self._data(answers)
        if data.size == 0 and single is None:
            return gp.prior()
        return gp.posterior_from(
            data.first,
            data.second,
            data.likelihood(band),
            init=self.posterior,
            single=single,
            single_likelihood=single_likelihood,
        )


#: The full-grid path refuses grids past this many actions (its posterior reads every one;
#: the model's own bound, ``model/engines.py``); :class:`~gaitpref.loop.line.LineCoSpar` runs
#: on any space.
GRID_LIMIT_ACTIONS = MODEL_GRID_LIMIT
#: ... and features with more values than this: the kernel's factor of a feature is ``n x n``,
#: built at every fit (and eigendecomposed for samples: 0.3 s at 1,000, 34 s at 4,000).
GRID_LIMIT_VALUES = 1_000
#: Actions per query (``n``) and remembered trials (``buffer``): each at most this many (a
#: config's ``[cospar] n`` and ``buffer``, ``gaitpref.config.schema.MAX_QUERY``).  A buffer of
#: 10**9 kept every trial's actions and compared each trial with all of them.
QUERY_LIMIT = 64


def check_radius(radius: object) -> None:
    """An avoided neighbourhood's radius: a number in ``[0, 1]`` (a fraction of the ranges)."""
    if not (is_number(radius) and np.isfinite(radius) and 0 <= radius <= 1):  # type: ignore[call-overload, operator]
        raise ValueError(f"radius must be in [0, 1], got {radius!r}")


def _check_grid(space: Space) -> None:
    """A clear refusal where the full-grid path would not fit (issue 13, item 3)."""
    if isinstance(space, PointSet):
        return  # the line path's explicit points
    if space.continuous:
        names = ", ".join(f.name for f in space.features if f.continuous)
        raise ValueError(
            f"CoSpar runs on a grid, and {names} are continuous: use gaitpref.loop.line."
            "LineCoSpar (the line path; [cospar] subspace = 'line' in a config)"
        )
    for f in space.features:
        n = len(f.values)
        if n > GRID_LIMIT_VALUES:
            raise ValueError(
                f"feature {f.name!r} has {n:,} values; the full-grid path holds at most "
                f"{GRID_LIMIT_VALUES:,} a feature (its kernel factor is {n:,} x {n:,}, "
                f"{n * n * 8 / 2**30:,.2f} GiB, built at every fit): use fewer values, or "
                "gaitpref.loop.line.LineCoSpar (the line path; [cospar] subspace = 'line' in a "
                "config)"
            )
    size = space.grid_size
    if size is not None and size > GRID_LIMIT_ACTIONS:
        raise ValueError(
            f"the grid has {size:,} actions; the full-grid path holds at most "
            f"{GRID_LIMIT_ACTIONS:,} (a {size:,} x m cross-covariance and {size:,}-long samples "
            "would not fit in memory): use gaitpref.loop.line.LineCoSpar (the line path; "
            "[cospar] subspace = 'line' in a config)"
        )


def proposed(strategy: Strategy, context: AskContext) -> tuple[int, ...]:
    """What ``strategy`` proposes, checked: ``context.n`` integer actions of the context's
    posterior, each allowed (a strategy written outside the package is held to the protocol:
    a gait outside ``allowed``, in the region of avoidance or near an unsafe flag, was run)."""
    picks = tuple(strategy.propose(context))
    name = getattr(strategy, "name", type(strategy).__name__)
    if len(picks) != context.n:
        raise ValueError(
            f"strategy {name!r} proposed {len(picks)} actions; the query asks {context.n}"
        )
    size = len(context.posterior.space)
    for a in picks:
        if not is_count(a) or not 0 <= a < size:
            raise ValueError(f"strategy {name!r} proposed {a!r}, not an action (0..{size - 1})")
        if context.allowed is not None and not context.allowed[a]:
            raise ValueError(f"strategy {name!r} proposed action {a}, which may not be proposed")
    return tuple(int(a) for a in picks)


def _check_parts(**parts: object) -> None:
    """The loop's parts are what their names say (a strategy from ``make_strategy``, ...):
    a name or a dict in their place failed at the first ask or tell."""
    for name, value in parts.items():
        if value is None:
            continue
        if name == "strategy":
            if not callable(getattr(value, "propose", None)):
                raise TypeError(
                    f"strategy must be a Strategy (gaitpref.make_strategy(name)), got {value!r}"
                )
            continue
        kind = {"learning": Learning, "ordinal": Ordinal, "safety": Safety}[name]
        if not isinstance(value, kind):
            raise TypeError(f"{name} must be a {kind.__name__} or None, got {value!r}")


def as_records(name: str, value: object) -> list[object]:
    """``tell``'s (or ``Session.answer``'s) argument ``name`` as a list of items: a list (or any
    iterable) of records or raw tuples, not one record, a string or a number (a TypeError from
    unpacking before)."""
    if kind_of(value) is not None:
        raise FeedbackError(
            f"{name}: expected a list of feedback records, got one {type(value).__name__}: "
            f"give [{value!r}]"
        )
    if isinstance(value, str | bytes) or not isinstance(value, Iterable):
        raise FeedbackError(f"{name}: expected a list of feedback records, got {value!r}")
    return list(value)


def _as_comparisons(items: Iterable[object]) -> list[object]:
    """``comparisons=`` items: raw triples or :class:`Comparison` records, nothing else."""
    out = list(items)
    for k, item in enumerate(out):
        kind = kind_of(item)
        if kind is not None and not isinstance(item, Comparison):
            raise FeedbackError(f"comparison {k}: expected (i, j, outcome), got {item!r}")
    return out


def _merged(
    current: dict[int, frozenset[int]],
    drops: Mapping[int, Collection[int]],
    position: dict[int, int],
    answers: list[Answer],
    field: str,
) -> dict[int, frozenset[int]]:
    """``current`` with ``drops`` (query id -> indices into that answer's ``field``) added."""
    if not isinstance(drops, Mapping):
        raise TypeError(
            f"{field} to exclude: expected a mapping of query id -> indices, got {drops!r}"
        )
    new = dict(current)
    for qid, indices in drops.items():
        if qid not in position:
            raise QueryError(f"cannot exclude from query {qid}: it has no recorded answer")
        size = len(getattr(answers[position[qid]], field))
        if isinstance(indices, str | bytes) or not isinstance(indices, Iterable):
            raise TypeError(f"query {qid}: {field} to exclude must be indices, got {indices!r}")
        indices = list(indices)  # read once (an iterator too)
        odd = [i for i in indices if not is_count(i)]
        if odd:
            raise TypeError(f"query {qid}: {field} to exclude must be integers, got {odd[0]!r}")
        chosen = {int(i) for i in indices}
        bad = sorted(i for i in chosen if not 0 <= i < size)
        if bad:
            raise IndexError(f"query {qid} has {size} {field}; cannot exclude index {bad[0]}")
        new[qid] = new.get(qid, frozenset()) | frozenset(chosen)
    return new


__all__ = ["Answer", "CoSpar", "FeedbackError", "Query", "QueryError"]
