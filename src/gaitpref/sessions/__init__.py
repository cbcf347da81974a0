"""Experiment sessions with real subjects: the one import surface of ``gaitpref.sessions``.

A session is a config, a subject and a seed in a database, plus an append-only log of typed,
versioned events (``events.py``).  Its state is never stored: it is rebuilt by replaying the log
(``state.py``, ``replay.py``), and replay re-derives every proposal and checks it against the log.

- :class:`Session` (``session.py``): create, open, next query, answer, undo, exclude, validate.
- records (``records.py``): :class:`SessionQuery`, :class:`Trial`, :class:`ComparisonRecord`,
  :class:`SuggestionRecord`, :class:`Answered`, :class:`ShownGait` (a validation gait as shown),
  :class:`ValidationRound` (a blind validation round: who opened it, what became of it).
- warm starts from earlier sessions (``warm.py``; :func:`read_prior_from` reads typed ids
  and subject codes), the confidence after every answer and the recommended gait
  (``confidence.py``; :class:`StopCheckWarning` when the ``[stop]`` rule could not be checked
  after a stored answer);
- blind validation (``validation.py``), export and import (``export.py``), the stored config
  (``stored_config.py``) and the simulated demo subject (``demo.py``).
"""

from gaitpref.errors import ExportError, ReplayError, SessionError, SessionStateError
from gaitpref.loop.stopping import preference_learned
from gaitpref.sessions.confidence import StopCheckWarning
from gaitpref.sessions.export import export_session, import_session, posterior_summary
from gaitpref.sessions.records import (
    REASONS,
    Answered,
    ComparisonRecord,
    FeedbackEntry,
    InfeasibleGait,
    Reason,
    SessionQuery,
    ShownGait,
    SuggestionRecord,
    Trial,
    ValidationRound,
)
from gaitpref.sessions.session import Session
from gaitpref.sessions.stored_config import GaitLibraryLike, software_version
from gaitpref.sessions.validation import ValidationPlan, ValidationResult
from gaitpref.sessions.warm import read_prior_from

__all__ = [
    "REASONS",
    "Answered",
    "ComparisonRecord",
    "ExportError",
    "FeedbackEntry",
    "GaitLibraryLike",
    "InfeasibleGait",
    "Reason",
    "ReplayError",
    "Session",
    "SessionError",
    "SessionQuery",
    "SessionStateError",
    "ShownGait",
    "StopCheckWarning",
    "SuggestionRecord",
    "Trial",
    "ValidationPlan",
    "ValidationResult",
    "ValidationRound",
    "export_session",
    "import_session",
    "posterior_summary",
    "preference_learned",
    "read_prior_from",
    "software_version",
]
