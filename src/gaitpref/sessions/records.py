"""The records a session shows: its queries, trials and answers as they were given, with what
became of them (undone, excluded).  The events they are read from are in ``events.py``."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal, get_args

from gaitpref.checks import char_name, hidden_in
from gaitpref.feedback import QueryPair, compared_actions, comparison_pairs

Reason = Literal["device_fault", "stumble", "distracted", "other"]
REASONS: tuple[Reason, ...] = get_args(Reason)


@dataclass(frozen=True)
class SessionQuery:
    """A query as a session issues it: run ``actions`` (trials ``trials``), compare with
    ``buffer`` (trials ``buffer_trials``).  ``id`` is unique in the session."""

    id: int
    loop_id: int
    actions: tuple[int, ...]
    buffer: tuple[int, ...]
    trials: tuple[int, ...]
    buffer_trials: tuple[int, ...]
    #: the actions' feature values (features' units), one row per action: the point a gait
    #: generator makes a gait for
    points: tuple[tuple[float, ...], ...] = field(default=(), compare=False)

    @property
    def members(self) -> tuple[int, ...]:
        """Every action a comparison may name: executed, then buffered."""
        return self.actions + self.buffer

    @property
    def member_trials(self) -> tuple[int, ...]:
        return self.trials + self.buffer_trials

    @property
    def pairs(self) -> tuple[QueryPair, ...]:
        """The pairs of members it asks to compare, and those it does not (and why), by
        position in :attr:`members` and :attr:`member_trials`:
        :func:`~gaitpref.feedback.comparison_pairs`."""
        return comparison_pairs(self.actions, self.buffer)

    @property
    def compared(self) -> tuple[tuple[int, int], ...]:
        """The pairs of actions it asks to compare, ``(executed, other)``, in order."""
        return compared_actions(self.actions, self.buffer)

    def trial_of(self, action: int) -> int:
        """The trial number of ``action`` in this query (the first, if it appears twice)."""
        return self.member_trials[self.members.index(action)]


@dataclass(frozen=True)
class InfeasibleGait:
    """A proposal whose gait could not be made (event ``seq``): never shown as a trial.

    ``values``: the proposed point's feature values.  On the line path ``action`` is the row
    the point had in the point table when it was proposed; the proposal is withdrawn and its
    rows are given to the points proposed next, so the row names another point later: look the
    proposal up by ``values`` or ``gait_id``, never by ``action``.  (On a grid an action is a
    grid point, so both agree.)
    """

    seq: int
    action: int
    gait_id: str
    reason: str
    values: dict[str, float] = field(default_factory=dict, compare=False)


@dataclass(frozen=True)
class ShownGait:
    """A blind validation gait as its round showed it: ``label`` (``A``, ``B``, ``C``), the row
    ``action`` it had when the round started, its name ``gait`` (library or generator id, or
    ``G<action>``), its feature values and their text (``Space.describe``).

    A round keeps what it showed: on the line path an unsafe flag that withdraws the pending
    query gives that query's rows to the points proposed next, so a round's row may later name
    another point, or none (``loop/line.py``).  (On a grid a row is a grid point: both agree.)
    """

    label: str
    action: int
    gait: str
    values: dict[str, float]
    text: str


@dataclass(frozen=True)
class Trial:
    """An executed trial.  ``undone``: its answer was taken back (the number is reused)."""

    number: int
    query: int
    action: int
    seq: int
    excluded: Reason | None = None
    exclusion_detail: str = ""
    undone: bool = False


@dataclass(frozen=True)
class ComparisonRecord:
    """A comparison as answered, with what became of it."""

    seq: int
    query: int
    first: int
    second: int
    outcome: str
    first_trial: int
    second_trial: int
    undone: bool = False
    excluded: bool = False

    @property
    def tie(self) -> bool:
        return self.outcome == "none"


@dataclass(frozen=True)
class SuggestionRecord:
    """A coactive suggestion as given; ``target`` is None when the move clipped back."""

    seq: int
    query: int
    trial: int
    action: int
    feature: str
    move: str
    target: int | None
    undone: bool = False
    excluded: bool = False


@dataclass(frozen=True)
class FeedbackEntry:
    """An answer of a kind other than comparison and suggestion (``gaitpref.feedback``), as
    stored: its kind, its event payload, and what became of it."""

    seq: int
    query: int
    kind: str
    payload: dict[str, Any]
    undone: bool = False
    excluded: bool = False


@dataclass(frozen=True)
class Answered:
    """What :meth:`gaitpref.Session.answer` wrote."""

    query: int
    trials: tuple[int, ...]
    seqs: tuple[int, ...]
    preferences: int  # how many pair terms (preferences) entered the model
    singles: int = 0  # how many single-action terms entered it
    #: the answer is stored, but the ``[stop]`` rule could not be checked after it: why
    #: (also issued as a :class:`~gaitpref.sessions.confidence.StopCheckWarning`); None when it was
    stop_warning: str | None = None
    #: suggestions that asked to go past the edge of a feature's range, clipped there (stored
    #: as given): one sentence each for the operator
    #: (:func:`~gaitpref.feedback.suggestion.clipped_note`)
    clipped: tuple[str, ...] = ()
    #: the ``[stop]`` rule's reason when the check after this answer opened blind validation
    #: (``"30 trials reached max_trials = 30"``, or the confidence sentence), so that the
    #: operator is told why a round opens; None when it did not
    stopped: str | None = None


def check_storable(text: str, what: str) -> str:
    """``text`` unless it holds a lone surrogate (what a terminal's undecodable bytes become),
    which no database or export can write as UTF-8: a ValueError naming ``what``."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise ValueError(
            f"{what} is not valid text: character {exc.start} is not Unicode (an undecodable "
            "byte?); nothing was written"
        ) from None
    return text


