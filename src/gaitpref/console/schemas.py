"""Request and response bodies of the console's JSON API (Pydantic models).

Every request model forbids unknown fields and uses strict scalars (``1`` is an integer, ``"1"``
and ``true`` are not), with bounds on every number and every list, so a malformed body is refused
with 422 naming the field (FastAPI's ``loc``) before the session API is called.  Answers use the
same triples as :meth:`gaitpref.CoSpar.tell`.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, StrictInt, StrictStr, field_validator

from gaitpref.console.limits import (
    MAX_COMPARISONS,
    MAX_CONFIG_TEXT,
    MAX_LIST,
    MAX_SUGGESTIONS,
)
from gaitpref.feedback import Outcome
from gaitpref.space import Move

MAX_ID = 2**63 - 1
#: a subject code: pseudonymous, never a name
SUBJECT_PATTERN = r"^[A-Za-z0-9._-]{1,64}$"

Id = Annotated[StrictInt, Field(ge=1, le=MAX_ID)]
GridIndex = Annotated[StrictInt, Field(ge=0, le=2**31)]
FeatureName = Annotated[StrictStr, Field(min_length=1, max_length=100)]
ComparisonTriple = tuple[GridIndex, GridIndex, Outcome]
SuggestionTriple = tuple[GridIndex, FeatureName, Move]
Note = Annotated[StrictStr, Field(max_length=2000)]


class _Request(BaseModel):
    model_config = ConfigDict(extra="forbid")


class CreateSessionIn(_Request):
    """A new session: ``config`` is a shipped config's name or the text of a TOML config."""

    config: StrictStr = Field(
        min_length=1,
        max_length=MAX_CONFIG_TEXT,
        description="a shipped config name (GET /api/configs) or TOML config text",
        examples=["exo-1d-step-length"],
    )
    subject: StrictStr = Field(
        pattern=SUBJECT_PATTERN, description="pseudonymous subject code", examples=["S01"]
    )
    seed: Annotated[StrictInt, Field(ge=0, le=MAX_ID)] | None = Field(
        default=None, description="the session's seed (default: the config's)"
    )
    prior_from: list[
        Annotated[StrictInt, Field(ge=1, le=MAX_ID)]
        | Annotated[StrictStr, Field(pattern=SUBJECT_PATTERN)]
    ] = Field(
        default_factory=list,
        max_length=MAX_LIST,
        description="warm start from these earlier sessions (ids) or subjects' sessions (codes)",
        examples=[[3, "S02"]],
    )


class CreatedOut(BaseModel):
    id: int


class FeatureOut(BaseModel):
    """A gait feature and how an operator words its coactive moves."""

    name: str
    unit: str
    values: list[float]
    words: tuple[str, str] = Field(description="(increase, decrease), e.g. (longer, shorter)")
    moves: dict[str, str] = Field(description="move -> its words, e.g. +small -> slightly longer")


class GaitOut(BaseModel):
    """A gait of the grid: its index, feature values in physical units, and its trial number."""

    index: int = Field(description="flat grid index (C order over the features)")
    gait_id: str = Field(description="the gait library's id, or G<index> without a library")
    values: dict[str, float]
    units: dict[str, str]
    trial: int | None = Field(default=None, description="the trial number it runs (or ran) as")
    made: bool | None = Field(
        default=None,
        description="with gaits made on demand, whether this session made its gait (false: a "
        "point no query proposed, such as a coactive suggestion's, never walked, which may prove "
        "infeasible; argmax may be one, and under [gaits] recommend = 'any' recommended); null "
        "when gaits are not made on demand, and for a blind validation round's gaits (made, as "
        "the round showed them)",
    )


class QueryOut(BaseModel):
    """The pending query: run ``actions`` now, compare them with ``buffer``."""

    session_id: int
    query_id: int
    actions: list[GaitOut]
    buffer: list[GaitOut]
    trials_done: int = Field(description="trials answered so far")
    comparisons: list[tuple[int, int]] = Field(
        description="the pairs (i, j) the operator is asked to compare, as grid indices"
    )


