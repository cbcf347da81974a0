"""The operator's "unsafe" flag: logged with its reason, replayed, withdrawn; the flagged gait
and its neighbourhood are never proposed again, and a pending query that proposes one is
withdrawn before anyone walks it."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gaitpref import Session, SessionStateError
from gaitpref.config import parse_config
from gaitpref.loop.safety import near
from tests.sessions.unsafekit import unsafe_config

CONFIG = unsafe_config("unsafe-1d", 0.15)


def _answer(s: Session, k: int) -> None:
    q = s.next_query()
    a = q.actions[0]
    s.answer(
        q.id,
        [(a, q.buffer[0], "first" if k % 2 else "second")] if q.buffer and q.buffer[0] != a else [],
    )


def test_flag_replay_withdraw(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'u.db'}"
    cfg = parse_config(CONFIG)
    with Session.create(url, cfg, "S01") as s:
        for k in range(4):
            _answer(s, k)
        flagged = s.trials()[1].action
        s.flag_unsafe(2, "knee hyperextension")
        assert s.unsafe_flags() == {2: (flagged, "knee hyperextension")}
        banned = near(cfg.space, {flagged}, 0.15)
        assert 1 < banned.sum() < len(cfg.space)
        proposed = []
        for k in range(12):
            proposed += list(s.next_query().actions)
            _answer(s, k)
        assert not any(banned[a] for a in proposed)
        with pytest.raises(SessionStateError, match="already flagged"):
            s.flag_unsafe(2, "again")
        mean = np.asarray(s.posterior().mean).copy()
        pending = s.pending
        sid = s.id
    with Session.open(url, sid) as again:
        assert np.array_equal(np.asarray(again.posterior().mean), mean)
        assert again.pending == pending and again.unsafe_flags() == {
            2: (flagged, "knee hyperextension")
        }
        again.withdraw_unsafe(2)
        assert again.unsafe_flags() == {}
        with pytest.raises(SessionStateError, match="not flagged"):
            again.withdraw_unsafe(2)
    with Session.open(url, sid) as third:
        assert third.unsafe_flags() == {}


def test_a_pending_query_near_the_flag_is_withdrawn(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'u.db'}"
    with Session.create(url, parse_config(CONFIG), "S01") as s:
        _answer(s, 0)
        q = s.next_query()
        trial = s.trials()[0]
        assert near(s.config.space, {trial.action}, 0.15)[q.actions[0]]  # seed 1: the case
        s.flag_unsafe(trial.number, "stumbled")
        assert s.pending is None
        q2 = s.next_query()
        assert q2.id != q.id
        assert not near(s.config.space, {trial.action}, 0.15)[q2.actions[0]]


def test_undo_waits_for_the_flag_and_reasons_are_required(tmp_path: Path) -> None:
    with Session.create(f"sqlite:///{tmp_path / 'u.db'}", parse_config(CONFIG), "S01") as s:
        _answer(s, 0)
        with pytest.raises(ValueError, match="reason"):
            s.flag_unsafe(1, " ")
        with pytest.raises(SessionStateError, match="no trial 7"):
            s.flag_unsafe(7, "why")
        s.flag_unsafe(1, "pain")
        with pytest.raises(SessionStateError, match="withdraw the flag"):
            s.undo()
        s.withdraw_unsafe(1)
        s.undo()


def test_exports_name_gaits_and_mark_unsafe_trials(tmp_path: Path) -> None:
    import csv

    from gaitpref.sessions import export_session

    with Session.create(f"sqlite:///{tmp_path / 'u.db'}", parse_config(CONFIG), "S01") as s:
        for k in range(3):
            _answer(s, k)
        s.flag_unsafe(2, "knee hyperextension")
        export_session(s, tmp_path / "out")
        actions = [t.action for t in s.trials()]
    with (tmp_path / "out" / "trials.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [r["gait"] for r in rows] == [f"G{a}" for a in actions]
    assert [r["unsafe"] for r in rows] == ["false", "true", "false"]
    assert rows[1]["unsafe_reason"] == "knee hyperextension"
    with (tmp_path / "out" / "comparisons.csv").open() as f:
        first = next(csv.DictReader(f))
    assert first["first_gait"] == f"G{first['first_action']}"


def test_an_undone_trial_is_not_marked_with_the_flag_of_its_number_walked_again(
    tmp_path: Path,
) -> None:
    """Trial numbers are reused after an undo: the flag of the trial walked again marked the
    undone trial of that number unsafe too, with the same reason, in the export's trials."""
    import csv

    from gaitpref.sessions import export_session

    with Session.create(f"sqlite:///{tmp_path / 'u.db'}", parse_config(CONFIG), "S01") as s:
        for k in range(2):
            _answer(s, k)
        s.undo()
        _answer(s, 1)
        s.flag_unsafe(2, "knee hyperextension")
        export_session(s, tmp_path / "out")
    with (tmp_path / "out" / "trials.csv").open() as f:
        rows = [
            (r["trial"], r["undone"], r["unsafe"], r["unsafe_reason"]) for r in csv.DictReader(f)
        ]
    assert rows == [
        ("1", "false", "false", ""),
        ("2", "true", "false", ""),
        ("2", "false", "true", "knee hyperextension"),
    ]


