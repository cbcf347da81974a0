"""A coactive suggestion: "executed action ``a`` would be better with ``feature`` moved".

The paper's coactive feedback: the move ``a -> a~`` (a fraction of the feature's range,
``space.coactive_move``) enters the model as a preference ``a~ > a`` with probit noise
``sigma / beta`` (``beta``: the coactive weight); a move that clips back to ``a`` is stored and
ignored.  Stored as a ``suggestion_given`` event, with its target action.  A move that would
leave the feature's range is clipped at its edge; :func:`clipped_note` says so for the operator
(``Answered.clipped``), and what is stored is the suggestion as given either way.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

from gaitpref.errors import FeedbackError
from gaitpref.feedback.base import (
    ExportTable,
    FeedbackKind,
    ModelContext,
    Observations,
    Preference,
    QueryView,
    TrialQuery,
    expect_fields,
    grid_index,
)
from gaitpref.payloads import EventPayload
from gaitpref.space import MOVES, Move, Space


@dataclass(frozen=True)
class Suggestion:
    """ "Executed action ``action`` would be better with ``feature`` moved by ``move``"."""

    action: int
    feature: str
    move: Move


class SuggestionGiven(EventPayload):
    """``suggestion_given``: the suggestion, its trial and the action it points to (None:
    the move clipped back to the same action)."""

    kind: ClassVar[str] = "suggestion_given"
    version: ClassVar[int] = 1

    query: int
    trial: int
    action: int
    feature: str
    move: Move
    target: int | None


class SuggestionKind(FeedbackKind[Suggestion]):
    """Coactive suggestions for actions executed in the query, one per (action, feature)."""

    name: ClassVar[str] = "suggestion"
    record_type: ClassVar[type[Suggestion]] = Suggestion
    payload_type: ClassVar[type[EventPayload]] = SuggestionGiven
    export: ClassVar[ExportTable] = ExportTable(
        "suggestions", ("query", "trial", "action", "feature", "move", "target")
    )

    def parse(self, raw: object, query: QueryView, context: ModelContext, where: str) -> Suggestion:
        space = context.space
        if isinstance(raw, Suggestion):
            raw = (raw.action, raw.feature, raw.move)
        item = expect_fields(raw, ("action", "feature", "move"), where)
        action = grid_index(space, item[0], where)
        if action not in query.actions:
            raise FeedbackError(
                f"{where}: action {action} was not executed in this query "
                f"(executed: {', '.join(map(str, query.actions))})"
            )
        feature = item[1]
        if not isinstance(feature, str) or feature not in space.names:
            raise FeedbackError(
                f"{where}: unknown feature {feature!r}; features are {', '.join(space.names)}"
            )
        move = item[2]
        if move not in MOVES:
            raise FeedbackError(f"{where}: move must be one of {', '.join(MOVES)}; got {move!r}")
        return Suggestion(action, feature, move)

    def check_all(self, records: Sequence[Suggestion], query: QueryView) -> None:
        seen: set[tuple[int, str]] = set()
        for k, s in enumerate(records):
            if (s.action, s.feature) in seen:
                raise FeedbackError(
                    f"suggestion {k}: two suggestions for {s.feature} of action {s.action}"
                )
            seen.add((s.action, s.feature))

    def observations(
        self, record: Suggestion, context: ModelContext, query_id: int
    ) -> Observations:
        target = context.space.coactive_move(record.action, record.feature, record.move)
        if target is None:
            return Observations()  # clipped back to the same point: ignored
        noise = context.noise / context.coactive_weight
        return Observations(
            preferences=(Preference(target, record.action, noise, "coactive", query_id),)
        )

    def payload(self, record: Suggestion, query: TrialQuery, context: ModelContext) -> EventPayload:
        return SuggestionGiven(
            query=query.id,
            trial=query.trial_of(record.action),
            action=record.action,
            feature=record.feature,
            move=record.move,
            target=context.space.coactive_move(record.action, record.feature, record.move),
        )

    def from_payload(self, payload: EventPayload) -> Suggestion:
        assert isinstance(payload, SuggestionGiven)
        return Suggestion(payload.action, payload.feature, payload.move)


def clipped_note(space: Space, action: int, feature: str, move: str, trial: int) -> str | None:
    """What to tell the operator when the suggestion (``move`` of ``feature`` from ``action``,
    walked in ``trial``) asked to go past the edge of the feature's range and was clipped there:
    to the edge, or, at the edge already, back to the same gait (stored, but no term enters the
    model).  None when the move stays within the range.  Nothing stored changes: the suggestion
    is stored as given either way."""
    if move not in MOVES:
        raise ValueError(f"move must be one of {', '.join(MOVES)}; got {move!r}")
    number = space.feature_number(feature)
    f = space.features[number]
    value = float(space.point(action)[number])
    if not f.move_clipped(value, move):
        return None
    more, less = f.words
    word = {"+big": more, "+small": f"slightly {more}", "-small": f"slightly {less}"}.get(
        move, less
    )
    unit = f" {f.unit}" if f.unit else ""
    edge = f.values[-1] if move.startswith("+") else f.values[0]
    said = f"trial {trial}: {feature} {word} goes past the edge of its range ({edge:.4g}{unit})"
    if f.move_value(value, move) is None:
        return (
            f"{said}; the gait is at the edge already, so the suggestion is stored but does not "
            "enter the model"
        )
    return f"{said}; it is taken as a move to the edge"


__all__ = ["Suggestion", "SuggestionGiven", "SuggestionKind", "clipped_note"]