class FeedbackIn(BaseModel):
    """One answer of any registered feedback kind: ``kind`` names it (``GET
    /api/sessions/{id}`` lists the session's), the other keys are its record's fields, e.g.
    ``{"kind": "rating", "action": 7, "label": "okay"}`` (a label is a category name or its
    number ``1..K``, worst first)."""

    model_config = ConfigDict(extra="allow", json_schema_extra={"additionalProperties": True})

    kind: StrictStr = Field(min_length=1, max_length=100, examples=["rating"])

    def fields(self) -> dict[str, object]:
        """The record's fields (every key but ``kind``)."""
        return dict(self.model_extra or {})


class AnswerIn(_Request):
    """An answer to query ``query_id`` (the same triples as ``CoSpar.tell``, and ``feedback``
    records of any other registered kind, such as ratings)."""

    query_id: Id
    comparisons: list[ComparisonTriple] = Field(
        default_factory=list, max_length=MAX_COMPARISONS, examples=[[[12, 7, "first"]]]
    )
    suggestions: list[SuggestionTriple] = Field(
        default_factory=list,
        max_length=MAX_SUGGESTIONS,
        examples=[[[12, "step_length", "+small"]]],
    )
    feedback: list[FeedbackIn] = Field(
        default_factory=list,
        max_length=MAX_LIST,
        examples=[[{"kind": "rating", "action": 12, "label": "okay"}]],
    )
    note: Note | None = None


class AnsweredOut(BaseModel):
    query_id: int
    trials: list[int]
    next_query_id: int | None
    stop_warning: str | None = Field(
        default=None,
        description="the answer is stored, but the [stop] rule could not be checked after it: "
        "why (it is checked again after the next answer); null when it was",
    )
    clipped: list[str] = Field(
        default_factory=list,
        description="suggestions that asked to go past the edge of a feature's range and were "
        "clipped there (stored as given): one sentence each",
    )
    stopped: str | None = Field(
        default=None,
        description="the [stop] rule's reason when it opened blind validation after this "
        "answer (GET /api/sessions/{id}/validation lists it); null when it did not",
        examples=["30 trials reached max_trials = 30"],
    )


class UndoIn(_Request):
    """Optionally name the pending query the undo was decided on: refused (409) if it changed."""

    query_id: Id | None = None


class UndoneOut(BaseModel):
    pending_query_id: int | None = Field(
        description="the query pending now: the one whose answer was taken back, or, when it "
        "proposed a gait flagged unsafe since or in the region of avoidance now, a new one in "
        "its place (null while the session is "
        "paused or a validation round is open: GET /query proposes it)"
    )
    trials: list[int] = Field(description="its trial numbers (they will be given again)")
    discarded_query_id: int | None = Field(
        description="the query that was pending before the undo (withdrawn)"
    )
    undone_query_id: int = Field(description="the query whose answer was taken back")
    withdrawn: bool = Field(
        description="the undone query proposed a gait flagged unsafe after it was asked, or "
        "one in the region of avoidance as the undo left the model (an exclusion since moved "
        "it), so it was withdrawn rather than asked again"
    )
    next_query_error: str | None = Field(
        default=None,
        description="the undo stands, but no query could be proposed in the withdrawn one's "
        "place: why (the gait generator's error, that no gait may be proposed, or the database's "
        "error writing the new query); GET /query tries again (503 while the generator or the "
        "database fails, 409 while no gait may be proposed). Null otherwise",
    )


class NoteIn(_Request):
    text: Annotated[StrictStr, Field(min_length=1, max_length=2000)]

    @field_validator("text")
    @classmethod
    def _not_blank(cls, text: str) -> str:
        if not text.strip():
            raise ValueError("the note is empty (only white space)")
        return text


class ExcludeIn(_Request):
    reason: Literal["device_fault", "stumble", "distracted", "other"]
    detail: Annotated[StrictStr, Field(max_length=500)] = ""


class ConfidenceOut(BaseModel):
    """How sure the model is of its recommended gait (``gaitpref.loop.stopping``)."""

    sentence: str = Field(examples=["88% that G95 is within 5% of the best"])
    probability: float = Field(description="P(the gait is within tolerance of the best)")
    tolerance: float = Field(description="a fraction of the utility's range")
    regret: float = Field(description="expected shortfall of stopping now, utility units")
    relative_regret: float = Field(description="the same as a fraction of the range")
    samples: int


