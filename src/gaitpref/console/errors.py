"""The one place where errors of the session API become HTTP statuses.

==========================================  ======  =========================================
error                                       status  meaning
==========================================  ======  =========================================
``FormUnreadableError`` (console)           400     a page's form that is not a form
                                                    (multipart without its boundary, ...)
``CsrfError`` (console)                     403     a form without a valid CSRF token
``FormTooLargeError`` (console)             413     a page's form past a limit of
                                                    ``limits.py`` (a field's bytes, the
                                                    fields or files of one form)
``SessionNotFoundError``                    404     no such session
``AnsweredDifferentlyError`` (console)       409     a page's answer to a query answered
                                                    already with another answer (the same
                                                    answer again redirects: already saved)
``QueryError``                              409     stale, unknown or already-answered query
``SessionStateError``                       409     paused/finished session, nothing to undo...
``ConflictError``                           409     another writer changed the session first
``SessionBusyError``                        409     another writer held the session too long
                                                    (a POST; a GET gets 503 with Retry-After)
``SessionFinishedError``                    409     the session takes no more events
``NoSafeGaitError``                         409     no gait may be proposed (all avoided or
                                                    near an unsafe flag): nothing proposed
``InfeasibleProposalsError``                 409     (a ``NoSafeGaitError``) gaits on demand:
                                                    the ask stopped at ``[gaits]
                                                    max_infeasible`` gaits that cannot be
                                                    made; nothing proposed, *those* logged
``FeedbackError`` / ``ConfigError``         422     an answer or a config that cannot be used
``PriorFromError``                          422     a warm start's prior_from names no session,
                                                    or one that cannot be rebuilt
``InputError`` (console) / ``ValueError``   422     any other refused input
``ConvergenceError``                        422     the model could not take this answer
``SchemaError`` / ``StorageConnectError``   503     the database cannot be used as it is
``StorageFailureError``                     503     the database failed while in use (disk
                                                    I/O error, a locked, removed or replaced
                                                    SQLite file): the message names it
``GaitError`` (not ``GaitLibraryError``)    503     the gait generator failed to make a
                                                    proposed gait: nothing proposed
``ReplayError``                             500     the stored log does not replay: see message
==========================================  ======  =========================================

In every case but one the session API wrote nothing (it checks before it writes), so a refused
request leaves the database as it was; the one is an ask that stopped (``query_stopped``), which
logged the gaits it found could not be made (and avoids them): ``InfeasibleProposalsError``, so
that asking again goes on from there, or a ``NoSafeGaitError`` when no gait was left to propose
after them.
An undo (``POST .../undo``, a round withdrawn with ``undo``) is written before the query drawn
in place of the undone one, when that one is withdrawn (it proposed a gait flagged unsafe
since): should that query not be written (``StorageError``), made (``GaitError``) or proposed
(``NoSafeGaitError``), the request is not refused (the undo stands): it succeeds (200, or the
page's redirect), and the API's ``next_query_error`` says why; the next ask proposes the query.
API requests get JSON (``{"detail": ...}``; 422 in FastAPI's shape, with ``loc`` naming the
field), pages get an HTML page that says what happened.
"""

from __future__ import annotations

from dataclasses import dataclass

from gaitpref.config import ConfigError
from gaitpref.errors import (
    ConvergenceError,
    FeedbackError,
    GaitError,
    GaitLibraryError,
    NoSafeGaitError,
    PriorFromError,
    PriorNotPositiveDefiniteError,
    ReplayError,
    SessionStateError,
)
from gaitpref.loop.cospar import QueryError
from gaitpref.storage import (
    ConflictError,
    SchemaError,
    SessionBusyError,
    SessionFinishedError,
    SessionNotFoundError,
    StorageConnectError,
    StorageError,
    StorageFailureError,
)

#: the most characters of a refused value an error message quotes (then its length)
QUOTE_CHARS = 60


