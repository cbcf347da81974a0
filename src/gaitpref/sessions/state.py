"""A session's state rebuilt from its events: the one adapter from the log to CoSpar calls.

Live operations and replay share this code, so a resumed session follows the same path as the one
that wrote the log: every operation first *derives* its events from the current state (asking
CoSpar for a proposal, telling it an answer, ...), the caller writes them, then :meth:`commit`
books them.  Replay derives the same events and compares them with the logged ones field by field
(the payload classes' checked fields, ``events.py``); a difference (another config, another
software version) raises
:class:`~gaitpref.sessions.records.ReplayError` that shows it.

Exclusion (``trial_excluded``): a comparison leaves the model when it names the excluded trial's
action in a query where that trial took part (executed or buffered); a suggestion leaves it when
it was given for the excluded trial.  Comparisons answered later against an excluded buffered
trial leave it too.  The records stay, flagged.

Notation: trials are numbered 1, 2, ... in execution order among the answers in force; an undone
answer's trial numbers are given again to the next answer.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from gaitpref.config import ExperimentConfig
from gaitpref.errors import ReplayError, SessionStateError
from gaitpref.feedback import (
    Comparison,
    ComparisonAnswered,
    Preference,
    Suggestion,
    SuggestionGiven,
    kind_of,
)
from gaitpref.loop.cospar import Answer, CoSpar, Query, QueryError
from gaitpref.loop.safety import near_point
from gaitpref.sessions import events as log
from gaitpref.sessions.gaits import RecordedGaits, propose_with_gaits
from gaitpref.sessions.records import (
    REASONS,
    ComparisonRecord,
    FeedbackEntry,
    InfeasibleGait,
    Reason,
    SessionQuery,
    ShownGait,
    SuggestionRecord,
    Trial,
    ValidationRound,
    check_storable,
    check_unsafe_reason,
    check_withdraw_reason,
)
from gaitpref.sessions.validation import (
    BlindGait,
    ValidationPlan,
    ValidationResult,
    blind_plan,
    unblind,
)
from gaitpref.storage import EventRecord, NewEvent, SessionRecord, Status

if TYPE_CHECKING:  # gaits/ loads SciPy's optimizers: only when a config names a generator
    from gaitpref.gaits.gait_cache import GaitCache
    from gaitpref.gaits.on_demand import OnDemandGaits

_VALIDATION_STREAM = 0x7A11DA7E  # the validation order's generator: (seed, this, round)
_STATUS_OF: dict[str, Status] = {
    log.PAUSED: "paused",
    log.RESUMED: "active",
    log.FINISHED: "finished",
}


@dataclass
class _Told:
    """An answer in force: its query, CoSpar's record and the rows it wrote."""

    query: SessionQuery
    answer: Answer
    trial_rows: list[int]
    comparison_rows: list[int]
    suggestion_rows: list[int]
    feedback_rows: list[int] = field(default_factory=list)  # other kinds' entries


@dataclass
class _Round:
    plan: ValidationPlan
    roles: dict[str, str]
    values: dict[str, float]
    seq: int
    shown: dict[str, ShownGait]  # label -> the gait as the round showed it (rows move on)
    result: ValidationResult | None = None
    version: int = 1  # its validation_started payload's: 2 chose among proposable gaits
    opened_by: log.Opener | None = None  # version 3: "rule" or "operator"; None before
    opened_after: int | None = None  # the rule's: the query whose answer made it open
    withdrawn: tuple[int, str] | None = None  # (seq, reason) of its validation_withdrawn


