"""Replay: rebuilding a session from its log gives the same posterior, query and generator."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np
import pytest

import gaitpref.sessions.session
from gaitpref import Posterior, ReplayError, Session, load_config
from gaitpref.storage import Storage
from tests.sessions.sessionkit import CONFIG, Drive, state_of


def _busy_session(db: str | Storage, drive: Drive) -> Session:
    """A session with a bit of everything: answers, undo, exclusion, notes, pause, validation."""
    s = Session.create(db, CONFIG, "S01", seed=11)
    drive(s, 6)
    s.undo()
    drive(s, 3)
    s.exclude(4, "device_fault", "motor current limit")
    s.note("subject asked for water")
    s.pause()
    s.resume()
    plan = s.start_validation()
    s.answer_validation(plan.round, "CAB")
    drive(s, 3)
    return s


def test_reopening_gives_the_same_state(db: str | Storage, drive: Drive) -> None:
    s = _busy_session(db, drive)
    mean, var, query, rng = state_of(s)
    again = Session.open(db, s.id)
    mean2, var2, query2, rng2 = state_of(again)
    np.testing.assert_allclose(mean2, mean, rtol=0, atol=1e-12)
    np.testing.assert_allclose(var2, var, rtol=0, atol=1e-12)
    assert query2 == query and rng2 == rng
    assert again.trials(include_undone=True) == s.trials(include_undone=True)
    assert again.comparisons() == s.comparisons() and again.suggestions() == s.suggestions()
    assert again.validations() == s.validations() and again.notes() == s.notes()
    assert again.last_seq == s.last_seq == len(s.events())


def test_replay_equals_the_live_session_at_every_step(sqlite_url: str, drive: Drive) -> None:
    s = Session.create(sqlite_url, CONFIG, "S01", seed=2)
    for _ in range(5):
        drive(s, 1)
        reopened = Session.open(sqlite_url, s.id)
        np.testing.assert_array_equal(reopened.posterior().mean, s.posterior().mean)
        assert reopened.next_query() == s.next_query()


def _tamper(path: Path, text: str) -> None:
    """Another config in the row, and (so that the row still matches it) in the created event:
    what replay's re-derived proposals must catch."""
    import hashlib

    sha = hashlib.sha256(text.encode()).hexdigest()
    with sqlite3.connect(path) as raw:
        old = raw.execute("SELECT config_sha256 FROM sessions").fetchone()[0]
        raw.execute("UPDATE sessions SET config_text = ?, config_sha256 = ?", (text, sha))
        raw.execute("DROP TRIGGER events_no_update")
        raw.execute(
            "UPDATE events SET payload = replace(payload, ?, ?) WHERE kind = 'created'", (old, sha)
        )


