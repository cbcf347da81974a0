"""The storage contract as a reusable test suite: check any :class:`~gaitpref.storage.Storage`.

gaitpref runs this suite against its three backends (memory, SQLite, PostgreSQL) in
``tests/storage/test_contract.py``; a lab that writes its own backend runs the same suite against
it, as Optuna ships ``optuna/testing/storages.py``.  Subclass :class:`StorageContract` in a test
module (a class whose name starts with ``Test``) and say how to open your storage::

    # tests/test_my_storage.py
    from pathlib import Path

    from gaitpref.storage import Storage
    from gaitpref.storage.testing import StorageContract
    from my_lab.storage import LabStorage


    class TestLabStorage(StorageContract):
        def make_storage(self, tmp_path: Path) -> Storage:
            return LabStorage(f"sqlite:///{tmp_path / 'lab.db'}")

Then ``pytest tests/test_my_storage.py`` runs every ``test_*`` method below against it.
:meth:`StorageContract.make_storage` is called once per handle and must return a new handle on
*the same* database each time within a test (the two-writer tests open two); ``tmp_path`` is new
for every test, so each test starts from an empty database.  Handles are closed after the test.
To supply handles another way (a server, a fixture of your own), override the ``open_db`` fixture
instead, as ``tests/storage/test_contract.py`` does.

pytest is imported by this module only: ``import gaitpref`` does not need it.
"""

from __future__ import annotations

import hashlib
import threading
from collections.abc import Callable, Iterator
from datetime import UTC, datetime
from pathlib import Path

import pytest

from gaitpref.storage import (
    ConflictError,
    NewEvent,
    SessionFinishedError,
    SessionNotFoundError,
    SessionRecord,
    SessionSpec,
    Storage,
    StorageError,
)

__all__ = ["Opener", "StorageContract"]

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


class StorageContract:
    """The written storage contract (``gaitpref/storage/base.py``) as pytest test methods.

    Subclass it as ``Test<Something>`` and implement :meth:`make_storage` (or override the
    ``open_db`` fixture).  Not collected itself: its name does not start with ``Test``.
    """

    def make_storage(self, tmp_path: Path) -> Storage:
        """A new handle on this test's database (kept under ``tmp_path``)."""
        raise NotImplementedError(
            f"{type(self).__name__} must implement make_storage(tmp_path) or override the "
            "open_db fixture"
        )

    @pytest.fixture
    def open_db(self, tmp_path: Path) -> Iterator[Opener]:
        """Opens this test's database: each call is a new handle (closed after the test)."""
        opened: list[Storage] = []

        def opener() -> Storage:
            store = self.make_storage(tmp_path)
            if all(store is not s for s in opened):
                opened.append(store)
            return store

        yield opener
        for store in opened:
            store.close()

    def test_create_get_and_list(self, open_db: Opener) -> None:
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

    def test_a_checked_create_sees_the_subjects_sessions_and_a_refusal_writes_nothing(
        self, open_db: Opener
    ) -> None:
        db = open_db()
        first = db.create_session(_spec("S01"))
        db.create_session(_spec("S02"))
        seen: list[list[int]] = []
        made = db.create_session_checked(
            _spec("S01"), check=lambda sessions: seen.append([r.id for r in sessions])
        )
        assert seen == [[first.id]] and db.get_session(made.id).subject == "S01"

        def refuse(sessions: list[SessionRecord]) -> None:
            raise StorageError("refused")

        with pytest.raises(StorageError, match="refused"):
            db.create_session_checked(_spec("S03"), [NewEvent("created")], check=refuse)
        assert [r.subject for r in db.list_sessions()] == ["S01", "S02", "S01"]
        assert [s.code for s in db.list_subjects()] == ["S01", "S02"]

    def test_append_numbers_events_and_round_trips_json(self, open_db: Opener) -> None:
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

    def test_records_are_copies(self, open_db: Opener) -> None:
        db = open_db()
        sid = db.create_session(_spec()).id
        payload = {"list": [1, 2]}
        db.append(sid, 0, [NewEvent("a", payload)])
        payload["list"].append(3)
        read = db.events(sid)[0]
        read.payload["list"].append(4)
        assert db.events(sid)[0].payload == {"list": [1, 2]}

    def test_stale_append_conflicts_and_writes_nothing(self, open_db: Opener) -> None:
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
        [
            {"x": float("nan")},
            {"x": float("inf")},
            {"x": object()},
            {1: "int key"},
            ["not", "dict"],
        ],
    )
    def test_non_json_payload_is_refused_whole_batch(
        self, open_db: Opener, payload: object
    ) -> None:
        db = open_db()
        sid = db.create_session(_spec()).id
        with pytest.raises(StorageError):
            db.append(sid, 0, [NewEvent("ok"), NewEvent("bad", payload)])  # type: ignore[arg-type]
        assert db.events(sid) == [] and db.get_session(sid).last_seq == 0

    def test_bad_specs_are_refused(self, open_db: Opener) -> None:
        db = open_db()
        for bad in (_spec("Jane Doe"), _spec(""), _spec(seed=-1), _spec(seed=2**63)):
            with pytest.raises(StorageError):
                db.create_session(bad)
        with pytest.raises(StorageError, match="kind"):
            db.create_session(_spec(), [NewEvent("")])
        assert db.list_sessions() == []

    def test_finished_sessions_take_no_events(self, open_db: Opener) -> None:
        db = open_db()
        sid = db.create_session(_spec()).id
        db.append(sid, 0, [NewEvent("finished")], status="finished")
        with pytest.raises(SessionFinishedError):
            db.append(sid, 1, [NewEvent("note")])
        assert len(db.events(sid)) == 1

    def test_unknown_sessions(self, open_db: Opener) -> None:
        db = open_db()
        for sid in (12345, "1", None):
            with pytest.raises(SessionNotFoundError):
                db.get_session(sid)  # type: ignore[arg-type]
            with pytest.raises(SessionNotFoundError):
                db.append(sid, 0, [NewEvent("a")])  # type: ignore[arg-type]
            with pytest.raises(SessionNotFoundError):
                db.events(sid)  # type: ignore[arg-type]

    def test_import_times_are_kept(self, open_db: Opener) -> None:
        db = open_db()
        then = datetime(2020, 3, 1, 12, 30, 5, 123456, tzinfo=UTC)
        sid = db.create_session(_spec(), [NewEvent("created", {}, at=then)], status="paused").id
        assert db.events(sid)[0].at == then
        assert db.get_session(sid).status == "paused"

    def test_two_writers_cannot_append_the_same_sequence_number(self, open_db: Opener) -> None:
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

    def test_sessions_are_independent(self, open_db: Opener) -> None:
        db = open_db()
        a, b = db.create_session(_spec("S01")).id, db.create_session(_spec("S02")).id
        db.append(a, 0, [NewEvent("x")])
        db.append(b, 0, [NewEvent("y"), NewEvent("z")])
        db.append(a, 1, [NewEvent("x2")])
        assert [e.kind for e in db.events(a)] == ["x", "x2"]
        assert [e.kind for e in db.events(b)] == ["y", "z"]
