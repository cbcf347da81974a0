"""A feedback kind registered outside the package is held to its terms: grid actions and a
positive noise (a preference on action -1 was fitted on the last gait, silently)."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import ClassVar

import pytest

from gaitpref import CoSpar, Feature, FeedbackError, Space, SquaredExponential
from gaitpref.feedback import (
    ExportTable,
    FeedbackKind,
    ModelContext,
    Observations,
    Preference,
    QueryView,
    TrialQuery,
    register,
    unregister,
)
from gaitpref.payloads import EventPayload


@dataclass(frozen=True)
class Nudge:
    """A faulty kind: "``winner`` beats ``loser``", its terms made as given."""

    winner: int
    loser: int
    noise: float = 0.1


class NudgeGiven(EventPayload):
    kind: ClassVar[str] = "nudge_given"
    version: ClassVar[int] = 1
    winner: int
    loser: int


class NudgeKind(FeedbackKind[Nudge]):
    name: ClassVar[str] = "nudge"
    record_type: ClassVar[type[Nudge]] = Nudge
    payload_type: ClassVar[type[EventPayload]] = NudgeGiven
    export: ClassVar[ExportTable] = ExportTable("nudges")

    def parse(self, raw: object, query: QueryView, context: ModelContext, where: str) -> Nudge:
        assert isinstance(raw, Nudge)
        return raw  # no check: the loop is what stops its terms

    def observations(self, record: Nudge, context: ModelContext, query_id: int) -> Observations:
        pref = Preference(record.winner, record.loser, record.noise, "comparison", query_id)
        return Observations(preferences=(pref,))

    def payload(self, record: Nudge, query: TrialQuery, context: ModelContext) -> EventPayload:
        return NudgeGiven(winner=record.winner, loser=record.loser)

    def from_payload(self, payload: EventPayload) -> Nudge:
        assert isinstance(payload, NudgeGiven)
        return Nudge(payload.winner, payload.loser)


@pytest.fixture
def nudges() -> Iterator[None]:
    register(NudgeKind())
    yield
    unregister("nudge")


@pytest.mark.usefixtures("nudges")
def test_terms_of_a_kind_are_checked() -> None:
    space = Space([Feature.linspace("x", 0, 1, 6)])
    loop = CoSpar(space, SquaredExponential(0.3, 1.0, 1e-6), 0.1)
    query = loop.ask()
    for record, message in (
        (Nudge(-1, 0), "kind 'nudge' made a term on -1, not an action"),
        (Nudge(0, 6), "kind 'nudge' made a term on 6, not an action"),
        (Nudge(0, 1, 0.0), "kind 'nudge' made a preference with noise 0.0"),
    ):
        with pytest.raises(FeedbackError, match=message):
            loop.tell(query, [record])
        assert not loop.answers and loop.pending is query
    assert loop.tell(query, [Nudge(5, 0)]).preferences[0].winner == 5
