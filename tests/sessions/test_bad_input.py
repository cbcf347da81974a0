"""Bad input gets a clear error and writes nothing."""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from gaitpref import ConfigError, FeedbackError, QueryError, Session, SessionStateError
from gaitpref.errors import ExportError
from gaitpref.feedback import Comparison, Suggestion
from gaitpref.storage import (
    MemoryStorage,
    SchemaError,
    SessionNotFoundError,
    Storage,
    StorageConnectError,
    StorageError,
)
from tests.sessions.sessionkit import CONFIG, Drive


def test_unknown_session(db: str | Storage) -> None:
    Session.create(db, CONFIG, "S01")
    with pytest.raises(SessionNotFoundError, match="no session 99"):
        Session.open(db, 99)


def test_finished_session_takes_nothing(db: str | Storage, drive: Drive) -> None:
    s = Session.create(db, CONFIG, "S01")
    drive(s, 2)
    q = s.next_query()
    s.finish()
    n = len(s.events())
    attempts: list[tuple[Callable[[], object], str]] = [
        (lambda: s.answer(q.id, [], []), "finished"),
        (s.next_query, "finished"),
        (s.undo, "finished"),
        (lambda: s.exclude(1, "stumble"), "finished"),
        (lambda: s.note("late"), "finished"),
        (s.start_validation, "finished"),
        (s.finish, "already finished"),
        (s.resume, "finished"),
    ]
    for attempt, message in attempts:
        with pytest.raises(SessionStateError, match=message):
            attempt()
    reopened = Session.open(db, s.id)
    assert reopened.status == "finished" and len(reopened.events()) == n
    with pytest.raises(SessionStateError, match="finished"):
        reopened.answer(q.id, [], [])


def test_paused_session_refuses_answers_until_resumed(db: str | Storage) -> None:
    s = Session.create(db, CONFIG, "S01")
    q = s.next_query()
    s.pause()
    with pytest.raises(SessionStateError, match="paused"):
        s.answer(q.id, [], [])
    with pytest.raises(SessionStateError, match="paused"):
        s.next_query()
    s.note("break: subject resting")  # notes, undo and exclusions are fine while paused
    s.resume()
    s.answer(q.id, [], [])
    assert [e.kind for e in s.events()][-3:] == ["note", "resumed", "trial_executed"]


def test_stale_and_unknown_queries(db: str | Storage, drive: Drive) -> None:
    s = Session.create(db, CONFIG, "S01")
    drive(s, 2)
    answered = s.trials()[-1].query
    q = s.next_query()
    n = len(s.events())
    with pytest.raises(QueryError, match="already answered"):
        s.answer(answered, [], [])
    with pytest.raises(QueryError, match="not the pending query"):
        s.answer(q.id + 100, [], [])
    for not_an_id in (True, q, str(q.id), float(q.id)):  # the query itself, not its id
        with pytest.raises(QueryError, match="query_id must be the pending query's id"):
            s.answer(not_an_id, [], [])  # type: ignore[arg-type]
    s.undo()  # q is discarded; the last answer's query is pending again
    with pytest.raises(QueryError, match="stale"):
        s.answer(q.id, [], [])
    assert len(s.events()) == n + 1


@pytest.mark.parametrize(
    "comparisons, suggestions, message",
    [
        ([(999, 0, "first")], [], "off the grid"),
        ([(-1, 0, "first")], [], "off the grid"),
        ([(3, 4, "first")], [], "not in this query"),
        ([("a", 0, "first")], [], "integer"),
        ([], [(999, "step_length", "+big")], "off the grid"),
        ([], [(None, "step_width", "+big")], "integer"),
        ("Q", [], "expected"),
        (Comparison(0, 1, "first"), [], "got one Comparison: give \\[Comparison"),
        ([], Suggestion(0, "step_length", "+big"), "suggestions: expected a list"),
        ([], 7, "suggestions: expected a list"),
    ],
)
def test_actions_off_the_grid_and_malformed_answers(
    db: str | Storage, comparisons: object, suggestions: object, message: str
) -> None:
    s = Session.create(db, CONFIG, "S01", seed=9)
    q = s.next_query()
    n = len(s.events())
    with pytest.raises(FeedbackError, match=message):
        s.answer(q.id, comparisons, suggestions)  # type: ignore[arg-type]
    assert len(s.events()) == n and s.pending == q
    s.answer(q.id, [], [])  # the session is unharmed


