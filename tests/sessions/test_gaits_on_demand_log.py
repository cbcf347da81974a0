"""The log carries the gaits made on demand (``gait_made`` / ``gait_infeasible`` version 2): a
session opens from its log alone, on any backend, without optimising a gait again; a log written
before (version 1) replays by taking the cache's gaits or making them again; a logged gait that
is not the proposal's, does not read as a gait, or contradicts its event's verdict is refused,
naming the event."""

from __future__ import annotations

import shutil
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gaitpref import ReplayError, Session
from gaitpref.config import parse_config
from gaitpref.gaits import GaitCacheWarning
from gaitpref.sessions import events as log
from gaitpref.storage import EventRecord, NewEvent, Storage
from tests.sessions.gaitkit import (
    CONFIG,
    GAIT_EVENTS,
    FakeSteps,
    copied,
    fresh_fake_steps,
    logged_as_version_1,
    never_made,
    prefer_short_steps,
)


@pytest.fixture(autouse=True)
def _fresh_generator() -> Iterator[None]:
    yield from fresh_fake_steps(0.5)  # half the steps have no gait


def _sqlite(tmp_path: Path) -> str:
    return f"sqlite:///{tmp_path / 'lab.db'}"


def _recorded(db: str | Storage, queries: int = 14) -> Session:
    """A session driven to short (infeasible) steps, a query pending."""
    s = Session.create(db, parse_config(CONFIG), "S01")
    prefer_short_steps(s, queries)
    s.next_query()
    assert s.infeasible_gaits(), "the subject's short steps reach infeasible gaits"
    return s


def _state(s: Session) -> tuple[Any, ...]:
    return (s.trials(), s.infeasible_gaits(), s.pending, s.events())


def test_new_sessions_log_each_gait_it_made(tmp_path: Path) -> None:
    s = _recorded(_sqlite(tmp_path))
    gait_events = [e for e in s.events() if e.kind in GAIT_EVENTS]
    assert {e.version for e in gait_events} == {2}
    for e in gait_events:
        g = e.payload["gait"]
        assert g["feasible"] is (e.kind == "gait_made")
        assert g["step_length"] == e.payload["values"]["step_length"]
    made = [e for e in gait_events if e.kind == "gait_made"]
    assert all(e.payload["cot"] == e.payload["gait"]["cot"] for e in made)
    refused = [e for e in gait_events if e.kind == "gait_infeasible"]
    assert all(e.payload["reason"] == e.payload["gait"]["solver_message"] for e in refused)


def test_a_session_opens_from_its_log_alone_on_every_backend(
    open_db: Callable[[], Storage], monkeypatch: pytest.MonkeyPatch
) -> None:
    """No cache folder (removed, or none: memory and PostgreSQL) and a generator that cannot
    make a gait: the same trials, posterior and next query."""
    s = _recorded(open_db())
    before, mean = _state(s), np.asarray(s.posterior().mean)
    folder = s.storage.folder_beside(".gaits")
    if folder is not None:
        shutil.rmtree(folder)
    monkeypatch.setattr(FakeSteps, "make", never_made)
    again = Session.open(open_db(), s.id)
    assert _state(again) == before
    assert np.array_equal(np.asarray(again.posterior().mean), mean)
    assert again.next_query() == s.next_query()
    if folder is not None:  # the log's gaits went back into the cache
        keys = {e.payload["key"] for e in before[3] if e.kind in GAIT_EVENTS}
        assert {p.stem for p in folder.glob("*.json")} == keys


def test_a_database_whose_gait_cache_cannot_be_written_opens_and_goes_on(tmp_path: Path) -> None:
    """The cache folder removed and a file in its place (as a read-only folder): opening the
    session (replay puts the log's gaits into the cache) and making new gaits failed with
    OSError; now a GaitCacheWarning names the folder and the session opens and goes on."""
    s = _recorded(_sqlite(tmp_path))
    before = _state(s)
    folder = s.storage.folder_beside(".gaits")
    assert folder is not None
    shutil.rmtree(folder)
    folder.write_text("not a folder")
    with pytest.warns(GaitCacheWarning, match="cannot write"):
        again = Session.open(_sqlite(tmp_path), s.id)
    assert _state(again) == before
    made = len(FakeSteps.calls)
    prefer_short_steps(again, 3)
    assert len(FakeSteps.calls) > made  # new gaits were made (and logged)
    with pytest.warns(GaitCacheWarning, match="cannot write"):
        reopened = Session.open(_sqlite(tmp_path), s.id)
    assert _state(reopened) == _state(again)
    assert folder.read_text() == "not a folder"