def _flag_then_undo(url: str, pause: bool) -> tuple[Session, int]:
    """Seed 1 runs gaits 6 then 8 (within the flag's radius of 6); flag trial 1, then undo
    trial 2's answer (optionally paused first)."""
    s = Session.create(url, parse_config(CONFIG), "S01")
    _answer(s, 0)
    _answer(s, 1)
    first, second = (t.action for t in s.trials())
    assert near(s.config.space, {first}, 0.15)[second]  # the case under test
    s.next_query()
    s.flag_unsafe(1, "ankle pain")
    if pause:
        s.pause()
    return s, first


def test_an_undo_withdraws_its_query_when_it_proposes_a_gait_flagged_since(
    tmp_path: Path,
) -> None:
    url = f"sqlite:///{tmp_path / 'u.db'}"
    s, first = _flag_then_undo(url, pause=False)
    undone = s.undo()
    assert undone is not None and s.pending == undone and undone.trials == (2,)
    banned = near(s.config.space, {first}, 0.15)
    assert not any(banned[a] for a in undone.actions)
    mean = np.asarray(s.posterior().mean).copy()
    s.close()
    with Session.open(url, s.id) as again:  # the replay derives the same withdrawal
        assert again.pending == undone
        assert np.array_equal(np.asarray(again.posterior().mean), mean)
        again.answer(undone.id, [])
        assert [t.action for t in again.trials()][1] == undone.actions[0]


def test_an_undo_while_paused_proposes_nothing_until_resumed(tmp_path: Path) -> None:
    s, first = _flag_then_undo(f"sqlite:///{tmp_path / 'u.db'}", pause=True)
    with s:
        assert s.undo() is None and s.pending is None
        s.resume()
        q = s.next_query()
        assert not near(s.config.space, {first}, 0.15)[q.actions[0]]


def _flag_near_the_best(s: Session) -> tuple[np.ndarray, tuple[int, int, int]]:
    """Six answers, then flag the trial nearest the posterior's max: what every gait's rule
    would show (max, mean, min) and the gaits the flag bans."""
    from gaitpref.sessions.validation import validation_actions

    for k in range(6):
        _answer(s, k)
    shown = validation_actions(np.asarray(s.posterior().mean))
    trial = min(s.trials(), key=lambda t: abs(t.action - shown[0]))
    banned = near(s.config.space, {trial.action}, 0.15)
    assert banned[shown[0]]  # the case under test: the max is within the flag's radius
    s.flag_unsafe(trial.number, "hip pain")
    return banned, shown


def test_blind_validation_never_shows_a_gait_near_an_unsafe_flag(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'u.db'}"
    with Session.create(url, parse_config(CONFIG), "S01") as s:
        banned, _ = _flag_near_the_best(s)
        plan = s.start_validation()
        assert not any(banned[g.action] for g in plan.gaits)
        mean = np.asarray(s.posterior().mean)
        allowed = np.flatnonzero(~banned)
        assert {g.action for g in plan.gaits} >= {int(allowed[np.argmax(mean[allowed])])}
        sid = s.id
    with Session.open(url, sid) as again:
        assert again.validation_plan == plan


