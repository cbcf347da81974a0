"""What is wrong, if anything, with a gait generator's document as JSON.

A generator's document (:meth:`~gaitpref.gaits.generator.GaitGenerator.document`: its name,
settings and a gait's parameters, and any field a generator of one's own adds) is hashed for the
gait's key and written into the gait cache as JSON, so it may hold only what JSON holds and reads
back unchanged: text, finite numbers, ``true``/``false``/``null``, lists (or tuples) and objects
whose keys are text.  :func:`document_problem` says where it does not, before anything is hashed
or written (``json`` alone would raise a ``TypeError`` naming no field, or, for a key that is a
number, write it as text, so that the document read back is not the one hashed).
"""

from __future__ import annotations

import math
from typing import Any

#: the parts of a document that decide its gait (:func:`~gaitpref.gaits.generator.content_key`)
DECIDING = ("generator", "settings", "parameters")


def document_problem(document: Any) -> str | None:
    """What is wrong with ``document`` as a gait's document, e.g. ``"parameters.step_length is
    a numpy.ndarray"``, or None: an object (dict) with :data:`DECIDING` fields, holding only JSON
    (:func:`json_problem`)."""
    if not isinstance(document, dict):
        return f"the document is {_a(document)}, not an object (a dict)"
    missing = [name for name in DECIDING if name not in document]
    if missing:
        return f"the document has no {', '.join(repr(m) for m in missing)}"
    return json_problem(document, "")


def json_problem(value: Any, where: str) -> str | None:
    """Where ``value`` (at ``where``: ``settings.limits[2]``; ``""`` for the whole) holds
    something other than text, finite numbers, booleans, None, lists, tuples and dicts with text
    keys, and what it is; None when it holds only those."""
    try:
        return _problem(value, where, set())
    except RecursionError:
        return f"{where or 'the document'} is nested too deeply"


def _problem(value: Any, where: str, inside: set[int]) -> str | None:
    """:func:`json_problem`; ``inside``: the ids of the containers ``value`` is in."""
    if value is None or isinstance(value, str | bool | int):
        return None
    if isinstance(value, float):
        if math.isfinite(value):
            return None
        return f"{where or 'the document'} is {'NaN' if math.isnan(value) else repr(float(value))}"
    if not isinstance(value, dict | list | tuple):
        return f"{where or 'the document'} is {_a(value)}"
    if id(value) in inside:
        return f"{where or 'the document'} refers back to an object or list it is in"
    inside = inside | {id(value)}
    if isinstance(value, dict):
        for key, item in value.items():
            if not isinstance(key, str):
                return (
                    f"{where or 'the document'} has the key {key!r} "
                    f"(of type {_type_name(key)}, not text)"
                )
            found = _problem(item, f"{where}.{key}" if where else key, inside)
            if found is not None:
                return found
        return None
    for i, item in enumerate(value):
        found = _problem(item, f"{where}[{i}]", inside)
        if found is not None:
            return found
    return None


def _type_name(value: object) -> str:
    """``set``, ``numpy.ndarray``: the type's name, with its package unless a builtin."""
    kind = type(value)
    package = kind.__module__.split(".")[0]
    return kind.__qualname__ if package == "builtins" else f"{package}.{kind.__qualname__}"


def _a(value: object) -> str:
    """``a set``, ``an int``: the type's name with its article."""
    name = _type_name(value)
    return f"{'an' if name[0].lower() in 'aeiou' else 'a'} {name}"


__all__ = ["DECIDING", "document_problem", "json_problem"]
