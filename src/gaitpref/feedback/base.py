"""What a kind of answer is: a record type, a check against its query, likelihood terms, an event
payload and export columns (:class:`FeedbackKind`).

The model takes likelihood terms of two shapes (``model/laplace.py``):

- on a pair of actions: :class:`Preference` (``winner > loser``, probit noise, Chu & Ghahramani
  2005 eq. (3) as the paper uses it) and :class:`Tie` (a "no preference", modelled only with
  ``ties = "model"``);
- on a single action: :class:`ActionObservation` (an observation of one utility ``f_s``; its
  kind turns a batch of them into an :class:`~gaitpref.model.likelihood.ActionLikelihood`).

A kind's :meth:`FeedbackKind.observations` gives a record's terms; the loop fits them all in one
Laplace fit.  A session stores each record as one event (:meth:`FeedbackKind.payload`, a typed,
versioned :class:`~gaitpref.payloads.EventPayload`) and rebuilds it on replay
(:meth:`FeedbackKind.from_payload`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Hashable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Generic, Literal, Protocol, TypeVar

from gaitpref.errors import FeedbackError
from gaitpref.payloads import EventPayload
from gaitpref.space import Space

if TYPE_CHECKING:  # the model's numerics load only when a loop fits
    from gaitpref.model.likelihood import ActionLikelihood
    from gaitpref.model.ordinal import Ordinal

Source = Literal["comparison", "coactive"]


@dataclass(frozen=True)
class Preference:
    """One pair term: ``winner > loser`` with probit noise ``noise``."""

    winner: int
    loser: int
    noise: float
    source: Source
    query_id: int


@dataclass(frozen=True)
class Tie:
    """A "no preference" pair term: stored; modelled only with ``ties = "model"``."""

    first: int
    second: int
    query_id: int


@dataclass(frozen=True)
class ActionObservation:
    """One single-action term: an observation of ``f[action]`` by feedback kind ``kind``.

    ``value`` is what the kind needs to build its likelihood (a rating's label, a measured
    value, ...), hashable and JSON-like.
    """

    action: int
    kind: str
    value: Hashable
    query_id: int


@dataclass(frozen=True)
class Observations:
    """The likelihood terms of one record (any of them may be empty)."""

    preferences: tuple[Preference, ...] = ()
    ties: tuple[Tie, ...] = ()
    singles: tuple[ActionObservation, ...] = ()

    @property
    def empty(self) -> bool:
        return not (self.preferences or self.ties or self.singles)


@dataclass(frozen=True)
class ModelContext:
    """What a kind needs of the loop to check its records and make its terms."""

    space: Space
    noise: float  # the probit noise of a comparison (sigma)
    coactive_weight: float = 1.0  # suggestions have noise sigma / coactive_weight
    ordinal: Ordinal | None = None  # the rating scale, when the loop takes ratings
    signal_variance: float = 1.0  # the kernel's, for thresholds set from the prior


class QueryView(Protocol):
    """What a kind checks an answer against: the query's executed and buffered actions."""

    @property
    def id(self) -> int: ...

    @property
    def actions(self) -> tuple[int, ...]: ...

    @property
    def buffer(self) -> tuple[int, ...]: ...

    @property
    def members(self) -> tuple[int, ...]: ...


class TrialQuery(QueryView, Protocol):
    """A query as a session issued it: each member action has a trial number."""

    def trial_of(self, action: int) -> int: ...


R = TypeVar("R", bound=Hashable)


@dataclass(frozen=True)
class ExportTable:
    """Where a kind's records go in a session export: a table name and the payload fields it
    shows, in order (empty: every field)."""

    name: str
    columns: tuple[str, ...] = field(default=())


class FeedbackKind(ABC, Generic[R]):
    """A kind of answer.  Subclass it, set the class attributes, and :func:`register` it.

    Only :meth:`parse`, :meth:`observations`, :meth:`payload` and :meth:`from_payload` must be
    written; :meth:`check_all` (checks across one answer's records) and
    :meth:`action_likelihood` (kinds with single-action terms) have defaults.
    """

    name: ClassVar[str]  # e.g. "comparison": how callers and configs name the kind
    record_type: ClassVar[type[Any]]  # the record class (frozen, hashable)
    payload_type: ClassVar[type[EventPayload]]  # its event payload class (kind, version)
    export: ClassVar[ExportTable]  # its table in exports

    @abstractmethod
    def parse(self, raw: object, query: QueryView, context: ModelContext, where: str) -> R:
        """One record from a record or raw input, checked against ``query`` (and the loop's
        ``context``: its space, rating scale, ...).

        Raises :class:`~gaitpref.errors.FeedbackError` naming ``where`` and the problem.
        """

    def check_all(self, records: Sequence[R], query: QueryView) -> None:
        """Checks across one answer's records of this kind (duplicates, ...); default none."""

    @abstractmethod
    def observations(self, record: R, context: ModelContext, query_id: int) -> Observations:
        """The likelihood terms of ``record`` (none: stored, not modelled)."""

    def action_likelihood(
        self, observations: Sequence[ActionObservation], context: ModelContext
    ) -> ActionLikelihood:
        """The likelihood of this kind's single-action terms, one entry per observation."""
        raise NotImplementedError(f"feedback kind {self.name!r} makes no single-action terms")

    @abstractmethod
    def payload(self, record: R, query: TrialQuery, context: ModelContext) -> EventPayload:
        """The event payload that stores ``record`` (answering ``query``, told to a loop whose
        ``context`` this is)."""

    @abstractmethod
    def from_payload(self, payload: EventPayload) -> R:
        """The record a stored payload holds (replay tells it to the loop again)."""

    def export_row(self, payload: EventPayload) -> dict[str, Any]:
        """One row of the export table; default: the payload's fields named by
        ``export.columns`` (every field when it names none)."""
        data = payload.to_json()
        columns = self.export.columns
        return {c: data[c] for c in columns} if columns else data

    @property
    def event_kind(self) -> str:
        return self.payload_type.kind


def expect_fields(
    raw: object, fields: tuple[str, ...], where: str, shape: str = ""
) -> tuple[Any, ...]:
    """``raw`` as a tuple of ``len(fields)`` values: from a sequence of that length or a mapping
    with exactly those keys.  ``shape`` is how errors show the expected form."""
    shape = shape or f"({', '.join(fields)})"
    if isinstance(raw, dict):
        if set(raw) != set(fields):
            raise FeedbackError(
                f"{where}: expected the keys {', '.join(fields)}; got {', '.join(map(str, raw))}"
            )
        return tuple(raw[f] for f in fields)
    if isinstance(raw, Sequence) and not isinstance(raw, str | bytes):
        if len(raw) != len(fields):
            raise FeedbackError(f"{where}: expected {shape}, got {raw!r}")
        return tuple(raw)
    raise FeedbackError(f"{where}: expected {shape}, got {raw!r}")


def grid_index(space: Space, value: object, where: str) -> int:
    """``value`` as a grid index of ``space``, or a :class:`FeedbackError` naming ``where``."""
    try:
        return space.check_index(value)
    except (TypeError, IndexError) as exc:
        raise FeedbackError(f"{where}: {exc}") from None


__all__ = [
    "ActionObservation",
    "ExportTable",
    "FeedbackKind",
    "ModelContext",
    "Observations",
    "Preference",
    "QueryView",
    "Source",
    "Tie",
    "TrialQuery",
    "expect_fields",
    "grid_index",
]