class PosteriorOut(BaseModel):
    """Posterior mean and standard deviation of the utility of every action (grid order)."""

    session_id: int
    features: list[str]
    shape: list[int] | None = Field(
        description="the grid's shape (None: no grid; mean and sd are over the points present, "
        "the visited points and the current line)"
    )
    mean: list[float]
    sd: list[float]
    argmax: GaitOut | None = Field(
        description="the gait of the highest posterior mean over every gait, which may be one "
        "that may not be proposed (flagged unsafe, near one, in the region of avoidance): see "
        "recommended (None while there is no point: the line path before its first query)"
    )
    recommended: GaitOut | None = Field(
        default=None,
        description="the best gait so far to walk: the highest posterior mean among the gaits "
        "that may be proposed (with gaits made on demand under [gaits] recommend = 'made', "
        "defaults 0.13 on, among the gaits made), the one confidence is about (None while there "
        "is no point, and when no gait may be recommended: see no_recommendation). Before a "
        "preference is learned (learned false) it is still the flat prior's argmax, the first "
        "gait that may be proposed, for no reason",
    )
    no_recommendation: str | None = Field(
        default=None,
        description="why no gait is recommended (None: one is, or the posterior has no point "
        "yet): every gait is in the region of avoidance or near a gait flagged unsafe, or, with "
        "gaits made on demand, no gait was made yet or every gait made is",
    )
    learned: bool = Field(
        description="whether a preference has been learned: the posterior mean tells some gaits "
        'apart (false before any answer, and after ties only; the trial page then says "No '
        'preference learned yet" and session show "none yet"). While false, argmax and '
        "recommended name the first gait for no reason",
    )
    trials: list[int] = Field(description="executed actions in trial order")
    confidence: ConfidenceOut | None = Field(
        default=None,
        description="how sure the model is of recommended (None before any answer, and when no "
        "gait may be proposed)",
    )


class SessionItemOut(BaseModel):
    """A session as listed: its row, without replaying its log."""

    id: int
    subject: str
    config: str
    status: str
    events: int = Field(description="events in its log")
    created_at: str
    updated_at: str


class RatingScaleOut(BaseModel):
    """The config's rating scale (``[feedback.rating]``), worst first."""

    categories: list[str]
    avoid: int = Field(description="the worst categories avoided by [safety] (0: none)")


class EarlierSessionOut(BaseModel):
    """An earlier session a warm start read, as its ``created`` event records it."""

    session: int
    subject: str
    last_seq: int = Field(description="the last of its events read (those since are not used)")


class SessionOut(BaseModel):
    """A session with what its log says now."""

    id: int
    subject: str
    config: str
    status: str
    events: int = Field(description="events in its log")
    created_at: str
    seed: int
    trials: int = Field(description="trials in force (answered, not undone)")
    pending_query_id: int | None
    validation_open: bool
    features: list[FeatureOut]
    rating: RatingScaleOut | None = Field(
        default=None, description="the rating scale, when the config asks for ratings"
    )
    unsafe: dict[int, str] = Field(
        default_factory=dict, description="trials flagged unsafe -> the reason"
    )
    stop_blocked: str | None = Field(
        default=None,
        description="why the [stop] rule, which says stop, cannot open blind validation (fewer "
        "than three gaits may be shown, or nothing learnt); None otherwise",
    )
    prior_from: list[EarlierSessionOut] = Field(
        default_factory=list,
        description="the earlier sessions its warm start read (empty: a cold start)",
    )
    prior_rho: float | None = Field(
        default=None, description="the shared fraction learnt from them (null: a cold start)"
    )


class TrialOut(BaseModel):
    """An executed trial (the chronology)."""

    trial: int
    query_id: int
    gait: GaitOut
    excluded: str | None = Field(description="the exclusion reason, if excluded")
    unsafe: str | None = Field(default=None, description="the unsafe flag's reason, if flagged")
    rating: str | None = Field(default=None, description="the category it was rated, if rated")


