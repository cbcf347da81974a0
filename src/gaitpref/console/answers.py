"""Answers of any registered feedback kind, as the console receives them.

The JSON API takes ``"feedback": [{"kind": "rating", "action": 7, "label": "okay"}, ...]``: the
kind's name and its record's fields.  Each item becomes the kind's record
(``kind.record_type(**fields)``, :func:`gaitpref.feedback.kind_named`), which the session then
checks against its query (``FeedbackKind.parse``), so a kind registered from outside the package
works here unchanged.  The trial page's rating buttons post ``rate-<action>`` fields (a label
``1..K`` or empty: not rated), read by :func:`read_rating_fields`.

Refusals are :class:`~gaitpref.console.errors.InputError` naming the field (``feedback`` with
the item's position, or the form field), so the client gets 422 and nothing is written.

:func:`logged_answer` compares an answer form posted to a query that is answered already with
the answer the session logged for it, so that the trial page can tell a repeated post of the
same form (a double click or a re-sent form without JavaScript: already saved, nothing to do)
from a different answer (refused, 409).
"""

from __future__ import annotations

import dataclasses
import re
from collections import Counter
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from gaitpref.console.errors import InputError, quoted
from gaitpref.feedback import Rating, kind_named
from gaitpref.feedback.rating import RatingGiven

if TYPE_CHECKING:
    from gaitpref.sessions.session import Session, SessionQuery

_RATE = re.compile(r"^rate-(\d{1,10})$")
_SCALARS = (str, int, float, bool, type(None))


def feedback_record(kind_name: str, fields: Mapping[str, object], where: str) -> object:
    """The record of kind ``kind_name`` with ``fields`` (values must be JSON scalars)."""
    try:
        kind = kind_named(kind_name)
    except KeyError as exc:
        raise InputError(where, str(exc.args[0])) from None
    for key, value in fields.items():
        if not isinstance(value, _SCALARS):
            raise InputError(where, f"{kind_name}: field {key!r} must be a number or a text")
    record_type = kind.record_type
    if dataclasses.is_dataclass(record_type):
        names = [f.name for f in dataclasses.fields(record_type)]
        missing = [n for n in names if n not in fields]
        extra = [k for k in fields if k not in names]
        if missing or extra:
            said = ", ".join(f"missing {n!r}" for n in missing)
            said += (", " if said and extra else "") + ", ".join(f"unknown {k!r}" for k in extra)
            raise InputError(where, f"{kind_name} takes the fields {', '.join(names)}: {said}")
    try:
        return record_type(**fields)
    except TypeError as exc:
        raise InputError(where, f"{kind_name}: {exc}") from None


def feedback_records(items: Sequence[tuple[str, Mapping[str, object]]]) -> list[object]:
    """Records of ``(kind, fields)`` items; errors name ``feedback.<position>``."""
    return [
        feedback_record(kind, fields, f"feedback.{n}") for n, (kind, fields) in enumerate(items)
    ]


def read_rating_fields(form: Mapping[str, str], size: int) -> list[Rating]:
    """Ratings of a trial page's ``rate-<action>`` fields (``1..size``; empty: not rated); a
    rating given to a session without a rating scale (``size`` 0) is refused saying so."""
    out: list[Rating] = []
    for name, value in form.items():
        m = _RATE.match(name)
        if m is None or value == "":
            continue
        if size == 0:
            raise InputError(
                name,
                "this session is not rated: its config has no [feedback.rating] table, so a "
                "trial takes no rating (leave it empty, or start a session whose config has one)",
            )
        if not re.fullmatch(r"\d{1,3}", value) or not 1 <= int(value) <= size:
            raise InputError(name, f"a rating is a number 1..{size} or empty; got {quoted(value)}")
        out.append(Rating(int(m.group(1)), int(value)))
    return out


def is_rating_field(name: str) -> bool:
    return _RATE.match(name) is not None


@dataclasses.dataclass(frozen=True)
class LoggedAnswer:
    """The answer the session logged for a query that is answered (and not undone), and
    whether a posted answer is the same one."""

    query: SessionQuery
    trials: tuple[int, ...]
    same: bool
    comparisons: tuple[tuple[int, int, str], ...]
    suggestions: tuple[tuple[int, str, str], ...]
    #: ``(action, category)`` of each rating
    ratings: tuple[tuple[int, str], ...]
    #: kinds of other feedback in the logged answer (a form cannot post them)
    other_kinds: tuple[str, ...]


def _comparison_key(first: int, second: int, outcome: str) -> tuple[int, int, str]:
    """A comparison with its pair in order: ``(j, i, "first")`` is ``(i, j, "second")``."""
    if first <= second:
        return first, second, outcome
    return second, first, {"first": "second", "second": "first"}.get(outcome, outcome)


def logged_answer(
    session: Session,
    query_id: int,
    comparisons: Sequence[tuple[int, int, str]],
    suggestions: Sequence[tuple[int, str, str]],
    ratings: Sequence[Rating],
) -> LoggedAnswer | None:
    """The logged answer of ``query_id`` compared with a posted one (comparisons, suggestions
    and ratings; the note is not part of the answer), or None when ``query_id`` is pending or
    has no answer in force (stale, unknown, or its answer undone).  Reads only."""
    pending = session.pending
    if pending is not None and pending.id == query_id:
        return None
    query = next((q for q, _ in session.history() if q.id == query_id), None)
    if query is None:
        return None
    trials = tuple(t.number for t in session.trials() if t.query == query_id)
    logged_cmp = tuple(
        (c.first, c.second, c.outcome)
        for c in session.comparisons()
        if c.query == query_id and not c.undone
    )
    logged_sug = tuple(
        (s.action, s.feature, s.move)
        for s in session.suggestions()
        if s.query == query_id and not s.undone
    )
    logged_rating: list[tuple[int, int, str]] = []
    others: list[str] = []
    for f in session.feedback():
        if f.query != query_id or f.undone:
            continue
        if f.kind == RatingGiven.kind:
            p = f.payload
            logged_rating.append((int(p["action"]), int(p["label"]), str(p.get("category", ""))))
        else:
            others.append(f.kind)
    same = (
        not others
        and Counter(_comparison_key(*c) for c in logged_cmp)
        == Counter(_comparison_key(i, j, o) for i, j, o in comparisons)
        and Counter(logged_sug) == Counter(suggestions)
        and Counter((a, label) for a, label, _ in logged_rating)
        == Counter((int(r.action), int(r.label)) for r in ratings)
    )
    return LoggedAnswer(
        query,
        trials,
        same,
        logged_cmp,
        logged_sug,
        tuple((a, category or str(label)) for a, label, category in logged_rating),
        tuple(others),
    )


__all__ = [
    "LoggedAnswer",
    "feedback_record",
    "feedback_records",
    "is_rating_field",
    "logged_answer",
    "read_rating_fields",
]
