"""A session's events: one typed, versioned payload class per kind (``gaitpref.payloads``).

A session's log is a sequence of events (``storage/base.py``).  Each answer is one batch: the
``trial_executed`` events of the query's actions, then one event per feedback record (the
kind's own payload class, ``gaitpref.feedback``: ``comparison_answered``, ``suggestion_given``,
...) and, when the answer triggered a hyperparameter fit, its ``hyperparameters_refit`` event
(and, in a warm-started session that re-learns the new subject's share, its ``share_refit``),
all carrying the query's id.  A query's ``id`` is the sequence number of its ``query_issued``
event: unique in the session and never reused.  With gaits made on demand, a query is a batch too:
``gait_made`` for each gait new to the session and ``gait_infeasible`` for each proposal whose gait
cannot be made (the loop proposes again without it), then the ``query_issued``; an ask that
reaches ``[gaits] max_infeasible`` such proposals (or after some finds no gait left that may be
proposed) ends its batch with ``query_stopped`` instead and proposes nothing.

Payloads are validated when written (:func:`new_event`) and when read (:func:`read_payload`,
which also checks the stored schema version).  Replay compares each re-derived event with the
logged one on the payload class's :meth:`~gaitpref.payloads.EventPayload.checked_fields`:
numbers within a relative 1e-9 (:func:`same_value`), because another machine's BLAS rounds
differently in the last bits; everything else exactly.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, ClassVar, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    SerializerFunctionWrapHandler,
    model_serializer,
)

from gaitpref.errors import ReplayError
from gaitpref.feedback import kind_for_event
from gaitpref.payloads import EventPayload, PayloadError, Recorded
from gaitpref.sessions.records import Reason
from gaitpref.storage import EventRecord, NewEvent


class PriorSession(BaseModel):
    """An earlier session a warm start read: its log up to ``last_seq`` hashed (``sha256``)."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)
    session: int
    subject: str
    last_seq: int
    sha256: str


class Created(EventPayload):
    """``created``: what the session was made of (also in the session's row)."""

    kind: ClassVar[str] = "created"
    subject: str
    config_name: str
    config_sha256: str
    seed: int
    software_version: str
    gait_library: bool = False
    # warm starts (0.2; absent in 0.1.0 logs): the earlier sessions read, and the shared fraction
    prior_from: list[PriorSession] = Field(default_factory=list)
    prior_rho: float | None = None
    # what the warm start carries: "all" (every registered kind's terms in force: preferences,
    # ties, ratings); absent: their preferences only (the first warm starts, replayed as written)
    prior_terms: Literal["all"] | None = None
    # the new subject's share re-learned every k answers (``share_refit`` events); absent: rho
    # held for the whole session (warm starts recorded before, replayed as written)
    prior_relearn_every: int | None = None
    # with it: the new subject starts alone (share 0) and shares only where the evidence favours
    # sharing over being alone by more than this many nats (``loop/warm.py``)
    prior_share_gate: float | None = None

    @model_serializer(mode="wrap")
    def _without_a_cold_start(self, handler: SerializerFunctionWrapHandler) -> Any:
        """A session without a warm start stores what 0.1 stored (and one whose warm start
        carries preferences only, what it stored then)."""
        out = handler(self)
        if isinstance(out, dict):
            if out.get("prior_terms") is None:
                out.pop("prior_terms", None)
            for key in ("prior_relearn_every", "prior_share_gate"):
                if out.get(key) is None:
                    out.pop(key, None)
            if not out.get("prior_from"):
                out.pop("prior_from", None)
                out.pop("prior_rho", None)
        return out


