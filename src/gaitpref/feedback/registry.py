"""The registry of feedback kinds: by name, by record type and by event kind.

``comparison``, ``suggestion`` and ``rating`` are registered when :mod:`gaitpref.feedback` is
imported; a kind defined elsewhere (a lab's own, a test's) becomes usable everywhere (the
loop, sessions, replay, exports) by :func:`register`.  Kinds keep their registration order: a
loop fits an answer's terms kind by kind in that order, so a replay gives the same numbers.
"""

from __future__ import annotations

from typing import Any

from gaitpref.feedback.base import FeedbackKind

_BY_NAME: dict[str, FeedbackKind[Any]] = {}


def register(kind: FeedbackKind[Any], *, replace: bool = False) -> FeedbackKind[Any]:
    """Make ``kind`` known; refuses a name, record type or event kind already taken (unless
    ``replace`` and the same name)."""
    for attr in ("name", "record_type", "payload_type", "export"):
        if not hasattr(kind, attr):
            raise TypeError(f"feedback kind {type(kind).__name__} does not set {attr}")
    old = _BY_NAME.get(kind.name)
    if old is not None and not replace:
        raise ValueError(f"a feedback kind named {kind.name!r} is already registered")
    for other in _BY_NAME.values():
        if other is old:
            continue
        if other.record_type is kind.record_type:
            raise ValueError(
                f"record type {kind.record_type.__name__} already belongs to kind {other.name!r}"
            )
        if other.event_kind == kind.event_kind:
            raise ValueError(
                f"event kind {kind.event_kind!r} already belongs to kind {other.name!r}"
            )
    _BY_NAME[kind.name] = kind
    return kind


def unregister(name: str) -> None:
    """Forget the kind called ``name`` (for tests that register their own)."""
    if name in ("comparison", "suggestion", "rating"):
        raise ValueError(f"the built-in feedback kind {name!r} cannot be removed")
    _BY_NAME.pop(name, None)


def kinds() -> tuple[FeedbackKind[Any], ...]:
    """Every registered kind, in registration order."""
    return tuple(_BY_NAME.values())


def kind_named(name: str) -> FeedbackKind[Any]:
    """The registered kind called ``name``; a ``KeyError`` listing the registered kinds if none."""
    try:
        return _BY_NAME[name]
    except KeyError:
        raise KeyError(
            f"no feedback kind {name!r}; registered kinds are {', '.join(_BY_NAME)}"
        ) from None


def kind_of(record: object) -> FeedbackKind[Any] | None:
    """The kind whose record type ``record`` is, or None (a raw tuple or dict)."""
    for kind in _BY_NAME.values():
        if isinstance(record, kind.record_type):
            return kind
    return None


def kind_for_event(event_kind: str) -> FeedbackKind[Any] | None:
    """The kind stored as events of ``event_kind``, or None."""
    for kind in _BY_NAME.values():
        if kind.event_kind == event_kind:
            return kind
    return None


__all__ = ["kind_for_event", "kind_named", "kind_of", "kinds", "register", "unregister"]
