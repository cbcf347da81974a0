"""A coactive suggestion: "executed action ``a`` would be better with ``feature`` moved".

The paper's coactive feedback: the move ``a -> a~`` (a fraction of the feature's range,
``space.coactive_move``) enters the model as a preference ``a~ > a`` with probit noise
``sigma / beta`` (``beta``: the coactive weight); a move that clips back to ``a`` is stored and
ignored.  Stored as a ``suggestion_given`` event, with its target action.
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
from gaitpref.space import MOVES, Move


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


__all__ = ["Suggestion", "SuggestionGiven", "SuggestionKind"]
