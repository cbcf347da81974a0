"""The storage contract (``gaitpref/storage/base.py``), run against every backend."""

from __future__ import annotations

import hashlib
import threading
from collections.abc import Callable
from datetime import UTC, datetime

import pytest

from gaitpref.storage import (
    ConflictError,
    NewEvent,
    SessionFinishedError,
    SessionNotFoundError,
    SessionSpec,
    Storage,
    StorageError,
)

Opener = Callable[[], Storage]


def _spec(subject: str = "S01", seed: int = 7) -> SessionSpec:
    text = "name = 'x'\n"
    return SessionSpec(
        subject=subject,
        config_name="exo-1d-step-length",
        config_text=text,
        config_sha256=hashlib.sha256(text.encode()).hexdigest(),
        seed=seed,
        software_version="0.1.0",
        meta={"gait_ids": ["g1", "g2"], "nested": {"a": [1, 2.5, None, True]}},
    )


def test_create_get_and_list(open_db: Opener) -> None:
    db = open_db()
    first = db.create_session(_spec("S01"), [NewEvent("created", {"seed": 7})])
    second = db.create_session(_spec("S02", seed=2**63 - 1))
    third = db.create_session(_spec("S01"))
    assert (first.id, second.id, third.id) == (first.id, first.id + 1, first.id + 2)
    got = db.get_session(first.id)
    assert got == first
    assert got.status == "active" and got.last_seq == 1 and got.seed == 7
    assert got.meta == _spec().meta and got.created_at.tzinfo is not None
    assert db.get_session(second.id).seed == 2**63 - 1
    assert [s.id for s in db.list_sessions()] == [first.id, second.id, third.id]
    assert [s.id for s in db.list_sessions("S01")] == [first.id, third.id]
    assert [s.code for s in db.list_subjects()] == ["S01", "S02"]
    assert [e.kind for e in db.events(first.id)] == ["created"]


def test_append_numbers_events_and_round_trips_json(open_db: Opener) -> None:
    db = open_db()
    sid = db.create_session(_spec()).id
    payload = {"x": 0.1 + 0.2, "tiny": 5e-324, "big": 2**53 + 1, "s": 'é ✓ "q"', "l": [[1], {}]}
    out = db.append(sid, 0, [NewEvent("a", payload), NewEvent("b")], status="paused")
    assert [(e.seq, e.kind) for e in out] == [(1, "a"), (2, "b")]
    stored = db.events(sid)
    assert stored[0].payload == payload and stored[1].payload == {}
    assert stored[0].payload["x"] == 0.1 + 0.2  # floats survive exactly
    record = db.get_session(sid)
    assert record.last_seq == 2 and record.status == "paused"
    assert record.updated_at >= record.created_at
    assert [e.seq for e in db.events(sid, after=1)] == [2]
    db.append(sid, 2, [NewEvent("c")])
    assert [e.seq for e in db.events(sid)] == [1, 2, 3]


def test_records_are_copies(open_db: Opener) -> None:
    db = open_db()
    sid = db.create_session(_spec()).id
    payload = {"list": [1, 2]}
    db.append(sid, 0, [NewEvent("a", payload)])
    payload["list"].append(3)
    read = db.events(sid)[0]
    read.payload["list"].append(4)
    assert db.events(sid)[0].payload == {"list": [1, 2]}


def test_stale_append_conflicts_and_writes_nothing(open_db: Opener) -> None:
    db = open_db()
    sid = db.create_session(_spec()).id
    db.append(sid, 0, [NewEvent("a")])
    for after in (0, 2, -1):
        with pytest.raises(ConflictError, match="another writer"):
            db.append(sid, after, [NewEvent("b")], status="paused")
    assert [e.kind for e in db.events(sid)] == ["a"]
    assert db.get_session(sid).status == "active"


@pytest.mark.parametrize(
    "payload",
    [{"x": float("nan")}, {"x": float("inf")}, {"x": object()}, {1: "int key"}, ["not", "dict"]],
)
def test_non_json_payload_is_refused_whole_batch(open_db: Opener, payload: object) -> None:
    db = open_db()
    sid = db.create_session(_spec()).id
    with pytest.raises(StorageError):
        db.append(sid, 0, [NewEvent("ok"), NewEvent("bad", payload)])  # type: ignore[arg-type]
    assert db.events(sid) == [] and db.get_session(sid).last_seq == 0


def test_bad_specs_are_refused(open_db: Opener) -> None:
    db = open_db()
    for bad in (_spec("Jane Doe"), _spec(""), _spec(seed=-1), _spec(seed=2**63)):
        with pytest.raises(StorageError):
            db.create_session(bad)
    with pytest.raises(StorageError, match="kind"):
        db.create_session(_spec(), [NewEvent("")])
    assert db.list_sessions() == []


def test_finished_sessions_take_no_events(open_db: Opener) -> None:
    db = open_db()
    sid = db.create_session(_spec()).id
    db.append(sid, 0, [NewEvent("finished")], status="finished")
    with pytest.raises(SessionFinishedError):
        db.append(sid, 1, [NewEvent("note")])
    assert len(db.events(sid)) == 1


def test_unknown_sessions(open_db: Opener) -> None:
    db = open_db()
    for sid in (12345, "1", None):
        with pytest.raises(SessionNotFoundError):
            db.get_session(sid)  # type: ignore[arg-type]
        with pytest.raises(SessionNotFoundError):
            db.append(sid, 0, [NewEvent("a")])  # type: ignore[arg-type]
        with pytest.raises(SessionNotFoundError):
            db.events(sid)  # type: ignore[arg-type]


def test_import_times_are_kept(open_db: Opener) -> None:
    db = open_db()
    then = datetime(2020, 3, 1, 12, 30, 5, 123456, tzinfo=UTC)
    sid = db.create_session(_spec(), [NewEvent("created", {}, at=then)], status="paused").id
    assert db.events(sid)[0].at == then
    assert db.get_session(sid).status == "paused"


def test_two_writers_cannot_append_the_same_sequence_number(open_db: Opener) -> None:
    sid = open_db().create_session(_spec()).id
    handles = [open_db(), open_db()]
    barrier = threading.Barrier(2)
    results: list[str] = []

    def write(k: int) -> None:
        barrier.wait()
        try:
            handles[k].append(sid, 0, [NewEvent("answer", {"writer": k})])
            results.append("ok")
        except ConflictError:
            results.append("conflict")

    threads = [threading.Thread(target=write, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(results) == ["conflict", "ok"]
    assert [e.seq for e in open_db().events(sid)] == [1]


def test_sessions_are_independent(open_db: Opener) -> None:
    db = open_db()
    a, b = db.create_session(_spec("S01")).id, db.create_session(_spec("S02")).id
    db.append(a, 0, [NewEvent("x")])
    db.append(b, 0, [NewEvent("y"), NewEvent("z")])
    db.append(a, 1, [NewEvent("x2")])
    assert [e.kind for e in db.events(a)] == ["x", "x2"]
    assert [e.kind for e in db.events(b)] == ["y", "z"]
