"""Kinds of answers behind one interface: comparisons with ties, coactive suggestions, ordinal
ratings, and any kind registered from outside.

A kind (:class:`FeedbackKind`, ``base.py``) is a record type, a check against its query, the
likelihood terms it adds to the model (on a pair of actions or on a single action), a typed
event payload and an export table.  ``comparison.py`` and ``suggestion.py`` are the paper's two
kinds (Algorithm 1's matrix ``R`` and its coactive feedback), ``rating.py`` ROIAL's ordinal
ratings; :func:`register` adds more.

    loop.tell(query, [Comparison(a, b, "first"), Suggestion(a, "step_length", "+small")])
"""

from gaitpref.errors import FeedbackError
from gaitpref.feedback.base import (
    ActionObservation,
    ExportTable,
    FeedbackKind,
    ModelContext,
    Observations,
    Preference,
    QueryView,
    Source,
    Tie,
    TrialQuery,
    expect_fields,
    grid_index,
)
from gaitpref.feedback.comparison import (
    OUTCOMES,
    Comparison,
    ComparisonAnswered,
    ComparisonKind,
    Outcome,
    QueryPair,
    compared_actions,
    comparison_pairs,
)
from gaitpref.feedback.rating import Rating, RatingGiven, RatingKind
from gaitpref.feedback.registry import (
    kind_for_event,
    kind_named,
    kind_of,
    kinds,
    register,
    unregister,
)
from gaitpref.feedback.suggestion import Suggestion, SuggestionGiven, SuggestionKind

register(ComparisonKind())
register(SuggestionKind())
register(RatingKind())

__all__ = [
    "OUTCOMES",
    "ActionObservation",
    "Comparison",
    "ComparisonAnswered",
    "ComparisonKind",
    "ExportTable",
    "FeedbackError",
    "FeedbackKind",
    "ModelContext",
    "Observations",
    "Outcome",
    "Preference",
    "QueryPair",
    "QueryView",
    "Rating",
    "RatingGiven",
    "RatingKind",
    "Source",
    "Suggestion",
    "SuggestionGiven",
    "SuggestionKind",
    "Tie",
    "TrialQuery",
    "compared_actions",
    "comparison_pairs",
    "expect_fields",
    "grid_index",
    "kind_for_event",
    "kind_named",
    "kind_of",
    "kinds",
    "register",
    "unregister",
]