def test_a_version_1_log_replays_from_the_cache_or_by_making_its_gaits_again(
    tmp_path: Path,
) -> None:
    s = _recorded(_sqlite(tmp_path))
    made = list(FakeSteps.calls)
    old = logged_as_version_1(s.storage, s.id)
    assert {e.version for e in s.storage.events(old) if e.kind in GAIT_EVENTS} == {1}
    assert all(
        type(log.read_payload(e)) in (log.GaitMadeV1, log.GaitInfeasibleV1)
        for e in s.storage.events(old)
        if e.kind in GAIT_EVENTS
    )
    cached = Session.open(s.storage, old)  # the cache has every gait: none is made
    assert FakeSteps.calls == made
    shutil.rmtree(tmp_path / "lab.db.gaits")
    remade = Session.open(s.storage, old)  # none cached: each made again, in order
    assert FakeSteps.calls[len(made) :] == made
    for again in (cached, remade):
        assert (again.trials(), again.infeasible_gaits(), again.pending) == _state(s)[:3]
        assert again.next_query() == s.next_query()
    assert [e.version for e in s.storage.events(old)] == [e.version for e in remade.events()]


def test_a_version_1_session_continued_makes_only_its_version_1_gaits_again(
    tmp_path: Path,
) -> None:
    """Opened by this gaitpref, an older session goes on writing version 2: only its gaits
    logged before are made again when it is replayed without a cache."""
    s = _recorded(_sqlite(tmp_path), queries=4)
    old = Session.open(s.storage, logged_as_version_1(s.storage, s.id))
    prefer_short_steps(old, 12)
    versions = {e.version for e in old.events() if e.kind in GAIT_EVENTS}
    assert versions == {1, 2}, "the continued session makes new gaits"
    v1 = [e.payload["values"]["step_length"] for e in old.events() if e.version == 1 and
          e.kind in GAIT_EVENTS]  # fmt: skip
    shutil.rmtree(tmp_path / "lab.db.gaits")
    FakeSteps.calls = []
    again = Session.open(s.storage, old.id)
    assert sorted(length for length, _ in FakeSteps.calls) == sorted(set(v1))
    assert _state(again) == _state(old)


def _first(storage: Storage, session_id: int, kind: str) -> EventRecord:
    return next(e for e in storage.events(session_id) if e.kind == kind)


def _edited(s: Session, kind: str, change: Callable[[dict[str, Any]], None]) -> tuple[int, int]:
    """A copy of ``s`` with the first ``kind`` event's payload changed: (copy's id, seq)."""
    target = _first(s.storage, s.id, kind)

    def edit(e: EventRecord) -> NewEvent | None:
        if e.seq != target.seq:
            return None
        payload = {**e.payload, "gait": dict(e.payload["gait"])}
        change(payload)
        return NewEvent(e.kind, payload, e.at, e.version)

    return copied(s.storage, s.id, edit), target.seq


def test_a_logged_gait_under_another_key_is_refused_naming_the_event(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    s = _recorded(_sqlite(tmp_path))
    other = _first(s.storage, s.id, "gait_infeasible").payload["key"]
    bad, seq = _edited(s, "gait_made", lambda p: p.update(key=other))
    monkeypatch.setattr(FakeSteps, "make", never_made)
    with pytest.raises(ReplayError, match=rf"event {seq} \(gait_made\): key: the log has {other}"):
        Session.open(s.storage, bad)


@pytest.mark.parametrize(
    ("kind", "change", "says"),
    [
        ("gait_infeasible", lambda g: g.update(feasible=True), r"the logged gait is feasible"),
        ("gait_made", lambda g: g.update(feasible=False), r"the logged gait is infeasible"),
        ("gait_made", lambda g: g.update(alpha=[[0.1, 0.2]]), r"gait: alpha: expected shape"),
        ("gait_made", lambda g: g.pop("degree"), r"gait: degree: missing"),
    ],
    ids=["infeasible-made-feasible", "made-made-infeasible", "alpha", "no-degree"],
)
def test_a_logged_gait_that_does_not_fit_its_event_is_refused(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    kind: str,
    change: Callable[[dict[str, Any]], None],
    says: str,
) -> None:
    s = _recorded(_sqlite(tmp_path))
    bad, seq = _edited(s, kind, lambda p: change(p["gait"]))
    monkeypatch.setattr(FakeSteps, "make", never_made)
    with pytest.raises(ReplayError, match=rf"event {seq} \({kind}\).*{says}"):
        Session.open(s.storage, bad)


def test_a_version_2_gait_event_without_its_gait_is_refused(tmp_path: Path) -> None:
    s = _recorded(_sqlite(tmp_path))
    bad, seq = _edited(s, "gait_made", lambda p: p.pop("gait"))
    with pytest.raises(ReplayError, match=rf"event {seq} \(gait_made\).*gait: field required"):
        Session.open(s.storage, bad)