class UnsafeIn(_Request):
    """Flag an answered trial unsafe: its gait and those within the config's
    ``[safety] unsafe_radius`` are never proposed again."""

    reason: Annotated[StrictStr, Field(min_length=1, max_length=2000)] = Field(
        description="what happened (required)", examples=["knee hyperextension"]
    )


class ConfigOut(BaseModel):
    name: str
    grid: list[int] | None = Field(description="values per feature (None: continuous features)")
    space: str = Field(description="the space in words, e.g. '15 x 10' or 'continuous: ...'")
    n: int
    buffer: int
    description: str


class AckOut(BaseModel):
    query_id: int
    acknowledged: bool = Field(description="false when it had been acknowledged before")


class NoteOut(BaseModel):
    seq: int


class EventOut(BaseModel):
    seq: int
    kind: str
    at: str
    payload: dict[str, object]


class StatusIn(_Request):
    status: Literal["active", "paused", "finished"]


class ValidationGaitOut(BaseModel):
    label: str
    gait: GaitOut


class ValidationOut(BaseModel):
    """A blind validation round: the gaits in their stored random order (roles hidden)."""

    round: int
    gaits: list[ValidationGaitOut]
    ranking: list[str] | None = None
    model_ranking: list[str] | None = None
    roles: dict[str, str] | None = None
    agrees: bool | None = None
    kendall_tau: float | None = None
    opened_by: Literal["rule", "operator"] | None = Field(
        default=None,
        description="who opened the round: the [stop] rule after an answer, or the operator; "
        "null for a round logged before releases recorded it",
    )


class WithdrawRoundIn(_Request):
    reason: StrictStr = Field(
        min_length=1, max_length=2000, description="why the round is withdrawn (logged)"
    )
    undo: bool = Field(
        default=False,
        description="also take back the answer after which the [stop] rule opened the round "
        "(refused, 409, for a round the rule did not open or whose answer is no longer the last)",
    )


class WithdrawnRoundOut(BaseModel):
    round: int = Field(
        description="the round withdrawn (its log stays; the next takes the next number)"
    )
    undone_query_id: int | None = Field(
        description="the query whose answer was taken back with it (null without undo)"
    )
    trials: list[int] = Field(description="that answer's trial numbers (empty without undo)")
    pending_query_id: int | None = Field(
        description="the query pending now (with undo: the undone one asked again, or a new one "
        "in its place when it proposed a gait flagged unsafe since or in the region of avoidance "
        "now; null while paused, or when none could be proposed: next_query_error says why)"
    )
    next_query_error: str | None = Field(
        default=None,
        description="the withdrawal and undo stand, but no query could be proposed in place of "
        "the undone one, withdrawn: why (as UndoneOut's: the database failed to write it, ...; "
        "GET /query tries again); null otherwise",
    )


class RankingIn(_Request):
    ranking: list[Annotated[StrictStr, Field(min_length=1, max_length=4)]] = Field(
        min_length=1, max_length=8, description="labels, best first", examples=[["B", "A", "C"]]
    )
    shown: list[Annotated[StrictStr, Field(min_length=1, max_length=200)]] | None = Field(
        None,
        max_length=8,
        description=(
            "optional: the gait ids the round showed, in label order (as GET .../validation "
            "gave them); refused (409) if a flag drew the round again since"
        ),
        examples=[["G7", "G14", "G2"]],
    )


class ErrorOut(BaseModel):
    detail: str


__all__ = [
    "SUBJECT_PATTERN",
    "AckOut",
    "AnswerIn",
    "AnsweredOut",
    "ComparisonTriple",
    "ConfigOut",
    "CreateSessionIn",
    "CreatedOut",
    "ErrorOut",
    "EventOut",
    "ExcludeIn",
    "FeatureOut",
    "FeedbackIn",
    "GaitOut",
    "Move",
    "NoteIn",
    "NoteOut",
    "PosteriorOut",
    "QueryOut",
    "RankingIn",
    "RatingScaleOut",
    "SessionItemOut",
    "SessionOut",
    "StatusIn",
    "SuggestionTriple",
    "TrialOut",
    "UndoIn",
    "UndoneOut",
    "UnsafeIn",
    "ValidationGaitOut",
    "ValidationOut",
    "WithdrawRoundIn",
    "WithdrawnRoundOut",
]
