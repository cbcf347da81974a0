"""Answers of any registered feedback kind, as the console receives them.

The JSON API takes ``"feedback": [{"kind": "rating", "action": 7, "label": "okay"}, ...]``: the
kind's name and its record's fields.  Each item becomes the kind's record
(``kind.record_type(**fields)``, :func:`gaitpref.feedback.kind_named`), which the session then
checks against its query (``FeedbackKind.parse``), so a kind registered from outside the package
works here unchanged.  The trial page's rating buttons post ``rate-<action>`` fields (a label
``1..K`` or empty: not rated), read by :func:`read_rating_fields`.

Refusals are :class:`~gaitpref.console.errors.InputError` naming the field (``feedback`` with
the item's position, or the form field), so the client gets 422 and nothing is written.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping, Sequence

from gaitpref.console.errors import InputError, quoted
from gaitpref.feedback import Rating, kind_named

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


__all__ = ["feedback_record", "feedback_records", "is_rating_field", "read_rating_fields"]