def quoted(value: str, limit: int = QUOTE_CHARS) -> str:
    """``value`` as an error message quotes it: whole (``repr``) up to ``limit`` characters, else
    its start and its length, so that a refused megabyte is not echoed back."""
    if len(value) <= limit:
        return repr(value)
    return f"{value[:limit]!r}... ({len(value):,} characters)"


class InputError(ValueError):
    """A request field the console refuses before calling the session API."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field if len(field) <= QUOTE_CHARS else f"{field[:QUOTE_CHARS]}..."


class CsrfError(PermissionError):
    """A form without this console's CSRF token."""


class FormTooLargeError(ValueError):
    """A page's form past one of the form limits (``limits.py``); the message says which."""


class FormUnreadableError(ValueError):
    """A page's form that cannot be parsed as the form it says it is."""


class AnsweredDifferentlyError(QueryError):
    """A page's answer form posted to a query that is answered already, with an answer other
    than the one logged (the message says which, and how to change it)."""


#: checked in order: the first matching type gives the status
STATUS_OF: tuple[tuple[type[Exception], int, str], ...] = (
    (CsrfError, 403, "refused form"),
    (FormTooLargeError, 413, "form too large"),
    (FormUnreadableError, 400, "form not readable"),
    (SessionNotFoundError, 404, "not found"),
    (AnsweredDifferentlyError, 409, "answered already"),
    (QueryError, 409, "stale query"),
    (SessionStateError, 409, "not now"),
    (ConflictError, 409, "changed elsewhere"),
    (SessionBusyError, 409, "session busy"),
    (SessionFinishedError, 409, "finished"),
    (NoSafeGaitError, 409, "no safe gait"),
    (SchemaError, 503, "database schema"),
    (StorageConnectError, 503, "database unreachable"),
    (StorageFailureError, 503, "database failed"),
    (GaitLibraryError, 422, "refused gait library"),
    (GaitError, 503, "gait not made"),
    (FeedbackError, 422, "refused answer"),
    (ConfigError, 422, "refused config"),
    (PriorNotPositiveDefiniteError, 422, "refused config"),
    (PriorFromError, 422, "refused warm start"),
    (InputError, 422, "refused input"),
    (ConvergenceError, 422, "model did not converge"),
    (StorageError, 422, "refused by storage"),
    (ValueError, 422, "refused input"),
    (ReplayError, 500, "log does not replay"),
)

HANDLED: tuple[type[Exception], ...] = tuple(t for t, _, _ in STATUS_OF)


@dataclass(frozen=True)
class Refusal:
    """An error as the console reports it."""

    status: int
    title: str
    detail: str
    field: str | None

    def api_body(self) -> dict[str, object]:
        if self.status == 422:
            loc: list[str] = ["body"] + ([self.field] if self.field else [])
            return {"detail": [{"loc": loc, "msg": self.detail, "type": "value_error"}]}
        return {"detail": self.detail}


def _field_of(exc: BaseException) -> str | None:
    if isinstance(exc, InputError):
        return exc.field
    if isinstance(exc, FeedbackError):
        text = str(exc)
        if text.startswith("comparison"):
            return "comparisons"
        if text.startswith("suggestion"):
            return "suggestions"
        return "feedback"  # a rating or another registered kind
    if isinstance(exc, ConfigError | PriorNotPositiveDefiniteError):
        return "config"
    if isinstance(exc, PriorFromError):
        return "prior_from"
    if isinstance(exc, QueryError):
        return "query_id"
    return None


def refusal(exc: BaseException, method: str = "POST") -> Refusal:
    """How ``exc`` is reported (for a request of ``method``): status, title and message.

    Reads never answer 409: a session busy past the bounded wait is 503 for them.
    """
    for kind, status, title in STATUS_OF:
        if isinstance(exc, kind):
            if isinstance(exc, SessionBusyError) and method in ("GET", "HEAD"):
                status = 503
            detail = str(exc) or title
            if status == 409 and isinstance(exc, QueryError | ConflictError):
                detail += "; nothing was written"
            return Refusal(status, title, detail, _field_of(exc))
    raise TypeError(f"no status is defined for {type(exc).__name__}")  # pragma: no cover