def check_printable(text: str, what: str) -> str:
    """``text`` unless it holds a character a terminal would act on or that reorders what is
    shown around it (:func:`~gaitpref.checks.hidden_in`: ESC, NUL, a carriage return, a line
    separator, a bidirectional override, ...; newlines and tabs pass): a ValueError naming
    ``what``.  For a *new* note, reason or detail only: events stored with one replay."""
    hidden = hidden_in(text)
    if hidden:
        at, char = hidden[0]
        raise ValueError(
            f"{what} holds {char_name(char)} at character {at + 1}: a control character other "
            "than a newline or a tab, a line separator or a bidirectional override, which "
            "terminals and exports would show as it is; nothing was written"
        )
    return text


#: the longest reason an unsafe flag takes (the terminal, the CLI and the API alike)
MAX_UNSAFE_REASON = 2000


def check_unsafe_reason(reason: str) -> str:
    """``reason`` if an unsafe flag may hold it: a text of 1 to :data:`MAX_UNSAFE_REASON`
    characters that a database can store; a ValueError saying which rule it breaks."""
    if not isinstance(reason, str) or not reason.strip() or len(reason) > MAX_UNSAFE_REASON:
        raise ValueError(
            f"an unsafe flag needs a reason: a text of 1 to {MAX_UNSAFE_REASON} characters"
        )
    return check_storable(reason, "the unsafe flag's reason")


#: the longest reason a withdrawn validation round takes (the terminal, the CLI and the API)
MAX_WITHDRAW_REASON = 2000


def check_withdraw_reason(reason: str) -> str:
    """``reason`` if a withdrawn validation round may hold it: a text of 1 to
    :data:`MAX_WITHDRAW_REASON` characters that a database can store and a terminal shows as
    it is; a ValueError saying which rule it breaks."""
    what = "the withdrawn round's reason"
    if not isinstance(reason, str) or not reason.strip() or len(reason) > MAX_WITHDRAW_REASON:
        raise ValueError(
            f"withdrawing a validation round needs a reason: a text of 1 to "
            f"{MAX_WITHDRAW_REASON} characters"
        )
    return check_printable(check_storable(reason, what), what)


@dataclass(frozen=True)
class ValidationRound:
    """A blind validation round as the log has it: its number, the seq of its
    ``validation_started``, who opened it (``"rule"``, ``"operator"``; None: logged before
    that was recorded), the query whose answer made the ``[stop]`` rule open it (None: not the
    rule's), and what became of it: ``answered``, or ``withdrawn`` (the reason) at
    ``withdrawn_seq``; an open round is neither."""

    round: int
    seq: int
    opened_by: Literal["rule", "operator"] | None
    opened_after: int | None
    answered: bool = False
    withdrawn: str | None = None
    withdrawn_seq: int | None = None

    @property
    def open(self) -> bool:
        return not self.answered and self.withdrawn is None
