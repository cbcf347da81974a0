"""A comparison of two actions of a query, with ties: "first", "second" or "no preference".

The paper's matrix ``R`` (Algorithm 1): each answer compares an action executed in this query
with another member (executed or buffered).  A preference enters the model as the probit term
``P(w > l) = Phi((f_w - f_l) / (sqrt(2) sigma))`` (Chu & Ghahramani 2005, eq. (3)); a "no
preference" is a :class:`~gaitpref.feedback.base.Tie` (stored; modelled with ``ties = "model"``).
Stored as a ``comparison_answered`` event.

:func:`comparison_pairs` is the one rule for which pairs a query asks (the terminal, the
console and the simulated users all follow it): every executed action against every later
member, a pair of two trials of one gait not asked (nothing to compare), a pair of gaits asked
once (``check_all`` refuses it twice).  A comparison of a gait with itself is still taken (an
earlier console asked it, and its logs replay as they were): stored, not modelled.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Annotated, ClassVar, Literal, get_args

from gaitpref.errors import FeedbackError
from gaitpref.feedback.base import (
    ExportTable,
    FeedbackKind,
    ModelContext,
    Observations,
    Preference,
    QueryView,
    Tie,
    TrialQuery,
    expect_fields,
    grid_index,
)
from gaitpref.payloads import EventPayload, Recorded

Outcome = Literal["first", "second", "none"]
OUTCOMES: tuple[Outcome, ...] = get_args(Outcome)


@dataclass(frozen=True)
class Comparison:
    """The user compared actions ``first`` and ``second`` (grid indices) with ``outcome``."""

    first: int
    second: int
    outcome: Outcome

    @property
    def is_tie(self) -> bool:
        return self.outcome == "none"

    def as_preference(self) -> tuple[int, int] | None:
        """``(winner, loser)``, or None for "no preference" or a self-comparison."""
        if self.outcome == "none" or self.first == self.second:
            return None
        if self.outcome == "first":
            return self.first, self.second
        return self.second, self.first


@dataclass(frozen=True)
class QueryPair:
    """Two members of a query by their positions in its members (executed actions, then
    buffered ones): ``first`` executed, ``second`` after it.  Not :attr:`asked` when both are
    one gait (:attr:`same_gait`) or when the same two gaits were asked earlier in the query
    (:attr:`repeats`: that pair's positions)."""

    first: int
    second: int
    same_gait: bool = False
    repeats: tuple[int, int] | None = None

    @property
    def asked(self) -> bool:
        return not self.same_gait and self.repeats is None


def comparison_pairs(actions: Sequence[int], buffer: Sequence[int]) -> tuple[QueryPair, ...]:
    """Every pair of a query's members with an executed one first, in the order they are asked:
    each executed action (``actions``, in order) against each member after it (the later
    executed ones, then ``buffer``); those that are not asked are kept, marked why.

    The paper's ``R`` (``n (n - 1) / 2 + n b`` pairs) when the query's gaits are distinct, as
    in its ``n = 1, b = 1`` runs whenever the new gait is not the buffered one.
    """
    members = (*actions, *buffer)
    out: list[QueryPair] = []
    asked: dict[frozenset[int], tuple[int, int]] = {}
    for r in range(len(actions)):
        for c in range(r + 1, len(members)):
            key = frozenset((members[r], members[c]))
            if len(key) == 1:
                out.append(QueryPair(r, c, same_gait=True))
            elif key in asked:
                out.append(QueryPair(r, c, repeats=asked[key]))
            else:
                asked[key] = (r, c)
                out.append(QueryPair(r, c))
    return tuple(out)


def compared_actions(actions: Sequence[int], buffer: Sequence[int]) -> tuple[tuple[int, int], ...]:
    """The pairs of actions :func:`comparison_pairs` asks, ``(executed, other)``."""
    members = (*actions, *buffer)
    pairs = comparison_pairs(actions, buffer)
    return tuple((members[p.first], members[p.second]) for p in pairs if p.asked)


class ComparisonAnswered(EventPayload):
    """``comparison_answered``: the comparison and the trial numbers of its two actions."""

    kind: ClassVar[str] = "comparison_answered"
    version: ClassVar[int] = 1

    query: int
    first: int
    second: int
    outcome: Outcome
    first_trial: Annotated[int, Recorded]
    second_trial: Annotated[int, Recorded]


class ComparisonKind(FeedbackKind[Comparison]):
    """Comparisons between a query's members (at least one of the two executed in it)."""

    name: ClassVar[str] = "comparison"
    record_type: ClassVar[type[Comparison]] = Comparison
    payload_type: ClassVar[type[EventPayload]] = ComparisonAnswered
    export: ClassVar[ExportTable] = ExportTable(
        "comparisons",
        ("query", "first_trial", "second_trial", "first", "second", "outcome"),
    )

    def parse(self, raw: object, query: QueryView, context: ModelContext, where: str) -> Comparison:
        space = context.space
        if isinstance(raw, Comparison):
            raw = (raw.first, raw.second, raw.outcome)
        item = expect_fields(raw, ("first", "second", "outcome"), where, "(i, j, outcome)")
        i = grid_index(space, item[0], where)
        j = grid_index(space, item[1], where)
        outcome = item[2]
        if outcome not in OUTCOMES:
            raise FeedbackError(
                f"{where}: outcome must be one of {', '.join(OUTCOMES)}; got {outcome!r}"
            )
        members = query.members
        for a in (i, j):
            if a not in members:
                raise FeedbackError(
                    f"{where}: action {a} is not in this query (its actions are "
                    f"{', '.join(map(str, members))})"
                )
        if i not in query.actions and j not in query.actions:
            raise FeedbackError(f"{where}: neither {i} nor {j} was executed in this query")
        return Comparison(i, j, outcome)

    def check_all(self, records: Sequence[Comparison], query: QueryView) -> None:
        seen: set[frozenset[int]] = set()
        for k, c in enumerate(records):
            pair = frozenset((c.first, c.second))
            if pair in seen and c.first != c.second:
                raise FeedbackError(
                    f"comparison {k}: the pair ({c.first}, {c.second}) is compared twice"
                )
            seen.add(pair)

    def observations(
        self, record: Comparison, context: ModelContext, query_id: int
    ) -> Observations:
        pair = record.as_preference()
        if pair is not None:
            return Observations(
                preferences=(Preference(pair[0], pair[1], context.noise, "comparison", query_id),)
            )
        if record.is_tie and record.first != record.second:
            return Observations(ties=(Tie(record.first, record.second, query_id),))
        return Observations()

    def payload(self, record: Comparison, query: TrialQuery, context: ModelContext) -> EventPayload:
        return ComparisonAnswered(
            query=query.id,
            first=record.first,
            second=record.second,
            outcome=record.outcome,
            first_trial=query.trial_of(record.first),
            second_trial=query.trial_of(record.second),
        )

    def from_payload(self, payload: EventPayload) -> Comparison:
        assert isinstance(payload, ComparisonAnswered)
        return Comparison(payload.first, payload.second, payload.outcome)


__all__ = ["OUTCOMES", "Comparison", "ComparisonAnswered", "ComparisonKind", "Outcome"]
