"""An ask with gaits made on demand in which the gait generator describes a gait with a document
that is not JSON (a numpy array, a set, NaN or infinity, a key that is not text).

The document (generator, settings, parameters and anything a generator of one's own adds) is
hashed for the gait's key and written into the gait cache as JSON.  Such a document is a
:class:`~gaitpref.errors.GaitGeneratorFaultError` naming the generator, the gait (its id and
parameter vector) and where the document is wrong, raised before anything of that gait is
cached or logged: the session's log and cache are as they were, and asking again fails the
same way until the generator is fixed.  Before, a bare ``TypeError`` or ``ValueError`` escaped
from the cache's write (after the gait was kept in the cache's memory, so a retry went on with a
gait the cache could not hold), or a fault said "failed naming the gait" with ``json``'s words
and no field.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.errors import GaitGeneratorFaultError
from gaitpref.space import FloatArray
from tests.sessions.gaitkit import CONFIG, NAME, FakeSteps, logged

Edit = Callable[[dict[str, Any]], None]


def _array(doc: dict[str, Any]) -> None:
    doc["parameters"]["step_length"] = np.array([doc["parameters"]["step_length"]])


def _set(doc: dict[str, Any]) -> None:
    doc["settings"]["tags"] = {"fast"}


def _nan(doc: dict[str, Any]) -> None:
    doc["settings"]["below"] = float("nan")


def _inf(doc: dict[str, Any]) -> None:
    doc["settings"]["limits"] = [0.0, 1.0, float("inf")]


def _int_key(doc: dict[str, Any]) -> None:
    doc["parameters"][1] = 0.5


def _extra(doc: dict[str, Any]) -> None:  # a field of one's own, not part of the key
    doc["notes"] = {"solver": np.float32(1.5)}


CASES = pytest.mark.parametrize(
    ("edit", "where", "what"),
    [
        (_array, "parameters.step_length", "is a numpy.ndarray"),
        (_set, "settings.tags", "is a set"),
        (_nan, "settings.below", "is NaN"),
        (_inf, "settings.limits[2]", "is inf"),
        (_int_key, "parameters", "has the key 1 (of type int, not text)"),
        (_extra, "notes.solver", "is a numpy.float32"),
    ],
    ids=["ndarray", "set", "nan", "inf", "int-key", "own-field"],
)


def _describe_with(monkeypatch: pytest.MonkeyPatch, edit: Edit) -> None:
    """``FakeSteps`` describes every gait with its document edited by ``edit``."""
    original = FakeSteps.document

    def document(self: FakeSteps, vector: FloatArray) -> dict[str, Any]:
        doc = original(self, vector)
        edit(doc)
        return doc

    monkeypatch.setattr(FakeSteps, "document", document)


@CASES
def test_a_document_that_is_not_json_is_named_and_nothing_is_cached_or_logged(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, edit: Edit, where: str, what: str
) -> None:
    config = parse_config(CONFIG)
    reference = Session.create(f"sqlite:///{tmp_path / 'ref.db'}", config, subject="S01")
    expected = reference.next_query()  # the same ask without the fault
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, config, subject="S01")
    _describe_with(monkeypatch, edit)
    with pytest.raises(GaitGeneratorFaultError) as caught:
        s.next_query()
    message = str(caught.value)
    # the generator, the gait's id and its parameter vector (step length, step width)
    named = re.match(
        rf"the gait generator {NAME!r} described gait (S[\d.]+-S[\d.]+) \((.*?)\)", message
    )
    assert named is not None, message
    length, width = (float(v) for v in named[2].split(", "))
    assert named[1] == f"S{length:.3f}-S{width:.3f}"
    assert f"a document that is not JSON: {where} {what}" in message, message
    assert "Nothing is logged" in message
    # nothing of the gait is cached or logged
    assert [e.kind for e in s.events()] == ["created"] and s.pending is None
    cache = tmp_path / "lab.db.gaits"
    assert not cache.exists() or list(cache.iterdir()) == []
    # asking again, with the generator unchanged, fails the same way, writing nothing
    with pytest.raises(GaitGeneratorFaultError) as again:
        s.next_query()
    assert str(again.value) == message
    assert [e.kind for e in Session.open(url, s.id).events()] == ["created"]
    assert not cache.exists() or list(cache.iterdir()) == []
    # the generator fixed: the ask is the one without the fault
    monkeypatch.undo()
    q = s.next_query()
    assert logged(s) == logged(reference)
    assert (q.actions, q.points) == (expected.actions, expected.points)


@pytest.mark.parametrize("field", ["format", "schema_version", "key", "warm_start", "gait"])
def test_a_document_with_a_field_of_the_cache_file_is_named_and_nothing_is_cached_or_logged(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, field: str
) -> None:
    """The cache file spreads the document among its own fields: a document's ``key`` or
    ``format`` replaced the file's (an entry that never read back), its ``gait`` or
    ``warm_start`` was replaced by them (the document read back was not the one given)."""

    def own(doc: dict[str, Any]) -> None:
        doc[field] = "mine"

    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, parse_config(CONFIG), subject="S01")
    _describe_with(monkeypatch, own)
    with pytest.raises(GaitGeneratorFaultError) as caught:
        s.next_query()
    message = str(caught.value)
    named = re.match(rf"the gait generator {NAME!r} described gait (S[\d.]+-S[\d.]+) \(", message)
    assert named is not None, message
    assert f"field {field!r}" in message and "the gait cache's own" in message, message
    assert [e.kind for e in s.events()] == ["created"] and s.pending is None
    cache = tmp_path / "lab.db.gaits"
    assert not cache.exists() or list(cache.iterdir()) == []
    monkeypatch.undo()
    assert s.next_query().actions