class LineDrawn(BaseModel):
    """The line a line-path query was chosen along (``loop/lines.py``): its seed, origin,
    unit direction (range-normalised) and points (the features' units); for a star of lines
    (``[cospar] line_count`` > 1; absent for one line, as every query stored before) the other
    lines' directions, ``others``, the points being every line's."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)
    seed: int
    origin: list[float]
    direction: list[float]
    points: list[list[float]]
    others: list[list[float]] | None = None

    @model_serializer(mode="wrap")
    def _one_line(self, handler: SerializerFunctionWrapHandler) -> Any:
        """One line stores what every line-path query stored before stars."""
        out = handler(self)
        if isinstance(out, dict) and out.get("others") is None:
            out.pop("others", None)
        return out


class QueryIssued(EventPayload):
    """``query_issued``: run ``actions`` as trials ``trials``; compare with ``buffer``.

    On the line path (issue 13; absent on the grid path, as 0.1 wrote every query) also the
    actions' ``points`` (feature values, one row per action) and the ``line`` they were chosen
    along; replay re-derives and compares both.
    """

    kind: ClassVar[str] = "query_issued"
    query_loop_id: int
    actions: list[int]
    buffer: list[int]
    trials: list[int]
    buffer_trials: list[int]
    points: list[list[float]] | None = None
    line: LineDrawn | None = None

    @model_serializer(mode="wrap")
    def _without_a_line(self, handler: SerializerFunctionWrapHandler) -> Any:
        """A grid-path query stores what 0.1 stored."""
        out = handler(self)
        if isinstance(out, dict):
            for key in ("points", "line"):
                if out.get(key) is None:
                    out.pop(key, None)
        return out


class TrialExecuted(EventPayload):
    """``trial_executed``: one executed action of an answered query, with its feature values."""

    kind: ClassVar[str] = "trial_executed"
    query: int
    trial: int
    action: int
    values: Annotated[dict[str, float], Recorded]
    gait_id: Annotated[str | None, Recorded] = None


class GaitPayload(EventPayload):
    """What a gait made on demand is logged with: the proposed ``action``, its gait id, its
    content address ``key`` in the gait cache and the key it was warm-started from."""

    action: int
    gait_id: str
    key: str
    values: Annotated[dict[str, float], Recorded]
    warm_start: Annotated[str | None, Recorded] = None


class GaitMadeV1(GaitPayload):
    """``gait_made`` as first written (payload version 1): without the gait, which replay takes
    from the gait cache or makes again."""

    kind: ClassVar[str] = "gait_made"
    cot: Annotated[float, Recorded]


class GaitInfeasibleV1(GaitPayload):
    """``gait_infeasible`` as first written (payload version 1): without the gait."""

    kind: ClassVar[str] = "gait_infeasible"
    radius: float
    reason: Annotated[str, Recorded]


class GaitMade(GaitMadeV1):
    """``gait_made``: the gait of a proposed action, made on demand (or found in the gait cache)
    the first time the session proposed it (``gaits/on_demand.py``); logged with its query.

    Version 2 carries the ``gait`` itself (``gaits/gait_cache.py``'s ``gait_document``: step
    length, Bezier coefficients, orbit, COT, verdict and solver message; under 1 kB), so that
    replay takes it from the log instead of optimising it again: a gait optimiser is sensitive
    to rounding, and another machine could make another gait.  Replay checks it (``gaits.py``)
    rather than comparing it with a re-derived one.
    """

    version: ClassVar[int] = 2
    gait: Annotated[dict[str, Any], Recorded]


class GaitInfeasible(GaitInfeasibleV1):
    """``gait_infeasible``: a proposed action whose gait cannot be made.  It is never shown as a
    trial; it and the actions within ``radius`` of it (``[gaits].avoid_radius``) are never
    proposed again, and the next proposal follows in the same batch (``reason``: the solver's).
    Version 2 carries the refused ``gait`` (as :class:`GaitMade`: its verdict and reason)."""

    version: ClassVar[int] = 2
    gait: Annotated[dict[str, Any], Recorded]


class QueryStopped(EventPayload):
    """``query_stopped``: an ask that proposed nothing, written after its gait events: its
    proposals' gaits could not be made, ``infeasible`` of them (``gait_infeasible`` events of
    this batch), once ``[gaits] max_infeasible`` (``limit``) was reached; each is avoided, so the
    next ask goes on from there (``sessions/gaits.py``).  ``infeasible`` under ``limit``: the
    ask stopped because, with those avoided, no gait was left that may be proposed (on the line
    path also: no line that has one holds the query's ``n`` points; the payload is the same;
    logs from before have no such event, as such an ask wrote nothing).  Replay stops the batch
    where the log does, with the logged ``limit``.  An ask cut by the gait generator's error
    is not logged (``sessions/gaits.py`` says why)."""

    kind: ClassVar[str] = "query_stopped"
    infeasible: Annotated[int, Field(ge=1)]
    limit: Annotated[int, Field(ge=1)]


class HyperValues(BaseModel):
    """The hyperparameters before or after a refit; ``thresholds`` (the ordinal ratings') only
    when they are fitted, and absent otherwise (as 0.1.0 wrote every refit)."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)
    lengthscale: list[float]
    signal_variance: float
    jitter: float
    tie_band: float | None
    thresholds: list[float] | None = None

    @model_serializer(mode="wrap")
    def _without_unfitted_thresholds(self, handler: SerializerFunctionWrapHandler) -> Any:
        return _without_none(handler(self), "thresholds")


def _without_none(out: Any, key: str) -> Any:
    """A serialised payload without ``key`` when it is None (a field older records lack)."""
    if isinstance(out, dict) and out.get(key) is None:
        out.pop(key, None)
    return out


class HypothesisValues(BaseModel):
    """One lengthscale hypothesis of a refit with ``[model].hyper = "average"``
    (``model/hypermix.py``): its factor of the fitted lengthscales, the lengthscales, its log
    evidence plus log prior (None: its Laplace fit failed) and its weight."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)
    factor: float
    lengthscale: list[float]
    objective: float | None
    weight: float


class HyperparametersRefit(EventPayload):
    """``hyperparameters_refit``: the evidence fit an answer triggered (``model/hyperfit.py``)."""

    kind: ClassVar[str] = "hyperparameters_refit"
    query: int
    before: HyperValues
    after: HyperValues
    accepted: bool
    converged: Annotated[bool, Recorded]
    message: Annotated[str, Recorded]
    evaluations: Annotated[int, Recorded]
    failed_evaluations: Annotated[int, Recorded]
    objective_before: Annotated[float | None, Recorded]
    objective_after: Annotated[float | None, Recorded]
    observations: Annotated[int, Recorded]
    #: only with ``hyper = "average"``; absent otherwise (as every earlier refit was written)
    hypotheses: list[HypothesisValues] | None = None

    @model_serializer(mode="wrap")
    def _without_hypotheses(self, handler: SerializerFunctionWrapHandler) -> Any:
        return _without_none(handler(self), "hypotheses")


class ShareValues(BaseModel):
    """One share hypothesis of a ``share_refit`` with ``[model].share = "average"``
    (``model/share_mix.py``): its share, prior mass, log evidence plus log prior mass (None: its
    Laplace fit failed) and weight."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)
    share: float
    prior: float
    objective: float | None
    weight: float


class ShareRefit(EventPayload):
    """``share_refit``: the new subject's shared fraction refitted by the evidence after this
    answer (a warm start that re-learns it; ``model/share_fit.py``); with ``[model].share =
    "average"`` the share hypotheses weighed (``hypotheses``; ``after`` their mean share)."""

    kind: ClassVar[str] = "share_refit"
    query: int
    before: float
    after: float
    accepted: bool
    message: Annotated[str, Recorded]
    evaluations: Annotated[int, Recorded]
    objective_before: Annotated[float | None, Recorded]
    objective_after: Annotated[float | None, Recorded]
    #: only with ``share = "average"``; absent otherwise (as every earlier share refit was
    #: written: the payload of those is unchanged, version 1)
    hypotheses: list[ShareValues] | None = None

    @model_serializer(mode="wrap")
    def _without_hypotheses(self, handler: SerializerFunctionWrapHandler) -> Any:
        return _without_none(handler(self), "hypotheses")


class UndoV1(EventPayload):
    """``undo`` as first written (payload version 1): the query it restores is withdrawn only
    when it proposes a gait flagged unsafe or avoided since it was asked."""

    kind: ClassVar[str] = "undo"
    query: int
    trials: list[int]


class Undo(UndoV1):
    """``undo``: the answer to ``query`` (its trials) is taken back.  Version 2 also withdraws
    the query it restores when one of its gaits lies in the region of avoidance of the model as
    the undo leaves it (an exclusion made after the answer moves the region; ``CoSpar.undo``);
    the payload is unchanged."""

    version: ClassVar[int] = 2


class TrialExcludedV1(EventPayload):
    """``trial_excluded`` as first written (payload version 1): the query pending when it was
    made stays pending, whatever the exclusion does to the region of avoidance."""

    kind: ClassVar[str] = "trial_excluded"
    trial: int
    query: int
    action: int
    reason: Reason
    detail: Annotated[str, Recorded] = ""


class TrialExcluded(TrialExcludedV1):
    """``trial_excluded``: a trial's answers leave the model; the records stay, flagged.
    Version 2 also withdraws the pending query when one of its gaits lies in the region of
    avoidance of the model as the exclusion leaves it (``CoSpar.exclude``), and an open
    version-2 blind validation round that shows a gait no query may propose now; the payload
    is unchanged."""

    version: ClassVar[int] = 2


class TrialFlaggedUnsafe(EventPayload):
    """``trial_flagged_unsafe``: the operator's hard stop; the trial's gait, and the gaits within
    ``[safety].unsafe_radius`` of it, are never proposed again (``loop/safety.py``)."""

    kind: ClassVar[str] = "trial_flagged_unsafe"
    trial: int
    query: int
    action: int
    reason: Annotated[str, Recorded]


class UnsafeFlagWithdrawn(EventPayload):
    """``unsafe_flag_withdrawn``: an unsafe flag taken back (its undo)."""

    kind: ClassVar[str] = "unsafe_flag_withdrawn"
    trial: int
    action: int


class BlindGaitShown(BaseModel):
    """One gait of a blind validation round: its label, action, role and posterior mean."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)
    label: str
    action: int
    role: str
    posterior_mean: float


class ValidationStartedV1(EventPayload):
    """``validation_started`` as first written (payload version 1): its three gaits chosen among
    every gait (every made gait, with gaits made on demand)."""

    kind: ClassVar[str] = "validation_started"
    round: int
    gaits: list[BlindGaitShown]


class ValidationStartedV2(ValidationStartedV1):
    """``validation_started`` as written by version 2: the paper's blind validation
    (``validation.py``), its three gaits chosen among the gaits a query could propose when the
    round starts: none near a gait flagged unsafe, avoided, or in the region of avoidance (a
    subject never walks a gait the operator stopped); the payload is version 1's."""

    version: ClassVar[int] = 2


#: who opened a blind validation round: the ``[stop]`` rule after an answer, or the operator
Opener = Literal["rule", "operator"]


class ValidationStarted(ValidationStartedV2):
    """``validation_started``: the paper's blind validation, its gaits chosen as version 2
    chooses them.  Version 3 also records who opened the round, ``opened_by``: ``"rule"`` (the
    ``[stop]`` rule, right after an answer) or ``"operator"`` (by hand; a round drawn again
    after a flag keeps its opener, and is None when that round's log did not say: one of an
    earlier release).  Written for the reader: replay takes it from the log; rounds of
    versions 1 and 2 read as opened by an unknown hand (None)."""

    version: ClassVar[int] = 3
    opened_by: Annotated[Opener | None, Recorded] = None


class ValidationWithdrawn(EventPayload):
    """``validation_withdrawn``: the operator withdrew the open, unanswered blind validation
    ``round`` (a mis-keyed answer made the ``[stop]`` rule open it, say), saying why
    (``reason``).  Its ``validation_started`` stays as written; the round is closed unanswered,
    queries and answers go on, and the next round takes the next number.  When the rule opened
    it, an ``undo`` of the answer that opened it may follow in the same transaction."""

    kind: ClassVar[str] = "validation_withdrawn"
    round: int
    reason: Annotated[str, Recorded]


class ValidationAnswered(EventPayload):
    """``validation_answered``: the subject's ranking and how it compares with the model's."""

    kind: ClassVar[str] = "validation_answered"
    round: int
    ranking: list[str]
    model_ranking: list[str]
    agrees: bool
    kendall_tau: float


class Note(EventPayload):
    """``note``: the operator's free text."""

    kind: ClassVar[str] = "note"
    text: str


class Paused(EventPayload):
    kind: ClassVar[str] = "paused"


class Resumed(EventPayload):
    kind: ClassVar[str] = "resumed"


class Finished(EventPayload):
    kind: ClassVar[str] = "finished"


SESSION_PAYLOADS: tuple[type[EventPayload], ...] = (
    Created,
    QueryIssued,
    GaitMade,
    GaitInfeasible,
    QueryStopped,
    TrialExecuted,
    HyperparametersRefit,
    ShareRefit,
    Undo,
    TrialExcluded,
    TrialFlaggedUnsafe,
    UnsafeFlagWithdrawn,
    ValidationStarted,
    ValidationWithdrawn,
    ValidationAnswered,
    Note,
    Paused,
    Resumed,
    Finished,
)
_BY_KIND = {p.kind: p for p in SESSION_PAYLOADS}
#: earlier payload versions still read, because events of them exist and are never rewritten
#: (new events are written in the newest): (kind, version) -> class
OLDER_PAYLOADS: dict[tuple[str, int], type[EventPayload]] = {
    (p.kind, p.version): p
    for p in (
        GaitMadeV1,
        GaitInfeasibleV1,
        ValidationStartedV1,
        ValidationStartedV2,
        UndoV1,
        TrialExcludedV1,
    )
}

CREATED = Created.kind
QUERY = QueryIssued.kind
GAIT_MADE = GaitMade.kind
GAIT_INFEASIBLE = GaitInfeasible.kind
QUERY_STOPPED = QueryStopped.kind
TRIAL = TrialExecuted.kind
REFIT = HyperparametersRefit.kind
SHARE_REFIT = ShareRefit.kind
UNDO = Undo.kind
EXCLUDED = TrialExcluded.kind
UNSAFE = TrialFlaggedUnsafe.kind
UNSAFE_WITHDRAWN = UnsafeFlagWithdrawn.kind
VALIDATION_STARTED = ValidationStarted.kind
VALIDATION_ANSWERED = ValidationAnswered.kind
VALIDATION_WITHDRAWN = ValidationWithdrawn.kind
NOTE = Note.kind
PAUSED = Paused.kind
RESUMED = Resumed.kind
FINISHED = Finished.kind


def payload_class(kind: str) -> type[EventPayload] | None:
    """The payload class of event ``kind``: a session event's or a feedback kind's."""
    found = _BY_KIND.get(kind)
    if found is not None:
        return found
    feedback = kind_for_event(kind)
    return None if feedback is None else feedback.payload_type


def is_feedback(kind: str) -> bool:
    """Whether events of ``kind`` store a feedback record."""
    return kind_for_event(kind) is not None


def is_query_part(kind: str) -> bool:
    """Whether events of ``kind`` are written in a query's batch, before its ``query_issued``."""
    return kind in (GAIT_MADE, GAIT_INFEASIBLE)


def is_answer_part(kind: str) -> bool:
    """Whether events of ``kind`` belong to an answer's batch."""
    return kind in (TRIAL, REFIT, SHARE_REFIT) or is_feedback(kind)


def new_event(payload: EventPayload) -> NewEvent:
    """The event that stores ``payload`` (validated when it was made)."""
    return NewEvent(payload.kind, payload.to_json(), version=payload.version)


def check_new(event: NewEvent, session_id: int) -> None:
    """Validate an event about to be written (a payload built as a dict is checked too)."""
    cls = payload_class(event.kind)
    where = f"session {session_id}: new {event.kind} event"
    if cls is None:
        raise ReplayError(f"{where}: unknown event kind {event.kind!r}")
    if event.version != cls.version:
        raise ReplayError(f"{where}: payload version {event.version}, expected {cls.version}")
    try:
        cls.parse(event.payload, where)
    except PayloadError as exc:
        raise ReplayError(str(exc)) from None


def read_payload(record: EventRecord) -> EventPayload:
    """The validated payload of a stored event; :class:`ReplayError` names session, event and
    field (an unknown kind, another schema version, a payload that does not validate)."""
    where = f"session {record.session_id}, event {record.seq} ({record.kind})"
    cls = payload_class(record.kind)
    if cls is None:
        raise ReplayError(
            f"{where}: unknown event kind {record.kind!r} (written by a newer gaitpref, or by a "
            "feedback kind that is not registered here?)"
        )
    if record.version != cls.version:
        older = OLDER_PAYLOADS.get((record.kind, record.version))
        if older is None:
            versions = sorted([v for k, v in OLDER_PAYLOADS if k == record.kind] + [cls.version])
            raise ReplayError(
                f"{where}: payload schema version {record.version}; this gaitpref reads "
                f"{record.kind!r} of version {' or '.join(map(str, versions))}"
            )
        cls = older
    try:
        return cls.parse(record.payload, where)
    except PayloadError as exc:
        raise ReplayError(f"{exc} (the stored event is left as it is)") from None


#: how far a re-derived number may be from the logged one and still be the same: the rounding
#: of another machine's BLAS (summation order, SIMD width), not a different computation
REL_TOL = 1e-9
ABS_TOL = 1e-12


def same_value(logged: Any, derived: Any) -> bool:
    """Whether a logged JSON value and a re-derived one agree: numbers within :data:`REL_TOL`
    (or :data:`ABS_TOL` near zero), lists and objects item by item, everything else exactly."""
    if isinstance(logged, bool) or isinstance(derived, bool):
        return logged is derived
    if isinstance(logged, int | float) and isinstance(derived, int | float):
        if isinstance(logged, int) and isinstance(derived, int):
            return logged == derived
        return math.isclose(logged, derived, rel_tol=REL_TOL, abs_tol=ABS_TOL)
    if isinstance(logged, list) and isinstance(derived, list):
        return len(logged) == len(derived) and all(
            same_value(a, b) for a, b in zip(logged, derived, strict=True)
        )
    if isinstance(logged, dict) and isinstance(derived, dict):
        return logged.keys() == derived.keys() and all(
            same_value(logged[k], derived[k]) for k in logged
        )
    return bool(logged == derived)


#: the longest value a mismatch shows whole (characters of its repr): a longer list or object
#: is shown at its first difference (a line-path query's ``line`` holds up to 4,096 points)
SHOWN_WHOLE = 200


def describe_mismatch(seq: int, kind: str, logged: dict[str, Any], derived: dict[str, Any]) -> str:
    """One line per checked field that differs between the log and what replay re-derived
    (a long list or object at its first difference: :func:`_difference`)."""
    cls = payload_class(kind)
    fields = cls.checked_fields() if cls else tuple(sorted(set(logged) | set(derived)))
    lines = [
        f"  {_difference(name, logged.get(name), derived.get(name))}"
        for name in fields
        if not same_value(logged.get(name), derived.get(name))
    ]
    return f"event {seq} ({kind}):\n" + "\n".join(lines)


def _difference(path: str, logged: Any, derived: Any) -> str:
    """``path: log has ..., replay gives ...``: both values whole when short
    (:data:`SHOWN_WHOLE`), else the first item or key where they differ, or their lengths or
    keys when those differ."""
    whole, other = repr(logged), repr(derived)
    if len(whole) <= SHOWN_WHOLE and len(other) <= SHOWN_WHOLE:
        return f"{path}: log has {whole}, replay gives {other}"
    if isinstance(logged, dict) and isinstance(derived, dict):
        if logged.keys() != derived.keys():
            return f"{path}: log has keys {sorted(logged)}, replay gives keys {sorted(derived)}"
        key = next(k for k in logged if not same_value(logged[k], derived[k]))
        return _difference(f"{path}.{key}", logged[key], derived[key])
    if isinstance(logged, list) and isinstance(derived, list):
        if len(logged) != len(derived):
            return f"{path}: log has {len(logged)} items, replay gives {len(derived)} items"
        i = next(
            i for i, (a, b) in enumerate(zip(logged, derived, strict=True)) if not same_value(a, b)
        )
        return _difference(f"{path}[{i}]", logged[i], derived[i])
    return f"{path}: log has {_clipped(whole)}, replay gives {_clipped(other)}"


def _clipped(text: str) -> str:
    return text if len(text) <= SHOWN_WHOLE else text[:SHOWN_WHOLE] + "..."


def same_event(record: EventRecord, derived: NewEvent) -> bool:
    """Whether the logged event and the re-derived one agree on every checked field (numbers
    within rounding: :func:`same_value`)."""
    if derived.kind != record.kind:
        return False
    cls = payload_class(record.kind)
    fields = cls.checked_fields() if cls is not None else ()
    return all(same_value(record.payload.get(f), derived.payload.get(f)) for f in fields)


__all__ = [
    "OLDER_PAYLOADS",
    "SESSION_PAYLOADS",
    "BlindGaitShown",
    "Created",
    "Finished",
    "GaitInfeasible",
    "GaitInfeasibleV1",
    "GaitMade",
    "GaitMadeV1",
    "GaitPayload",
    "HyperValues",
    "HyperparametersRefit",
    "LineDrawn",
    "Note",
    "Opener",
    "Paused",
    "PriorSession",
    "QueryIssued",
    "QueryStopped",
    "Resumed",
    "ShareRefit",
    "TrialExcluded",
    "TrialExcludedV1",
    "TrialExecuted",
    "TrialFlaggedUnsafe",
    "Undo",
    "UndoV1",
    "UnsafeFlagWithdrawn",
    "ValidationAnswered",
    "ValidationStarted",
    "ValidationStartedV1",
    "ValidationStartedV2",
    "ValidationWithdrawn",
    "check_new",
    "describe_mismatch",
    "is_answer_part",
    "is_feedback",
    "is_query_part",
    "new_event",
    "payload_class",
    "read_payload",
    "same_event",
    "same_value",
]