def test_a_round_logged_as_version_1_replays_by_its_own_rule(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Rounds logged before payload version 2 chose among every gait; they replay so."""
    from gaitpref.sessions import events

    url = f"sqlite:///{tmp_path / 'u.db'}"
    with Session.create(url, parse_config(CONFIG), "S01") as s:
        banned, shown = _flag_near_the_best(s)
        monkeypatch.setattr(events.ValidationStarted, "version", 1)
        plan = s.start_validation()
        monkeypatch.undo()
        assert sorted(g.action for g in plan.gaits) == sorted(shown)
        assert any(banned[g.action] for g in plan.gaits)  # as version 1 chose
        sid = s.id
    with Session.open(url, sid) as again:
        assert again.validation_plan == plan
        assert [e.version for e in again.events() if e.kind == "validation_started"] == [1]


def test_a_flag_on_a_gait_the_open_round_shows_draws_the_round_again(tmp_path: Path) -> None:
    """The stop rule opens a round right after an answer, before the operator can flag that
    trial (the terminal's "write and flag unsafe"): the flag withdraws the round, and it is
    drawn again among the gaits still allowed, in replay too."""
    url = f"sqlite:///{tmp_path / 'u.db'}"
    with Session.create(url, parse_config(CONFIG + "[stop]\nmax_trials = 6\n"), "S01") as s:
        for k in range(6):
            _answer(s, k)
        first = s.validation_plan
        assert first is not None  # opened by the stop rule
        shown = {g.action for g in first.gaits}
        space = s.config.space
        trial = next(t for t in s.trials() if near(space, {t.action}, 0.15)[list(shown)].any())
        assert s.flag_unsafe(trial.number, "knee") is True
        again = s.validation_plan
        banned = near(s.config.space, {trial.action}, 0.15)
        assert again is not None and again.round == first.round
        assert not any(banned[g.action] for g in again.gaits)
        kinds = [e.kind for e in s.events()][-3:]
        assert kinds == ["validation_started", "trial_flagged_unsafe", "validation_started"]
        # drawn again, the round keeps who opened it: the rule
        opened = [e.payload["opened_by"] for e in s.events() if e.kind == "validation_started"]
        assert opened == ["rule", "rule"]
        assert [r.opened_by for r in s.validation_rounds()] == ["rule"]
        plan, sid = s.validation_plan, s.id
    with Session.open(url, sid) as reopened:
        assert reopened.validation_plan == plan


def test_a_ranking_of_the_gaits_a_redrawn_round_showed_before_is_refused(tmp_path: Path) -> None:
    """``answer_validation(..., shown=...)``: the ranking is of the gaits the subject walked;
    a round drawn again since (a flag from another writer) is not ranked with it."""
    url = f"sqlite:///{tmp_path / 'u.db'}"
    with Session.create(url, parse_config(CONFIG + "[stop]\nmax_trials = 6\n"), "S01") as s:
        for k in range(6):
            _answer(s, k)
        walked = [g.gait for g in s.validation_gaits()]
        shown = {g.action for g in s.validation_gaits()}
        space = s.config.space
        trial = next(t for t in s.trials() if near(space, {t.action}, 0.15)[list(shown)].any())
        with Session.open(url, s.id) as other:
            assert other.flag_unsafe(trial.number, "knee") is True
        before = len(s.events())
        with pytest.raises(SessionStateError, match="round 1 was drawn again") as err:
            s.answer_validation(1, "ABC", shown=walked)
        now = [g.gait for g in s.validation_gaits()]
        assert f"now shows {', '.join(now)}, not {', '.join(walked)}" in str(err.value)
        assert len(s.events()) == before and s.validations() == []
        assert s.answer_validation(1, "ABC", shown=now).round == 1


def test_a_round_drawn_again_keeps_the_answer_that_opened_it(tmp_path: Path) -> None:
    """The rule opens round 1 after the last answer; that answer is undone (the round stays
    open), then a flag draws the round again.  The redrawn round was still opened by the
    undone answer, not by the one now last: withdrawing it with undo is refused, and takes
    back no answer that did not open it (it undid the earlier answer), live and replayed."""
    url = f"sqlite:///{tmp_path / 'u.db'}"
    with Session.create(url, parse_config(CONFIG + "[stop]\nmax_trials = 6\n"), "S01") as s:
        for k in range(6):
            _answer(s, k)
        first = s.validation_plan
        assert first is not None  # opened by the stop rule
        opener = s.trials()[-1].query
        s.undo(query=opener)
        assert s.validation_plan == first  # still open
        shown = {g.action for g in first.gaits}
        space = s.config.space
        trial = next(t for t in s.trials() if near(space, {t.action}, 0.15)[list(shown)].any())
        assert s.trials()[-1].query != trial.query  # the last answer stays undoable
        assert s.flag_unsafe(trial.number, "knee") is True
        assert [r.opened_after for r in s.validation_rounds()] == [opener]
        seq = s.last_seq
        with pytest.raises(SessionStateError, match="no longer the last answer in force"):
            s.withdraw_validation(1, "mis-keyed", undo=True)
        assert s.last_seq == seq
        sid = s.id
    with Session.open(url, sid) as again:
        assert [r.opened_after for r in again.validation_rounds()] == [opener]


def test_an_undo_whose_new_query_another_writer_keeps_from_being_written_says_it_stands(
    tmp_path: Path,
) -> None:
    """The undo is written; the query in place of its withdrawn one loses the compare-and-set
    twice (another writer kept appending): the SessionBusyError says the undo is written and
    the query not (it said 'nothing was written, try again', and the CLI and console, which
    read it as nothing written, said so too)."""
    from gaitpref.storage import ConflictError, SessionBusyError

    url = f"sqlite:///{tmp_path / 'u.db'}"
    s, _ = _flag_then_undo(url, pause=False)
    append = s.storage.append

    def conflicting(*args: Any, **kwargs: Any) -> Any:
        if any(e.kind == "query_issued" for e in args[2]):
            raise ConflictError("another writer appended first")
        return append(*args, **kwargs)

    s.storage.append = conflicting  # type: ignore[method-assign]
    with pytest.raises(SessionBusyError, match=r"^the undo is written; the query drawn in place"):
        s.undo()
    s.close()
    with Session.open(url, 1) as again:
        assert [t.number for t in again.trials()] == [1] and again.pending is None
