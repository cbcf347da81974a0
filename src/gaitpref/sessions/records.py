"""Session events and the records a session shows: what each event kind means.

A session's log is a sequence of events (``storage/base.py``); this module fixes their kinds and
payloads.  Each answer is one batch: the ``trial_executed`` events of the query's actions, then its
``comparison_answered`` and ``suggestion_given`` events and, when the answer triggered a
hyperparameter fit (``[model] fit = "evidence"``), its ``hyperparameters_refit`` event, all
carrying the query's id.

========================  ================================================================
kind                      payload
========================  ================================================================
``created``               config_name, config_sha256, seed, software_version, subject
``query_issued``          query_loop_id, actions, buffer, trials, buffer_trials
``trial_executed``        query, trial, action, values (feature -> value), gait_id
``comparison_answered``   query, first, second, outcome, first_trial, second_trial
``suggestion_given``      query, trial, action, feature, move, target (null: clipped)
``hyperparameters_refit`` query, before, after, accepted, converged, message, evaluations, ...
``undo``                  query, trials
``trial_excluded``        trial, query, action, reason, detail
``validation_started``    round, gaits [{label, action, role, posterior_mean}]
``validation_answered``   round, ranking, model_ranking, agrees, kendall_tau
``note``                  text
``paused`` ``resumed``    (nothing)
``finished``              (nothing)
========================  ================================================================

A query's ``id`` is the sequence number of its ``query_issued`` event: unique in the session and
never reused, so an answer to a query that is no longer pending is recognised as stale.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

CREATED = "created"
QUERY = "query_issued"
TRIAL = "trial_executed"
COMPARISON = "comparison_answered"
SUGGESTION = "suggestion_given"
REFIT = "hyperparameters_refit"
UNDO = "undo"
EXCLUDED = "trial_excluded"
VALIDATION_STARTED = "validation_started"
VALIDATION_ANSWERED = "validation_answered"
NOTE = "note"
PAUSED = "paused"
RESUMED = "resumed"
FINISHED = "finished"

ANSWER_KINDS = (TRIAL, COMPARISON, SUGGESTION, REFIT)
KINDS = (
    CREATED,
    QUERY,
    *ANSWER_KINDS,
    UNDO,
    EXCLUDED,
    VALIDATION_STARTED,
    VALIDATION_ANSWERED,
    NOTE,
    PAUSED,
    RESUMED,
    FINISHED,
)

#: the fields replay re-derives and compares with the log, per kind
CHECKED_FIELDS: dict[str, tuple[str, ...]] = {
    QUERY: ("query_loop_id", "actions", "buffer", "trials", "buffer_trials"),
    TRIAL: ("query", "trial", "action"),
    COMPARISON: ("query", "first", "second", "outcome"),
    SUGGESTION: ("query", "trial", "action", "feature", "move", "target"),
    REFIT: ("query", "before", "after", "accepted"),
    UNDO: ("query", "trials"),
    EXCLUDED: ("trial", "query", "action", "reason"),
    VALIDATION_STARTED: ("round", "gaits"),
    VALIDATION_ANSWERED: ("round", "ranking", "model_ranking", "agrees", "kendall_tau"),
}

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

    @property
    def members(self) -> tuple[int, ...]:
        """Every action a comparison may name: executed, then buffered."""
        return self.actions + self.buffer

    @property
    def member_trials(self) -> tuple[int, ...]:
        return self.trials + self.buffer_trials

    def trial_of(self, action: int) -> int:
        """The trial number of ``action`` in this query (the first, if it appears twice)."""
        return self.member_trials[self.members.index(action)]


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
class Answered:
    """What :meth:`gaitpref.Session.answer` wrote."""

    query: int
    trials: tuple[int, ...]
    seqs: tuple[int, ...]
    preferences: int  # how many preferences entered the model


def describe_mismatch(
    seq: int, kind: str, logged: dict[str, object], derived: dict[str, object]
) -> str:
    """One line per field that differs between the log and what replay re-derived."""
    fields = CHECKED_FIELDS.get(kind, tuple(sorted(set(logged) | set(derived))))
    lines = [
        f"  {name}: log has {logged.get(name)!r}, replay gives {derived.get(name)!r}"
        for name in fields
        if logged.get(name) != derived.get(name)
    ]
    return f"event {seq} ({kind}):\n" + "\n".join(lines)
