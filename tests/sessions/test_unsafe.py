"""The operator's "unsafe" flag: logged with its reason, replayed, withdrawn; the flagged gait
and its neighbourhood are never proposed again, and a pending query that proposes one is
withdrawn before anyone walks it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitpref import Session, SessionStateError
from gaitpref.config import parse_config
from gaitpref.loop.safety import near

CONFIG = """
name = "unsafe-1d"
[space.step_length]
min = 0.08
max = 0.18
num = 15
[model]
lengthscale = 0.03
signal_variance = 0.005
noise = 0.02
jitter = 0.0
fit = "fixed"
[cospar]
seed = 1
strategy = "self-sparring"
[safety]
unsafe_radius = 0.15
"""


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
        if not near(s.config.space, {trial.action}, 0.15)[q.actions[0]]:
            pytest.skip("this seed's pending query is far from the flagged gait")
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
