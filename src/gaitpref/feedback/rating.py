"""An ordinal rating of an executed gait ("very bad" ... "good"), as ROIAL and POLAR ask.

After each trial the subject may rate the gait in one of the ``K`` categories of the loop's
:class:`~gaitpref.model.ordinal.Ordinal` scale (worst first; ``[feedback.rating]`` in a config).
A rating is a single-action term: the ordered probit ``P(k | f) = Phi((t_k - f) / s) -
Phi((t_{k-1} - f) / s)`` on the rated action's utility (``model/ordinal.py``).  Ratings are
optional (a trial may go unrated) and at most one per executed action of a query.  Stored as a
``rating_given`` event with the label's index (``1..K``) and, for readers, its category name.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated, ClassVar

from gaitpref.errors import FeedbackError
from gaitpref.feedback.base import (
    ActionObservation,
    ExportTable,
    FeedbackKind,
    ModelContext,
    Observations,
    QueryView,
    TrialQuery,
    expect_fields,
    grid_index,
)
from gaitpref.payloads import EventPayload, Recorded

if TYPE_CHECKING:
    from gaitpref.model.ordinal import OrdinalLikelihood


@dataclass(frozen=True)
class Rating:
    """Executed action ``action`` rated ``label``: a category name or its index ``1..K``."""

    action: int
    label: int | str


class RatingGiven(EventPayload):
    """``rating_given``: the rated trial and action, the label's index and its category."""

    kind: ClassVar[str] = "rating_given"
    version: ClassVar[int] = 1

    query: int
    trial: int
    action: int
    label: int
    category: Annotated[str, Recorded]


class RatingKind(FeedbackKind[Rating]):
    """Ordinal ratings of the actions executed in a query (needs the loop's rating scale)."""

    name: ClassVar[str] = "rating"
    record_type: ClassVar[type[Rating]] = Rating
    payload_type: ClassVar[type[EventPayload]] = RatingGiven
    export: ClassVar[ExportTable] = ExportTable(
        "ratings", ("query", "trial", "action", "label", "category")
    )

    def parse(self, raw: object, query: QueryView, context: ModelContext, where: str) -> Rating:
        if context.ordinal is None:
            raise FeedbackError(
                f"{where}: this loop takes no ratings (give the config a [feedback.rating] "
                "table with its labels)"
            )
        if isinstance(raw, Rating):
            raw = (raw.action, raw.label)
        action, label = expect_fields(raw, ("action", "label"), where, "(action, label)")
        a = grid_index(context.space, action, where)
        if a not in query.actions:
            raise FeedbackError(
                f"{where}: action {a} was not executed in this query "
                f"(executed: {', '.join(map(str, query.actions))})"
            )
        try:
            index = context.ordinal.label_index(label)
        except ValueError as exc:
            raise FeedbackError(f"{where}: {exc}") from None
        return Rating(a, index)

    def check_all(self, records: Sequence[Rating], query: QueryView) -> None:
        seen: set[int] = set()
        for k, r in enumerate(records):
            if r.action in seen:
                raise FeedbackError(f"rating {k}: action {r.action} is rated twice")
            seen.add(r.action)

    def observations(self, record: Rating, context: ModelContext, query_id: int) -> Observations:
        return Observations(
            singles=(ActionObservation(record.action, self.name, int(record.label), query_id),)
        )

    def action_likelihood(
        self, observations: Sequence[ActionObservation], context: ModelContext
    ) -> OrdinalLikelihood:
        from gaitpref.model.ordinal import rating_likelihood

        if context.ordinal is None:
            raise FeedbackError("ratings in the model need the loop's rating scale")
        labels = [int(o.value) for o in observations]  # type: ignore[call-overload]
        return rating_likelihood(context.ordinal, context.signal_variance, labels)

    def payload(self, record: Rating, query: TrialQuery, context: ModelContext) -> EventPayload:
        label = int(record.label)
        categories = context.ordinal.categories if context.ordinal is not None else ()
        return RatingGiven(
            query=query.id,
            trial=query.trial_of(record.action),
            action=record.action,
            label=label,
            category=categories[label - 1] if 0 < label <= len(categories) else "",
        )

    def from_payload(self, payload: EventPayload) -> Rating:
        assert isinstance(payload, RatingGiven)
        return Rating(payload.action, payload.label)


__all__ = ["Rating", "RatingGiven", "RatingKind"]
