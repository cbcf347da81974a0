"""Feedback records, and the one place user input is checked.

The paper's Algorithm 1 collects, per iteration, a matrix ``R`` of pairwise answers between the
``n`` new actions and the ``b`` buffered ones ("row preferred", "column preferred" or "no
preference") and one optional coactive suggestion per executed action.  Here an answer is a list of
:class:`Comparison` and :class:`Suggestion` records; :class:`Preference` is what enters the model
(``winner > loser`` with a probit noise) and :class:`Tie` a stored "no preference".
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import astuple, dataclass
from typing import Any, Literal, get_args

from gaitpref.errors import FeedbackError
from gaitpref.space import MOVES, Move, Space

Outcome = Literal["first", "second", "none"]
OUTCOMES: tuple[Outcome, ...] = get_args(Outcome)
Source = Literal["comparison", "coactive"]


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
class Suggestion:
    """ "Executed action ``action`` would be better with ``feature`` moved by ``move``"."""

    action: int
    feature: str
    move: Move


@dataclass(frozen=True)
class Preference:
    """One datum of the likelihood: ``winner > loser`` with probit noise ``noise``."""

    winner: int
    loser: int
    noise: float
    source: Source
    query_id: int


@dataclass(frozen=True)
class Tie:
    """A "no preference" answer: stored, not in the paper's likelihood."""

    first: int
    second: int
    query_id: int


def _grid_index(space: Space, value: object, where: str) -> int:
    try:
        return space.check_index(value)
    except (TypeError, IndexError) as exc:
        raise FeedbackError(f"{where}: {exc}") from None


def _triple(
    item: object, record: type[Comparison | Suggestion], where: str, expected: str
) -> Sequence[Any]:
    """A record or a 3-sequence as a 3-sequence; anything else is a :class:`FeedbackError`."""
    if isinstance(item, Comparison | Suggestion):
        if not isinstance(item, record):
            raise FeedbackError(f"{where}: expected {expected}, got {item!r}")
        return tuple(astuple(item))
    if not isinstance(item, Sequence) or isinstance(item, str) or len(item) != 3:
        raise FeedbackError(f"{where}: expected {expected}, got {item!r}")
    return item


def parse_comparisons(
    space: Space, raw: Iterable[object], members: Sequence[int], executed: Sequence[int]
) -> tuple[Comparison, ...]:
    """Check ``(i, j, outcome)`` triples against a query's ``members`` (executed + buffered).

    Each pair must include at least one action executed in this query (the rows of the paper's
    ``R``) and may appear once.
    """
    out: list[Comparison] = []
    seen: set[frozenset[int]] = set()
    for k, raw_item in enumerate(raw):
        where = f"comparison {k}"
        item = _triple(raw_item, Comparison, where, "(i, j, outcome)")
        i = _grid_index(space, item[0], where)
        j = _grid_index(space, item[1], where)
        outcome = item[2]
        if outcome not in OUTCOMES:
            raise FeedbackError(
                f"{where}: outcome must be one of {', '.join(OUTCOMES)}; got {outcome!r}"
            )
        for a in (i, j):
            if a not in members:
                raise FeedbackError(
                    f"{where}: action {a} is not in this query (its actions are "
                    f"{', '.join(map(str, members))})"
                )
        if i not in executed and j not in executed:
            raise FeedbackError(f"{where}: neither {i} nor {j} was executed in this query")
        pair = frozenset((i, j))
        if pair in seen and i != j:
            raise FeedbackError(f"{where}: the pair ({i}, {j}) is compared twice")
        seen.add(pair)
        out.append(Comparison(i, j, outcome))
    return tuple(out)


def parse_suggestions(
    space: Space, raw: Iterable[object], executed: Sequence[int]
) -> tuple[Suggestion, ...]:
    """Check ``(action, feature, move)`` triples; ``action`` must be executed in this query."""
    out: list[Suggestion] = []
    seen: set[tuple[int, str]] = set()
    for k, raw_item in enumerate(raw):
        where = f"suggestion {k}"
        item = _triple(raw_item, Suggestion, where, "(action, feature, move)")
        action = _grid_index(space, item[0], where)
        if action not in executed:
            raise FeedbackError(
                f"{where}: action {action} was not executed in this query "
                f"(executed: {', '.join(map(str, executed))})"
            )
        feature = item[1]
        if not isinstance(feature, str) or feature not in space.names:
            raise FeedbackError(
                f"{where}: unknown feature {feature!r}; features are {', '.join(space.names)}"
            )
        move = item[2]
        if move not in MOVES:
            raise FeedbackError(f"{where}: move must be one of {', '.join(MOVES)}; got {move!r}")
        if (action, feature) in seen:
            raise FeedbackError(f"{where}: two suggestions for {feature} of action {action}")
        seen.add((action, feature))
        out.append(Suggestion(action, feature, move))
    return tuple(out)
