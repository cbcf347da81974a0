"""Withdrawing an open blind validation round (``validation_withdrawn``), and who opened a round
(``validation_started`` version 3's ``opened_by``): live, replayed and refused."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from gaitpref import Session, SessionStateError
from gaitpref.config import ExperimentConfig, load_config, parse_config
from gaitpref.sessions import export_session, import_session
from gaitpref.sessions.demo import SimulatedSubject
from gaitpref.storage import MemoryStorage, Storage
from gaitpref.storage.sql import upgrade_database
from tests.sessions.sessionkit import CONFIG, Drive

FIXTURES = Path(__file__).resolve().parent.parent / "fixtures"


def _config(stop: str) -> ExperimentConfig:
    return parse_config(load_config(CONFIG).text + "\n[stop]\n" + stop, default_name=CONFIG)


def _same(a: Session, b: Session) -> None:
    """Two sessions in the same state, as the apps see it."""
    assert np.array_equal(a.posterior().mean, b.posterior().mean)
    assert np.array_equal(a.posterior().variance, b.posterior().variance)
    assert a._state.loop.rng.bit_generator.state == b._state.loop.rng.bit_generator.state
    assert a.validation_rounds() == b.validation_rounds()
    assert a.validation_plan == b.validation_plan
    assert a.pending == b.pending
    assert a.trials(include_undone=True) == b.trials(include_undone=True)
    assert a.comparisons() == b.comparisons()


def _ruled(db: str | Storage, drive: Drive) -> Session:
    """A session whose ``[stop]`` rule has just opened round 1 after an answer."""
    s = Session.create(db, _config("max_trials = 4\n"), "S01")
    drive(s, 4)
    assert s.validation_plan is not None
    return s


def test_opened_by_is_recorded_for_the_rule_and_the_operator(
    db: str | Storage, drive: Drive
) -> None:
    s = _ruled(db, drive)
    started = s.events()[-1]
    assert (started.kind, started.version) == ("validation_started", 3)
    assert started.payload["opened_by"] == "rule"
    last_answered = s.trials()[-1].query
    (info,) = s.validation_rounds()
    assert (info.round, info.opened_by, info.opened_after, info.open) == (
        1, "rule", last_answered, True
    )  # fmt: skip
    s.answer_validation(1, "ABC")
    drive(s, 1)
    plan = s.start_validation()
    assert plan.round == 2 and s.events()[-1].payload["opened_by"] == "operator"
    assert [(r.opened_by, r.opened_after, r.answered) for r in s.validation_rounds()] == [
        ("rule", last_answered, True),
        ("operator", None, False),
    ]
    _same(s, Session.open(db, s.id))


def test_withdraw_then_replay_equals_live_state(db: str | Storage, drive: Drive) -> None:
    s = Session.create(db, CONFIG, "S01", seed=3)
    drive(s, 6)
    plan = s.start_validation()
    pending = s.withdraw_validation(plan.round, "the subject felt unwell")
    assert pending is None and s.validation_plan is None  # no query was pending
    withdrawn = s.events()[-1]
    assert (withdrawn.kind, withdrawn.version) == ("validation_withdrawn", 1)
    assert withdrawn.payload == {"round": 1, "reason": "the subject felt unwell"}
    (info,) = s.validation_rounds()
    assert (info.withdrawn, info.withdrawn_seq, info.answered, info.open) == (
        "the subject felt unwell", withdrawn.seq, False, False
    )  # fmt: skip
    assert s.validations() == []
    drive(s, 2)  # queries and answers go on
    again = s.start_validation()
    assert again.round == 2  # the next number: round 1 stays in the log, withdrawn
    s.answer_validation(2, "BCA")
    _same(s, Session.open(db, s.id))


def test_a_withdrawn_round_exports_and_imports_as_logged(tmp_path: Path, drive: Drive) -> None:
    with Session.create(MemoryStorage(), CONFIG, "S01", seed=3) as s:
        drive(s, 6)
        s.withdraw_validation(s.start_validation().round, "unwell")
        drive(s, 1)
        s.answer_validation(s.start_validation().round, "ABC")
        export_session(s, tmp_path / "out")
        with import_session(f"sqlite:///{tmp_path / 'copy.db'}", tmp_path / "out") as copy:
            _same(copy, s)
            assert [(e.kind, e.version, e.payload) for e in copy.events()] == [
                (e.kind, e.version, e.payload) for e in s.events()
            ]
    with (tmp_path / "out" / "validation.csv").open(newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert {(r["round"], r["opened_by"]) for r in rows} == {("2", "operator")}  # 1 withdrawn


def test_withdraw_with_undo_takes_back_the_answer_that_opened_the_round(
    db: str | Storage, drive: Drive, subject: SimulatedSubject
) -> None:
    s = _ruled(db, drive)
    last = s.trials()[-1]
    before = len(s.trials())
    pending = s.withdraw_validation(1, "mis-keyed answer", undo=True)
    assert pending is not None and pending.id == last.query  # asked again
    kinds = [e.kind for e in s.events()[-2:]]
    assert kinds == ["validation_withdrawn", "undo"]
    assert len(s.trials()) == before - len(pending.trials)
    _same(s, Session.open(db, s.id))
    # answered again, the rule opens a round again: the withdrawn one does not count
    answered = s.answer(pending.id, *subject.respond(pending))
    assert answered.stopped is not None and s.validation_plan is not None
    assert s.validation_plan.round == 2
    assert s.events()[-1].payload["opened_by"] == "rule"
    # and `session undo` after a withdrawal undoes answers as always; the round stays withdrawn
    s.withdraw_validation(2, "again")
    s.undo()
    assert [r.withdrawn for r in s.validation_rounds()] == ["mis-keyed answer", "again"]
    assert s.validation_plan is None
    _same(s, Session.open(db, s.id))


def test_withdrawing_an_answered_or_missing_round_is_refused_naming_it(drive: Drive) -> None:
    db = MemoryStorage()
    s = Session.create(db, CONFIG, "S01", seed=3)
    drive(s, 5)
    with pytest.raises(
        SessionStateError, match=r"round 1 is not open: it was never started \(none"
    ):
        s.withdraw_validation(1, "why")
    s.start_validation()
    seq = s.last_seq
    for bad in ("", "   ", "x" * 2001):
        with pytest.raises(ValueError, match="needs a reason"):
            s.withdraw_validation(1, bad)
    with pytest.raises(ValueError, match="control character"):
        s.withdraw_validation(1, "bad\x1b[2J")
    with pytest.raises(SessionStateError, match=r"never started \(round 1 is open"):
        s.withdraw_validation(2, "why")
    # True == 1, but it is no round number (it said "it was withdrawn (round 1 is open)")
    with pytest.raises(SessionStateError, match="True is not open: a round is a whole number"):
        s.withdraw_validation(True, "why")
    with pytest.raises(SessionStateError, match="opened by the operator, not by the \\[stop\\]"):
        s.withdraw_validation(1, "why", undo=True)
    with pytest.raises(SessionStateError, match="opened by the operator"):
        s.check_withdraw_validation(1, undo=True)
    s.check_withdraw_validation(1)  # would be taken
    assert s.last_seq == seq  # nothing written by the refusals
    s.answer_validation(1, "ABC")
    with pytest.raises(SessionStateError, match="round 1 is not open: it is already answered"):
        s.withdraw_validation(1, "too late")
    drive(s, 1)
    s.start_validation()
    s.withdraw_validation(2, "once")
    with pytest.raises(SessionStateError, match="round 2 is not open: it was withdrawn"):
        s.withdraw_validation(2, "twice")
    with pytest.raises(
        SessionStateError, match=r"round 2 is not open: it was withdrawn.*no ranking"
    ):
        s.answer_validation(2, "ABC")
    s.finish()
    with pytest.raises(SessionStateError, match="finished"):
        s.withdraw_validation(2, "after")


def test_withdraw_with_undo_refused_when_the_opening_answer_is_not_the_last(
    drive: Drive,
) -> None:
    db = MemoryStorage()
    s = _ruled(db, drive)
    s.undo()  # the round stays open; the answer that opened it is gone
    seq = s.last_seq
    with pytest.raises(SessionStateError, match="no longer the last answer in force"):
        s.withdraw_validation(1, "mis-keyed", undo=True)
    assert s.last_seq == seq
    s.withdraw_validation(1, "mis-keyed")  # without undo it is taken
    assert s.validation_plan is None and s.pending is not None


def test_a_0_1_0_round_replays_and_exports_with_opened_by_empty(tmp_path: Path) -> None:
    """The 0.1.0 fixture's round (``validation_started`` version 1) replays as recorded and
    exports with ``opened_by`` empty (null in JSON), the other columns as before."""
    path = tmp_path / "old.db"
    shutil.copy(FIXTURES / "gaitpref-0.1.0.db", path)
    url = f"sqlite:///{path}"
    upgrade_database(url)
    with Session.open(url, 1) as s:
        (started,) = [e for e in s.events() if e.kind == "validation_started"]
        assert started.version == 1 and "opened_by" not in started.payload
        (info,) = s.validation_rounds()
        assert (info.opened_by, info.opened_after, info.answered) == (None, None, True)
        assert [r.agrees for r in s.validations()] == [False]  # as 0.1.0 recorded it
        export_session(s, tmp_path / "csv", "csv")
        export_session(s, tmp_path / "json", "json")
    with (tmp_path / "csv" / "validation.csv").open(newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 3 and all(r["opened_by"] == "" for r in rows)
    assert list(rows[0])[-3:] == ["agrees", "kendall_tau", "opened_by"]  # old columns kept
    listed = json.loads((tmp_path / "json" / "validation.json").read_text(encoding="utf-8"))
    assert [r["opened_by"] for r in listed] == [None, None, None]


def test_a_new_round_exports_who_opened_it(tmp_path: Path, drive: Drive) -> None:
    with Session.create(MemoryStorage(), _config("max_trials = 4\n"), "S01") as s:
        drive(s, 4)
        s.answer_validation(1, "ABC")
        drive(s, 1)
        s.answer_validation(s.start_validation().round, "CBA")
        export_session(s, tmp_path / "csv", "csv")
    with (tmp_path / "csv" / "validation.csv").open(newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert [(r["round"], r["opened_by"]) for r in rows] == [
        ("1", "rule"), ("1", "rule"), ("1", "rule"),
        ("2", "operator"), ("2", "operator"), ("2", "operator"),
    ]  # fmt: skip