@dataclass
class SessionState:
    """Everything a session knows, rebuilt event by event."""

    config: ExperimentConfig
    seed: int
    gait_ids: list[str] | None = None
    loop: CoSpar = field(init=False)
    last_seq: int = 0
    status: Status = "active"
    pending: SessionQuery | None = None
    told: list[_Told] = field(default_factory=list)
    trials_log: list[Trial] = field(default_factory=list)
    comparisons_log: list[ComparisonRecord] = field(default_factory=list)
    suggestions_log: list[SuggestionRecord] = field(default_factory=list)
    feedback_log: list[FeedbackEntry] = field(default_factory=list)
    excluded: dict[int, tuple[Reason, str]] = field(default_factory=dict)
    unsafe: dict[int, tuple[int, str]] = field(default_factory=dict)  # trial -> (action, reason)
    rounds: list[_Round] = field(default_factory=list)
    banned: tuple[int, _Round] | None = None  # (seq, round) a flag or exclusion last withdrew
    notes: list[tuple[int, str]] = field(default_factory=list)
    gait_cache: GaitCache | None = field(default=None, repr=False)  # gaits made on demand
    on_demand: OnDemandGaits | None = field(init=False, default=None)
    infeasible: list[InfeasibleGait] = field(default_factory=list)
    made_rows: list[int] = field(default_factory=list)  # each gait_made's action, as logged
    made_ids: set[str] = field(default_factory=set)  # each gait_made's gait id
    stopped: dict[str, Any] | None = None  # the last event's payload if it is a query_stopped
    row: SessionRecord | None = field(default=None, repr=False)  # checked against `created`

    def __post_init__(self) -> None:
        self.loop = self.config.make_loop(seed=self.seed)
        spec = self.config.generator
        if spec is not None:
            from gaitpref.gaits.gait_cache import GaitCache
            from gaitpref.gaits.on_demand import OnDemandGaits

            space = self.config.space
            cache = self.gait_cache if self.gait_cache is not None else GaitCache()
            ranges = [f.span for f in space]
            exact = space.continuous  # points off a grid: ids that cannot collide
            self.on_demand = OnDemandGaits(spec.make(space), cache, ranges, exact=exact)

    # -- views ---------------------------------------------------------------------------------
    @property
    def trial_actions(self) -> list[tuple[int, int]]:
        """``(trial number, action)`` of the trials in force, in order."""
        return [
            (t, a) for k in self.told for t, a in zip(k.query.trials, k.query.actions, strict=True)
        ]

    @property
    def walkable(self) -> list[int]:
        """The actions whose gait this session made (feasible), in the order first logged: each
        ``gait_made`` event's action while it still names that gait.  On the line path a
        withdrawn proposal's rows go to the points proposed next (``loop/line.py``), so a row
        logged with a made gait may later name an unmade point (a coactive suggestion's) or no
        point yet; such a row is left out until a made gait is its point again."""
        size = len(self.loop.space)
        return [
            a
            for a in dict.fromkeys(self.made_rows)
            if a < size and self.gait_id(a) in self.made_ids
        ]

    def gait_made(self, action: int) -> bool | None:
        """Whether ``action``'s gait is one this session made (feasible: a ``gait_made`` event
        logged it), so that a query has proposed it and it may be walked; None without gaits
        made on demand.  On the line path the posterior's highest is often a point no query
        proposed (a coactive suggestion's), whose gait is not made and may prove infeasible."""
        if self.on_demand is None:
            return None
        return self.gait_id(action) in self.made_ids

    @property
    def open_round(self) -> _Round | None:
        last = self.rounds[-1] if self.rounds else None
        return last if last is not None and last.result is None and last.withdrawn is None else None

    @property
    def rounds_in_force(self) -> list[_Round]:
        """The rounds not withdrawn (open or answered): the ``[stop]`` rule opens one only
        while there is none."""
        return [r for r in self.rounds if r.withdrawn is None]

    def validation_rounds(self) -> list[ValidationRound]:
        """Every round logged (a round drawn again after a flag once, under its number)."""
        return [
            ValidationRound(
                round=r.plan.round,
                seq=r.seq,
                opened_by=r.opened_by,
                opened_after=r.opened_after,
                answered=r.result is not None,
                withdrawn=None if r.withdrawn is None else r.withdrawn[1],
                withdrawn_seq=None if r.withdrawn is None else r.withdrawn[0],
            )
            for r in self.rounds
        ]

    def _not_open(self, round_: object) -> str:
        """Why validation round ``round_`` is not open (for a refusal naming the problem)."""
        if isinstance(round_, bool) or not isinstance(round_, int):  # True == 1: not a round
            return f"validation round {round_!r} is not open: a round is a whole number"
        found = [r for r in self.rounds if r.plan.round == round_]
        current = self.open_round
        now = "none is open" if current is None else f"round {current.plan.round} is open"
        if not found:
            return f"validation round {round_!r} is not open: it was never started ({now})"
        if found[-1].result is not None:
            return f"validation round {round_} is not open: it is already answered ({now})"
        return f"validation round {round_} is not open: it was withdrawn ({now})"

    # -- derive: queries -----------------------------------------------------------------------
    def derive_query(self, recorded: RecordedGaits | None = None) -> list[NewEvent]:
        """Ask CoSpar for the next proposal (the same one until it is answered): its
        ``query_issued`` event, after the gaits made on demand for it (``gaits.py``;
        ``recorded``: on replay, the gaits the log carries for it).  An ask that stopped at
        ``[gaits] max_infeasible``, or with no gait left after some were infeasible, ends with
        ``query_stopped`` instead: nothing is proposed."""
        events: list[NewEvent] = []
        if self.on_demand is None:
            q = self.loop.ask()
        else:
            events, proposed = propose_with_gaits(self.loop, self.on_demand, self.config, recorded)
            if proposed is None:
                return events
            q = proposed
        done = self.trial_actions
        numbers = [t for t, _ in done]
        start = numbers[-1] + 1 if numbers else 1
        buffered = numbers[len(numbers) - len(q.buffer) :] if q.buffer else []
        issued = log.QueryIssued(
            query_loop_id=int(q.id),
            actions=[int(a) for a in q.actions],
            buffer=[int(b) for b in q.buffer],
            trials=list(range(start, start + len(q.actions))),
            buffer_trials=buffered,
            **_line_fields(q),
        )
        return [*events, log.new_event(issued)]

    def _query_of(self, seq: int, payload: dict[str, Any]) -> SessionQuery:
        return SessionQuery(
            id=seq,
            loop_id=int(payload["query_loop_id"]),
            actions=tuple(payload["actions"]),
            buffer=tuple(payload["buffer"]),
            trials=tuple(payload["trials"]),
            buffer_trials=tuple(payload["buffer_trials"]),
            points=tuple(tuple(p) for p in payload.get("points") or self._points(payload)),
        )

    def _points(self, payload: dict[str, Any]) -> list[list[float]]:
        """A grid query's points (its log holds only the actions)."""
        out: list[list[float]] = self.loop.space.points_of(payload["actions"]).tolist()
        return out

    # -- derive: answers -----------------------------------------------------------------------
    def tell(
        self, query: SessionQuery, answers: Iterable[object], suggestions: Iterable[object] = ()
    ) -> Answer:
        """Tell CoSpar the answer (checked; nothing changes on error) and apply exclusions."""
        answer: Answer = self.loop.tell(query.loop_id, answers, suggestions)
        drops, single_drops = self._drops(query, answer)
        if drops or single_drops:
            try:
                self.loop.exclude({query.loop_id: drops}, {query.loop_id: single_drops})
            except BaseException:  # Ctrl-C during the refit too
                self.loop.undo(region=False)  # its query pending again, as it was
                raise
        return answer

    def answer_events(self, query: SessionQuery, answer: Answer) -> list[NewEvent]:
        """The answer's batch: its trials, one event per feedback record, and its refit."""
        space = self.loop.space  # the grid, or the line path's point set
        events = [
            log.new_event(
                log.TrialExecuted(
                    query=query.id,
                    trial=t,
                    action=a,
                    values=space.values_of(a),
                    gait_id=self.gait_id(a),
                )
            )
            for t, a in zip(query.trials, query.actions, strict=True)
        ]
        context = self.loop.context()
        for record in answer.records:
            kind = kind_of(record)
            assert kind is not None  # the loop took it, so its kind is registered
            events.append(log.new_event(kind.payload(record, query, context)))
        if answer.refit is not None:
            refit = log.HyperparametersRefit.parse(
                {"query": query.id, **answer.refit.to_json()}, "hyperparameters_refit"
            )
            events.append(log.new_event(refit))
        share = answer.share_refit
        if share is not None:

            def finite(x: float) -> float | None:
                return x if math.isfinite(x) else None

            payload = log.ShareRefit(
                query=query.id, before=share.before, after=share.after, accepted=share.accepted,
                message=share.message, evaluations=share.evaluations,
                objective_before=finite(share.objective_before),
                objective_after=finite(share.objective_after),
                hypotheses=[log.ShareValues.model_validate(h.to_json()) for h in share.hypotheses]
                or None,
            )  # fmt: skip
            events.append(log.new_event(payload))
        return events

    def revert_tell(self) -> None:
        """Take back a :meth:`tell` whose events could not be written: its query pending
        again as it was (nothing logged moved the region since)."""
        self.loop.undo(region=False)

    # -- derive: undo and exclusion ------------------------------------------------------------
    def undo_event(self) -> NewEvent:
        if not self.told:
            raise SessionStateError("nothing to undo: no answer is in force")
        last = self.told[-1]
        spoiled = [t for t in last.query.trials if t in self.excluded]
        if spoiled:
            raise SessionStateError(
                f"the last answer's trial {spoiled[0]} was excluded after it was given; "
                "an excluded trial's answer cannot be undone"
            )
        flagged = [t for t in last.query.trials if t in self.unsafe]
        if flagged:
            raise SessionStateError(
                f"the last answer's trial {flagged[0]} is flagged unsafe; withdraw the flag "
                "before undoing its answer"
            )
        return log.new_event(log.Undo(query=last.query.id, trials=list(last.query.trials)))

    def unsafe_event(self, trial: int, reason: str) -> NewEvent:
        """Flag an answered trial unsafe (``reason``: what happened, 1..2000 characters)."""
        check_unsafe_reason(reason)
        told, action = self._trial(trial)
        if trial in self.unsafe:
            raise SessionStateError(f"trial {trial} is already flagged unsafe")
        return log.new_event(
            log.TrialFlaggedUnsafe(trial=trial, query=told.query.id, action=action, reason=reason)
        )

    def withdraw_unsafe_event(self, trial: int) -> NewEvent:
        if trial not in self.unsafe:
            flagged = ", ".join(map(str, sorted(self.unsafe))) or "none"
            raise SessionStateError(f"trial {trial!r} is not flagged unsafe (flagged: {flagged})")
        return log.new_event(log.UnsafeFlagWithdrawn(trial=trial, action=self.unsafe[trial][0]))

    def _trial(self, trial: int) -> tuple[_Told, int]:
        """The answer in force that executed ``trial``, and the trial's action."""
        found = [k for k in self.told for t in k.query.trials if t == trial]
        if isinstance(trial, bool) or not isinstance(trial, int) or not found:
            done = self.trial_actions
            known = f"trials 1 to {done[-1][0]}" if done else "no trials yet"
            raise SessionStateError(
                f"no trial {trial!r} has been answered (this session has {known})"
            )
        told = found[0]
        return told, told.query.actions[told.query.trials.index(trial)]

    def exclude_event(self, trial: int, reason: str, detail: str) -> NewEvent:
        if reason not in REASONS:
            raise ValueError(f"reason must be one of {', '.join(REASONS)}; got {reason!r}")
        if not isinstance(detail, str) or len(detail) > 2000:
            raise ValueError("detail must be a string of at most 2000 characters")
        check_storable(detail, "the exclusion's detail")
        found = [(k, t) for k in self.told for t in k.query.trials if t == trial]
        if isinstance(trial, bool) or not isinstance(trial, int) or not found:
            done = self.trial_actions
            known = f"trials 1 to {done[-1][0]}" if done else "no trials yet"
            raise SessionStateError(
                f"no trial {trial!r} has been answered (this session has {known})"
            )
        if trial in self.excluded:
            raise SessionStateError(
                f"trial {trial} is already excluded ({self.excluded[trial][0]})"
            )
        told = found[0][0]
        action = told.query.actions[told.query.trials.index(trial)]
        return log.new_event(
            log.TrialExcluded(
                trial=trial,
                query=told.query.id,
                action=action,
                reason=reason,
                detail=detail,
            )
        )

    def apply_exclusion(self, payload: dict[str, Any], version: int) -> None:
        """Take the trial's answers out of the model (before writing).

        As payload ``version`` 2 (and later) does, the loop then withdraws the pending query
        when one of its gaits lies in the region of avoidance the exclusion leaves
        (``CoSpar.exclude``; :meth:`commit` books it); version 1, written before, kept it."""
        trial = payload["trial"]
        self.excluded[trial] = (payload["reason"], payload.get("detail", ""))
        drops: dict[int, list[int]] = {}
        single_drops: dict[int, list[int]] = {}
        for told in self.told:
            if trial in told.query.member_trials:
                pairs, singles = self._drops(told.query, told.answer)
                drops[told.query.loop_id] = pairs
                single_drops[told.query.loop_id] = singles
        try:
            self.loop.exclude(drops, single_drops, region=version > log.TrialExcludedV1.version)
        except Exception:
            del self.excluded[trial]
            raise
        for told in self.told:
            if trial in told.query.member_trials:
                self._flag_exclusions(told)

    # -- derive: validation --------------------------------------------------------------------
    def validation_event(
        self, version: int | None = None, opened_by: log.Opener | None = "operator"
    ) -> NewEvent:
        """The next blind round, its gaits chosen as payload ``version`` (default: the newest)
        chose them (1: among every gait or made gait; 2 and later: among those a query could
        propose); ``opened_by`` (version 3): ``"rule"`` or ``"operator"``."""
        version = log.ValidationStarted.version if version is None else version
        round_ = len(self.rounds) + 1
        mean = np.asarray(self.loop.posterior.mean)
        try:
            plan, roles = self._blind_plan(round_, mean, version)
        except ValueError as exc:
            raise SessionStateError(f"cannot start a blind validation: {exc}") from None
        gaits = [
            log.BlindGaitShown(
                label=g.label,
                action=g.action,
                role=roles[g.label],
                posterior_mean=float(mean[g.action]),
            )
            for g in plan.gaits
        ]
        older = {1: log.ValidationStartedV1, 2: log.ValidationStartedV2}.get(version)
        if older is not None:
            return log.new_event(older(round=round_, gaits=gaits))  # who opened it: not logged
        return log.new_event(log.ValidationStarted(round=round_, gaits=gaits, opened_by=opened_by))

    def withdraw_validation_event(self, round_: int, reason: str) -> NewEvent:
        """Withdraw the open, unanswered round ``round_`` (``reason``: why, 1..2000 characters);
        refused for a round that is answered, withdrawn, not started, or not the open one."""
        check_withdraw_reason(reason)  # a ValueError naming the rule it breaks
        current = self.open_round
        if isinstance(round_, bool) or current is None or current.plan.round != round_:
            raise SessionStateError(
                f"{self._not_open(round_)}: only an open, unanswered round can be withdrawn"
            )
        return log.new_event(log.ValidationWithdrawn(round=round_, reason=reason))

    def validation_blocked(self) -> str | None:
        """Why no blind validation round can be drawn now (fewer than three gaits may be shown,
        or the posterior mean is flat), or None when one can."""
        try:
            self._blind_plan(len(self.rounds) + 1, np.asarray(self.loop.posterior.mean))
        except ValueError as exc:
            return str(exc)
        return None

    def _blind_plan(
        self, round_: int, mean: np.ndarray, version: int | None = None
    ) -> tuple[ValidationPlan, dict[str, str]]:
        """Round ``round_``'s plan and roles as payload ``version`` chooses them (ValueError:
        none can be drawn)."""
        version = log.ValidationStarted.version if version is None else version
        rng = np.random.default_rng(
            np.random.SeedSequence(self.seed, spawn_key=(_VALIDATION_STREAM, round_))
        )
        shown = None if self.on_demand is None else sorted(set(self.walkable))
        if version >= 2:
            proposable = self.loop.proposable()
            if not proposable.all():
                among = np.flatnonzero(proposable) if shown is None else shown
                shown = [int(a) for a in among if proposable[a]]
        return blind_plan(round_, mean, rng, shown)

    def validation_answer_event(self, round_: int, ranking: Sequence[str] | str) -> NewEvent:
        current = self.open_round
        if current is None or current.plan.round != round_:
            raise SessionStateError(f"{self._not_open(round_)}: it takes no ranking")
        try:
            result = unblind(current.plan, current.roles, current.values, ranking)
        except ValueError as exc:
            raise SessionStateError(str(exc)) from None
        return log.new_event(
            log.ValidationAnswered(
                round=round_,
                ranking=list(result.ranking),
                model_ranking=list(result.model_ranking),
                agrees=result.agrees,
                kendall_tau=result.kendall_tau,
            )
        )

    # -- commit: book events that are written ---------------------------------------------------
    def commit(self, records: Sequence[EventRecord], answer: Answer | None = None) -> None:
        """Book written ``records`` (an answer batch comes with CoSpar's ``answer``)."""
        if not records:
            return
        first = records[0]
        if first.kind == log.TRIAL:
            assert answer is not None and self.pending is not None
            self._commit_answer(self.pending, answer, records)
        else:
            for r in records:
                self._commit_one(r)
        self.last_seq = records[-1].seq
        last = records[-1]
        self.stopped = dict(last.payload) if last.kind == log.QUERY_STOPPED else None

    def _commit_answer(
        self, query: SessionQuery, answer: Answer, records: Sequence[EventRecord]
    ) -> None:
        told = _Told(query, answer, [], [], [])
        for r in records:
            p = r.payload
            if r.kind == log.TRIAL:
                told.trial_rows.append(len(self.trials_log))
                self.trials_log.append(Trial(p["trial"], query.id, p["action"], r.seq))
            elif r.kind == ComparisonAnswered.kind:
                told.comparison_rows.append(len(self.comparisons_log))
                self.comparisons_log.append(
                    ComparisonRecord(
                        r.seq,
                        query.id,
                        p["first"],
                        p["second"],
                        p["outcome"],
                        p["first_trial"],
                        p["second_trial"],
                    )
                )
            elif r.kind == SuggestionGiven.kind:
                told.suggestion_rows.append(len(self.suggestions_log))
                self.suggestions_log.append(
                    SuggestionRecord(
                        r.seq,
                        query.id,
                        p["trial"],
                        p["action"],
                        p["feature"],
                        p["move"],
                        p["target"],
                    )
                )
            elif log.is_feedback(r.kind):
                told.feedback_rows.append(len(self.feedback_log))
                self.feedback_log.append(FeedbackEntry(r.seq, query.id, r.kind, dict(p)))
        self.told.append(told)
        self.pending = None
        self._flag_exclusions(told)

    def _commit_one(self, r: EventRecord) -> None:
        p = r.payload
        if r.kind == log.QUERY:
            self.pending = self._query_of(r.seq, p)
        elif r.kind == log.UNDO:
            # version 1 (written before the region was checked) replays by its own rule
            self.loop.undo(region=r.version > log.UndoV1.version)
            told = self.told.pop()
            for rows, name in (
                (told.trial_rows, "trials_log"),
                (told.comparison_rows, "comparisons_log"),
                (told.suggestion_rows, "suggestions_log"),
                (told.feedback_rows, "feedback_log"),
            ):
                records: list[Any] = getattr(self, name)
                for k in rows:
                    records[k] = replace(records[k], undone=True)
            # withdrawn when it proposes a gait flagged unsafe since it was asked, or one in
            # the region of avoidance now
            self.pending = told.query if self.loop.pending is not None else None
        elif r.kind == log.EXCLUDED:
            # applied to the model before it was written (apply_exclusion), which withdrew the
            # pending query from the loop when one of its gaits lies in the region now
            if self.loop.pending is None:
                self.pending = None
            if r.version > log.TrialExcludedV1.version:
                self._withdraw_banned_round(r.seq)  # showing a gait in the region now
        elif r.kind == log.UNSAFE:
            self.unsafe[p["trial"]] = (p["action"], p["reason"])
            if self.loop.flag_unsafe(p["action"]):
                self.pending = None  # the pending query proposed a gait it now avoids
            self._withdraw_banned_round(r.seq)  # showing a gait near the flag
        elif r.kind == log.UNSAFE_WITHDRAWN:
            action = self.unsafe.pop(p["trial"])[0]
            if all(a != action for a, _ in self.unsafe.values()):
                self.loop.unflag_unsafe(action)
        elif r.kind == log.VALIDATION_STARTED:
            gaits = p["gaits"]
            # drawn again right after the event that withdrew it: opened by the same answer
            # (which may be undone since), not by the one now last
            again = (
                self.banned[1]
                if self.banned is not None
                and self.banned[0] == r.seq - 1
                and self.banned[1].plan.round == p["round"]
                and self.banned[1].opened_by == p.get("opened_by")
                else None
            )
            plan = ValidationPlan(
                p["round"], tuple(BlindGait(g["label"], g["action"]) for g in gaits)
            )
            self.rounds.append(
                _Round(
                    plan,
                    {g["label"]: g["role"] for g in gaits},
                    {g["label"]: g["posterior_mean"] for g in gaits},
                    r.seq,
                    {g["label"]: self.shown_gait(g["label"], g["action"]) for g in gaits},
                    version=r.version,
                    opened_by=p.get("opened_by"),
                    opened_after=(
                        again.opened_after
                        if again is not None
                        else self.told[-1].query.id
                        if p.get("opened_by") == "rule" and self.told
                        else None
                    ),
                )
            )
        elif r.kind == log.VALIDATION_WITHDRAWN:
            current = self.open_round
            assert current is not None and current.plan.round == p["round"]
            current.withdrawn = (r.seq, p["reason"])
        elif r.kind == log.VALIDATION_ANSWERED:
            current = self.open_round
            assert current is not None
            current.result = unblind(current.plan, current.roles, current.values, p["ranking"])
        elif r.kind == log.GAIT_MADE:
            self.made_rows.append(p["action"])  # a gait the subject may walk (validation)
            self.made_ids.add(p["gait_id"])
        elif r.kind == log.GAIT_INFEASIBLE:  # the loop avoids it since derive_query
            bad = InfeasibleGait(r.seq, p["action"], p["gait_id"], p["reason"], dict(p["values"]))
            self.infeasible.append(bad)
        elif r.kind == log.QUERY_STOPPED:
            pass  # its gaits are booked above; the loop proposes anew at the next ask
        elif r.kind == log.NOTE:
            self.notes.append((r.seq, p["text"]))
        elif r.kind in _STATUS_OF:
            self.status = _STATUS_OF[r.kind]
        elif r.kind != log.CREATED:
            raise ReplayError(
                f"event {r.seq}: unknown kind {r.kind!r} (written by a newer gaitpref?)"
            )

    # -- exclusion rule --------------------------------------------------------------------------
    def _excluded_actions(self, query: SessionQuery) -> tuple[set[int], set[int]]:
        """Actions of excluded trials among the query's members, and among its executed ones."""
        members = {
            a for t, a in zip(query.member_trials, query.members, strict=True) if t in self.excluded
        }
        executed = {
            a for t, a in zip(query.trials, query.actions, strict=True) if t in self.excluded
        }
        return members, executed

    def _drops(self, query: SessionQuery, answer: Answer) -> tuple[list[int], list[int]]:
        """Indices of the answer's pair terms and single-action terms an exclusion spoils."""
        members, executed = self._excluded_actions(query)
        pairs = [k for k, p in enumerate(answer.preferences) if _spoiled(p, members, executed)]
        singles = [k for k, o in enumerate(answer.singles) if o.action in executed]
        return pairs, singles

    def _flag_exclusions(self, told: _Told) -> None:
        members, executed = self._excluded_actions(told.query)
        for k in told.comparison_rows:
            c = self.comparisons_log[k]
            if c.first in members or c.second in members:
                self.comparisons_log[k] = replace(c, excluded=True)
        for k in told.suggestion_rows:
            s = self.suggestions_log[k]
            if s.action in executed:
                self.suggestions_log[k] = replace(s, excluded=True)
        if told.feedback_rows:
            others = [r for r in told.answer.records if not isinstance(r, Comparison | Suggestion)]
            context = self.loop.context()
            for k, record in zip(told.feedback_rows, others, strict=True):
                kind = kind_of(record)
                assert kind is not None
                terms = kind.observations(record, context, told.query.loop_id)
                if any(_spoiled(p, members, executed) for p in terms.preferences) or any(
                    o.action in executed for o in terms.singles
                ):
                    self.feedback_log[k] = replace(self.feedback_log[k], excluded=True)
        for k in told.trial_rows:
            t = self.trials_log[k]
            if t.number in self.excluded:
                reason, detail = self.excluded[t.number]
                self.trials_log[k] = replace(t, excluded=reason, exclusion_detail=detail)

    # -- other ----------------------------------------------------------------------------------
    def shown_gait(self, label: str, action: int) -> ShownGait:
        """``action`` as shown now, under ``label`` (a validation round keeps it)."""
        space = self.loop.space
        name = self.gait_name(action)
        return ShownGait(label, int(action), name, space.values_of(action), space.describe(action))

    def gait_name(self, action: int) -> str:
        """How the apps, exports and the stop reason name a gait: its id, or ``G<action>``.
        An action that is not one of the space's (:meth:`gait_id`) is an error, not a name."""
        action = self.loop.space.check_index(action)
        return self.gait_id(action) or f"G{action}"

    def gait_id(self, action: int) -> str | None:
        """``action``'s gait id, or None: a ``TypeError`` for an action that is not an integer
        and an ``IndexError`` for one off the grid or the line path's point table (before, -1
        was named ``G-1``, or the library's last gait)."""
        action = self.loop.space.check_index(action)
        if self.on_demand is not None:
            return self.on_demand.gait_id(self.loop.space.point(action))
        return None if self.gait_ids is None else self.gait_ids[action]

    def _withdraw_banned_round(self, seq: int) -> None:
        """Withdraw the open blind validation round (version 2 and later: drawn from the gaits
        a query may propose) when it shows a gait no query may propose now (event ``seq``)."""
        current = self.open_round
        if current is not None and current.version >= 2 and self._shows_banned(current):
            self.banned = (seq, self.rounds.pop())

    def _shows_banned(self, current: _Round) -> bool:
        """Whether ``current`` shows a gait no query may propose now.  On the line path a flag
        may have withdrawn the pending query, whose rows the round can show: those are judged
        by the values the round showed, against the flags' radius."""
        allowed = self.loop.proposable()
        space, radius = self.loop.space, self.loop.safety.unsafe_radius
        for g in current.plan.gaits:
            if g.action < len(allowed):
                if not allowed[g.action]:
                    return True
                continue
            shown = current.shown[g.label].values
            point = np.array([shown[f.name] for f in space.features], dtype=np.float64)
            if near_point(space, self.loop.unsafe, point, radius):
                return True
        return False

    def check_open(self, what: str) -> None:
        """Refuse ``what`` in a finished session."""
        if self.status == "finished":
            raise SessionStateError(f"the session is finished: it takes no {what}")

    def check_active(self, what: str) -> None:
        """Refuse ``what`` (queries and answers) unless the session is running."""
        self.check_open(what)
        if self.status == "paused":
            raise SessionStateError(f"the session is paused: resume it before {what}")

    def pending_query_error(self, query_id: object) -> QueryError:
        pending = (
            "none is pending" if self.pending is None else f"the pending query is {self.pending.id}"
        )
        answered = any(k.query.id == query_id for k in self.told)
        if answered:
            return QueryError(f"query {query_id} was already answered ({pending})")
        return QueryError(
            f"query {query_id!r} is not the pending query ({pending}): it is stale or unknown"
        )


def _line_fields(query: Query) -> dict[str, Any]:
    """A line-path query's points and line, as its ``query_issued`` event stores them."""
    if query.line is None:
        return {}
    line = query.line
    return {
        "points": [list(p) for p in query.points],
        "line": log.LineDrawn(
            seed=line.seed,
            origin=list(line.origin),
            direction=list(line.direction),
            points=line.points.tolist(),
            others=[list(v) for v in line.others] if line.others else None,
        ),
    }


def _spoiled(p: Preference, members: set[int], executed: set[int]) -> bool:
    if p.source == "comparison":
        return p.winner in members or p.loser in members
    return p.loser in executed