def test_a_changed_config_stops_replay_and_shows_the_difference(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    s = Session.create(sqlite_url, CONFIG, "S01", seed=3)
    drive(s, 6)
    s.close()
    text = load_config(CONFIG).text.replace("lengthscale = { step_length = 0.03 }",
                                            "lengthscale = { step_length = 0.003 }")  # fmt: skip
    _tamper(tmp_path / "sessions.db", text)
    with pytest.raises(ReplayError) as err:
        Session.open(sqlite_url, s.id)
    message = str(err.value)
    assert "log has" in message and "replay gives" in message
    assert "stopped instead of going on" in message


def test_opening_with_another_config_shows_a_diff(sqlite_url: str, tmp_path: Path) -> None:
    s = Session.create(sqlite_url, CONFIG, "S01")
    other = tmp_path / "changed.toml"
    other.write_text(load_config(CONFIG).text.replace("noise = 0.02", "noise = 0.05"))
    with pytest.raises(ReplayError, match=r"(?s)-noise = 0.02.*\+noise = 0.05"):
        Session.open(sqlite_url, s.id, config=other)
    assert Session.open(sqlite_url, s.id, config=CONFIG).id == s.id


def test_other_numerics_stop_replay_naming_both_versions(
    sqlite_url: str, drive: Drive, monkeypatch: pytest.MonkeyPatch
) -> None:
    s = Session.create(sqlite_url, CONFIG, "S01", seed=5)
    drive(s, 4)
    monkeypatch.setattr(gaitpref.sessions.session, "software_version", lambda: "9.9.9")
    monkeypatch.setattr(  # numerics that propose other actions
        Posterior,
        "argmax_samples",
        lambda self, rng, size, allowed=None: np.full(size, np.argmin(self.mean)),
    )
    with pytest.raises(ReplayError, match=r"(?s)query_issued.*actions.*gaitpref 0\.1\.0.*9\.9\.9"):
        Session.open(sqlite_url, s.id)


def test_an_altered_config_text_is_detected(tmp_path: Path, sqlite_url: str) -> None:
    s = Session.create(sqlite_url, CONFIG, "S01")
    with sqlite3.connect(tmp_path / "sessions.db") as raw:
        raw.execute("UPDATE sessions SET config_text = config_text || '# edited'")
    with pytest.raises(ReplayError, match="does not match its hash"):
        Session.open(sqlite_url, s.id)


def _edit_row(path: Path, sql: str, *args: object) -> None:
    with sqlite3.connect(path) as raw:
        raw.execute(sql, args)


@pytest.mark.parametrize(
    ("sql", "args", "named"),
    [
        ("UPDATE sessions SET subject = ?", ("S02",), "subject is 'S02' in the row, 'S01'"),
        ("UPDATE sessions SET seed = ?", (12,), "seed is 12 in the row, 11 in the event"),
        ("UPDATE sessions SET software_version = ?", ("0.0.9",), "software_version is '0.0.9'"),
        ("UPDATE sessions SET config_name = ?", ("other",), "config_name is 'other' in the row"),
        ("UPDATE sessions SET meta = ?", ('{"gait_ids": ["a"]}',), "meta.gait_ids names a gait"),
        ("UPDATE sessions SET meta = ?", ('{"prior_rho": 0.5}',), "meta.prior_rho is 0.5"),
    ],
)
def test_a_row_that_disagrees_with_its_created_event_is_named(
    tmp_path: Path, sqlite_url: str, drive: Drive, sql: str, args: tuple[object], named: str
) -> None:
    """Replay read seed, config and warm start from the row and never compared it with the
    created event: an edited subject, version or name went unnoticed, an edited seed surfaced
    as 'event 2 (query_issued): actions ...'."""
    s = Session.create(sqlite_url, CONFIG, "S01", seed=11)
    drive(s, 3)
    s.close()
    subject = "S02" if "subject" in sql else "S01"
    if subject == "S02":
        _edit_row(tmp_path / "sessions.db", "INSERT INTO subjects (code, created_at) "
                  "SELECT 'S02', created_at FROM subjects WHERE code = 'S01'")  # fmt: skip
    _edit_row(tmp_path / "sessions.db", sql, *args)
    with pytest.raises(ReplayError) as err:
        Session.open(sqlite_url, s.id)
    message = str(err.value)
    assert "its row does not match its created event (event 1)" in message
    assert named in message and "altered" in message


def test_an_altered_row_alone_is_named_before_replay_derives_anything(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    """Another config in the row only (text and hash agreeing): the created event names the
    config the session was made with."""
    import hashlib

    s = Session.create(sqlite_url, CONFIG, "S01", seed=3)
    drive(s, 2)
    s.close()
    text = load_config(CONFIG).text.replace("noise = 0.02", "noise = 0.05")
    sha = hashlib.sha256(text.encode()).hexdigest()
    _edit_row(tmp_path / "sessions.db",
              "UPDATE sessions SET config_text = ?, config_sha256 = ?", text, sha)  # fmt: skip
    with pytest.raises(ReplayError, match=f"config_sha256 is '{sha}' in the row"):
        Session.open(sqlite_url, s.id)


def test_a_log_that_does_not_start_with_created_is_refused(drive: Drive) -> None:
    from gaitpref.storage import MemoryStorage, NewEvent
    from tests.sessions.gaitkit import copied

    db = MemoryStorage()
    s = Session.create(db, CONFIG, "S01", seed=3)
    drive(s, 1)
    dropped = copied(db, s.id, lambda e: NewEvent("note", {"text": "x"}) if e.seq == 1 else None)
    with pytest.raises(ReplayError, match="starts with its 'created' event"):
        Session.open(db, dropped)