def test_a_malformed_config_writes_nothing(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("[space.step_length]\nmin = 0.08\nmax = 0.18\nnum = 15\n[model]\nnoise = 1\n")
    url = f"sqlite:///{tmp_path / 'new.db'}"
    with pytest.raises(ConfigError, match="lengthscale"):
        Session.create(url, bad, "S01")
    with pytest.raises(ConfigError, match="no such file"):
        Session.create(url, tmp_path / "missing.toml", "S01")
    assert not (tmp_path / "new.db").exists()


def test_bad_subject_or_seed_writes_nothing(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'new.db'}"
    with pytest.raises(StorageError, match="pseudonymous"):
        Session.create(url, CONFIG, "Jane Doe")
    with pytest.raises(ValueError, match="seed"):
        Session.create(url, CONFIG, "S01", seed=-3)
    with pytest.raises(ValueError, match="library has 3 gaits"):
        Session.create(url, CONFIG, "S01", library=["a", "b", "c"])
    assert not (tmp_path / "new.db").exists()


def test_a_database_that_does_not_connect(tmp_path: Path) -> None:
    with pytest.raises(StorageConnectError, match="does not exist"):
        Session.create(f"sqlite:///{tmp_path}/no/such/folder/x.db", CONFIG, "S01")
    with pytest.raises(StorageConnectError, match="cannot connect"):
        Session.create("postgresql+psycopg://u@127.0.0.1:1/x", CONFIG, "S01")
    with pytest.raises(StorageConnectError, match="no gaitpref database"):
        Session.open(f"sqlite:///{tmp_path / 'absent.db'}", 1)
    assert not (tmp_path / "absent.db").exists()


def test_a_database_at_a_newer_schema(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'g.db'}"
    Session.create(url, CONFIG, "S01").close()
    with sqlite3.connect(tmp_path / "g.db") as raw:
        raw.execute("UPDATE alembic_version SET version_num = 'ffff'")
    newer: tuple[Callable[[], Session], ...] = (
        lambda: Session.open(url, 1),
        lambda: Session.create(url, CONFIG, "S02"),
    )
    for attempt in newer:
        with pytest.raises(SchemaError, match="newer gaitpref"):
            attempt()
    with sqlite3.connect(tmp_path / "g.db") as raw:
        assert raw.execute("SELECT count(*) FROM sessions").fetchone() == (1,)
        assert raw.execute("SELECT max(seq) FROM events").fetchone() == (1,)


def test_gait_library_ids_are_shown() -> None:
    ids = [f"gait-{k:02d}" for k in range(15)]
    s = Session.create(MemoryStorage(), CONFIG, "S01", library=ids)
    q = s.next_query()
    assert s.describe(q.actions[0]).endswith(f"[gait gait-{q.actions[0]:02d}]")
    s.answer(q.id, [], [])
    assert s.events()[-1].payload["gait_id"] == f"gait-{q.actions[0]:02d}"
    assert Session.open(s.storage, s.id).gait_ids == ids


def test_text_a_database_cannot_store_is_refused_by_name(tmp_path: Path, drive: Drive) -> None:
    """A terminal's undecodable bytes arrive as lone surrogates (surrogateescape): refused
    before anything is written, never accepted and then failing in an export."""
    with Session.create(f"sqlite:///{tmp_path / 'a.db'}", CONFIG, "S01") as s:
        drive(s, 2)
        before = len(s.events())
        bad = "bad \udcff byte"
        with pytest.raises(ValueError, match="the note is not valid text"):
            s.note(bad)
        with pytest.raises(ValueError, match="the exclusion's detail is not valid text"):
            s.exclude(1, "other", bad)
        with pytest.raises(ValueError, match="the unsafe flag's reason is not valid text"):
            s.flag_unsafe(1, bad)
        assert len(s.events()) == before


def test_an_export_that_fails_leaves_no_folder_and_can_run_again(
    tmp_path: Path, drive: Drive, monkeypatch: pytest.MonkeyPatch
) -> None:
    from gaitpref.sessions import export, export_session

    with Session.create(f"sqlite:///{tmp_path / 'a.db'}", CONFIG, "S01") as s:
        drive(s, 2)
        out = tmp_path / "export"

        def disk_full(rows: object) -> str:
            hidden = tmp_path / ".export.partial-x1y2" / "export" / "trials.csv"
            raise OSError(28, "No space left on device", str(hidden))

        with monkeypatch.context() as m:
            m.setattr(export, "_csv", disk_full)
            # named by the export asked for, not the hidden folder it was written in
            with pytest.raises(ExportError, match="could not write the export") as failed:
                export_session(s, out)
            assert str(out) in str(failed.value) and "partial" not in str(failed.value)
            assert "trials.csv: No space left on device" in str(failed.value)
        left = [p.name for p in tmp_path.iterdir() if not p.name.startswith("a.db")]
        assert left == []  # nothing half-written, not even the hidden folder
        manifest = export_session(s, out)
        assert manifest == out / "manifest.json" and manifest.is_file()
        (tmp_path / "empty").mkdir()
        assert export_session(s, tmp_path / "empty").is_file()  # an empty folder is fine


def test_a_config_file_that_is_not_utf8_is_a_config_error(tmp_path: Path) -> None:
    from gaitpref.config import load_config

    path = tmp_path / "bad.toml"
    path.write_bytes(b'name = "caf\xff"\n')
    with pytest.raises(ConfigError, match=r"bad.toml' is not UTF-8 text \(byte 11"):
        load_config(path)


@pytest.mark.parametrize("name", ["   ", "", "\t"])
def test_a_blank_config_name_is_refused_for_a_new_session(tmp_path: Path, name: str) -> None:
    """``name = "   "`` was taken: sessions listed, exported and shown under no name."""
    from gaitpref.config import load_config, parse_config

    named = f"name = {json.dumps(name)}"  # a TOML basic string: "\t" is a tab
    text = load_config(CONFIG).text.replace('name = "exo-1d-step-length"', named)
    path = tmp_path / "blank.toml"
    path.write_text(text, encoding="utf-8")
    db = MemoryStorage()
    for config in (path, parse_config(text)):
        with pytest.raises(ConfigError, match=r"^name: must name the config") as err:
            Session.create(db, config, "S01")
        assert err.value.key == "name"
    assert Session.list_sessions(db) == []


def test_a_session_stored_with_a_blank_config_name_reopens_and_replays(
    tmp_path: Path, drive: Drive, monkeypatch: pytest.MonkeyPatch
) -> None:
    import gaitpref.config.new
    from gaitpref.config import load_config, parse_config

    url = f"sqlite:///{tmp_path / 'old.db'}"
    text = load_config(CONFIG).text.replace('name = "exo-1d-step-length"', 'name = "   "')
    with monkeypatch.context() as m:  # as earlier releases took it
        m.setattr(gaitpref.config.new, "check_name", lambda config: None)
        s = Session.create(url, parse_config(text), "S01", seed=4)
    drive(s, 3)
    mean = s.posterior().mean.copy()
    s.close()
    with Session.open(url, s.id) as again:
        assert again.config.name == "   " and again.record.config_name == "   "
        assert (again.posterior().mean == mean).all() and len(again.trials()) == 3
        drive(again, 1)  # and it goes on


@pytest.mark.parametrize("where", ["answer_events", "exclude"])
def test_an_answer_interrupted_before_it_is_written_is_taken_back(
    sqlite_url: str, drive: Drive, monkeypatch: pytest.MonkeyPatch, where: str
) -> None:
    """Ctrl-C after CoSpar took the answer but before it was written (building its events, or
    the refit without an excluded buffered trial) writes nothing and leaves the session object
    as it was: the same query can be answered, and the log replays."""
    from gaitpref.loop.cospar import CoSpar
    from gaitpref.sessions.state import SessionState

    s = Session.create(sqlite_url, CONFIG, "S01")
    drive(s, 3)
    q = s.next_query()
    assert q.buffer and q.buffer[0] != q.actions[0]
    if where == "exclude":
        s.exclude(q.buffer_trials[0], "stumble")  # the answer's comparison is then dropped
        q = s.next_query()
    n = s.last_seq

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    if where == "answer_events":
        monkeypatch.setattr(SessionState, "answer_events", interrupted)
    else:
        monkeypatch.setattr(CoSpar, "exclude", interrupted)
    given = [(q.actions[0], q.buffer[0], "first")]
    with pytest.raises(KeyboardInterrupt):
        s.answer(q.id, given)
    monkeypatch.undo()
    assert s.last_seq == n
    s.answer(q.id, given)  # before: "query N was already answered", until reopened
    mean = s.posterior().mean.copy()
    s.close()
    with Session.open(sqlite_url, s.id) as again:
        assert again.posterior().mean.tolist() == mean.tolist()


@pytest.mark.parametrize("where", ["exclusion refit", "undo booked"])
def test_an_interrupted_exclusion_or_undo_leaves_a_log_that_replays(
    sqlite_url: str, drive: Drive, monkeypatch: pytest.MonkeyPatch, where: str
) -> None:
    """Ctrl-C while an exclusion refits the model (before it is written), or while an undo
    written is being booked, left the live Session's model off its log (the exclusion in
    memory, not logged; the undo applied twice on catching up): the queries it then logged
    were not the log's, and the session no longer opened ("cannot be rebuilt exactly")."""
    from gaitpref.loop.cospar import CoSpar

    s = Session.create(sqlite_url, CONFIG, "S01")
    drive(s, 4)
    q = s.next_query()
    if where == "exclusion refit":

        def interrupted(*args: object, **kwargs: object) -> None:
            raise KeyboardInterrupt

        monkeypatch.setattr(CoSpar, "exclude", interrupted)
        with pytest.raises(KeyboardInterrupt):
            s.exclude(q.buffer_trials[0], "stumble")
    else:
        undo = CoSpar.undo

        def booked_then_interrupted(self: CoSpar, *args: Any, **kwargs: Any) -> Any:
            undo(self, *args, **kwargs)
            raise KeyboardInterrupt

        monkeypatch.setattr(CoSpar, "undo", booked_then_interrupted)
        with pytest.raises(KeyboardInterrupt):
            s.undo()
    monkeypatch.undo()
    drive(s, 3)
    mean = s.posterior().mean.copy()
    query = s.next_query()
    s.close()
    with Session.open(sqlite_url, s.id) as again:
        assert again.next_query() == query
        assert again.posterior().mean.tolist() == mean.tolist()
