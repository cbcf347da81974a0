"""Typed, versioned JSON payloads: the base of every stored event's payload.

Each kind of event has one payload class (a frozen pydantic model) with a ``kind`` (the event
kind stored beside it) and a schema ``version`` (stored in the event's ``version`` column).  A
payload is validated when it is written and again when it is read; a stored payload of another
version, or one that does not validate, is refused with an error naming the event and the field.

Replay re-derives every event and compares the fields that are re-derivable: by default every
field; a field annotated :data:`Recorded` (``Annotated[T, Recorded]``) is written for the reader
(a gait's feature values, a free-text detail) and not compared.  :meth:`EventPayload.checked_fields`
gives the compared ones, so the replay checks follow the classes rather than a hand-kept list.
"""

from __future__ import annotations

from typing import Any, ClassVar, Self

from pydantic import BaseModel, ConfigDict, ValidationError

from gaitpref.errors import GaitprefError


class _RecordedMarker:
    """Marks a payload field that replay does not compare (see the module docstring)."""

    def __repr__(self) -> str:
        return "Recorded"


Recorded = _RecordedMarker()


class PayloadError(GaitprefError, ValueError):
    """A payload that does not fit its class; the message names the field."""


class EventPayload(BaseModel):
    """Base of every event payload: subclasses set ``kind`` and ``version`` and their fields."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)

    kind: ClassVar[str] = ""
    version: ClassVar[int] = 1

    @classmethod
    def checked_fields(cls) -> tuple[str, ...]:
        """The fields replay re-derives and compares with the log (all but :data:`Recorded`)."""
        return tuple(
            name
            for name, info in cls.model_fields.items()
            if not any(isinstance(m, _RecordedMarker) for m in info.metadata)
        )

    @classmethod
    def parse(cls, data: object, where: str = "") -> Self:
        """Validate stored or given JSON ``data``; :class:`PayloadError` names the field."""
        try:
            return cls.model_validate(data)
        except ValidationError as exc:
            raise PayloadError(f"{where or cls.kind}: {describe(exc)}") from None

    def to_json(self) -> dict[str, Any]:
        """The payload as stored (plain JSON types)."""
        return self.model_dump(mode="json")


def describe(exc: ValidationError) -> str:
    """pydantic's errors as one line each: ``field: message (got value)``."""
    lines = []
    for err in exc.errors():
        where = ".".join(str(p) for p in err["loc"]) or "payload"
        got = err.get("input")
        shown = repr(got) if len(repr(got)) <= 60 else repr(got)[:57] + "..."
        lines.append(f"{where}: {err['msg'].lower()} (got {shown})")
    return "; ".join(lines)


__all__ = ["EventPayload", "PayloadError", "Recorded", "describe"]
