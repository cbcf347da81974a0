"""Gaits made on demand in a session: an infeasible gait never reaches the subject; it is logged
with its reason, its neighbourhood is avoided and the next proposal is made; replay reproduces
both, from the gait cache or the log (a log written before it carried the gaits: by making them
again; ``test_gaits_on_demand_log.py``)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from gaitpref import ReplayError, Session
from gaitpref.config import DEFAULTS_VERSION, parse_config
from gaitpref.gaits import CompassHZD, make_generator
from gaitpref.loop.safety import near
from tests.sessions.gaitkit import (
    COMPASS,
    CONFIG,
    CONTINUOUS,
    FakeSteps,
    logged_as_version_1,
    never_made,
    prefer_short_steps,
)


def _run(url: str, queries: int) -> Session:
    """A subject who prefers short steps: drives the loop towards the infeasible ones."""
    s = Session.create(url, parse_config(CONFIG), subject="S01")
    space = s.config.space
    for _ in range(queries):
        q = s.next_query()
        a = q.actions[0]
        b = q.buffer[0] if q.buffer else None
        if b is None or b == a:
            s.answer(q.id, [])
            continue
        shorter = space.values_of(a)["step_length"] < space.values_of(b)["step_length"]
        s.answer(q.id, [(a, b, "first" if shorter else "second")])
    return s


def _lengths(s: Session, actions: list[int]) -> list[float]:
    return [s.config.space.values_of(a)["step_length"] for a in actions]


def test_an_infeasible_gait_is_logged_avoided_and_never_walked(tmp_path: Path) -> None:
    s = _run(f"sqlite:///{tmp_path / 'lab.db'}", 12)
    infeasible = s.infeasible_gaits()
    assert infeasible, "the subject's preference for short steps reaches the infeasible ones"
    # nothing the subject walked, and nothing any query proposed, is infeasible
    walked = [t.action for t in s.trials()]
    assert min(_lengths(s, walked)) >= FakeSteps.below
    events = s.events()
    kinds = [e.kind for e in events]
    for e in events:
        if e.kind == "query_issued":
            assert min(_lengths(s, e.payload["actions"])) >= FakeSteps.below
    # each infeasible proposal: its reason, the same batch's next proposal is made, and the
    # neighbourhood is never proposed afterwards
    space = s.config.space
    for bad in infeasible:
        k = next(i for i, e in enumerate(events) if e.seq == bad.seq)
        assert "too short" in bad.reason and bad.gait_id == s.gait_name(bad.action)
        assert events[k].payload["radius"] == 0.1
        nxt = kinds.index("query_issued", k)
        assert all(kinds[j] in ("gait_made", "gait_infeasible") for j in range(k, nxt))
        banned = near(space, [bad.action], 0.1)
        later = [a for e in events[nxt:] if e.kind == "query_issued" for a in e.payload["actions"]]
        assert not any(banned[a] for a in later)
    # the gait id is shown and logged as with a library
    trial_events = [e for e in events if e.kind == "trial_executed"]
    assert all(e.payload["gait_id"] == s.gait_name(e.payload["action"]) for e in trial_events)
    assert trial_events[0].payload["gait_id"].startswith("S")  # the fake's id: S<length>-S<width>


def test_replay_reproduces_infeasible_proposals_from_the_cache_and_from_the_log(
    tmp_path: Path,
) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = _run(url, 10)
    before = (s.trials(), s.infeasible_gaits(), s.pending, [e.kind for e in s.events()])
    made = len(FakeSteps.calls)
    assert made > 0 and (tmp_path / "lab.db.gaits").is_dir()
    assert len(list((tmp_path / "lab.db.gaits").glob("*.json"))) == made
    # from the cache: nothing is made again
    again = Session.open(url, s.id)
    assert len(FakeSteps.calls) == made
    assert (again.trials(), again.infeasible_gaits(), again.pending) == before[:3]
    # without it: the log carries every gait, so nothing is made either
    shutil.rmtree(tmp_path / "lab.db.gaits")
    rebuilt = Session.open(url, s.id)
    assert len(FakeSteps.calls) == made
    assert (rebuilt.trials(), rebuilt.infeasible_gaits(), rebuilt.pending) == before[:3]
    # and the session goes on as it would have
    q1, q2 = again.next_query(), rebuilt.next_query()
    assert (q1.id, q1.actions) == (q2.id, q2.actions)


def test_replay_refuses_a_generator_that_now_decides_otherwise(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = _run(url, 10)
    assert s.infeasible_gaits()
    old = logged_as_version_1(s.storage, s.id)  # gaits made again on replay: by the new rule
    shutil.rmtree(tmp_path / "lab.db.gaits")
    FakeSteps.below = 0.0  # every gait is feasible now (and its keys differ)
    for session_id in (s.id, old):
        with pytest.raises(ReplayError, match=r"gait_infeasible|gait_made|key"):
            Session.open(url, session_id)


def test_warm_starts_come_from_the_nearest_feasible_gait_made_before(tmp_path: Path) -> None:
    s = _run(f"sqlite:///{tmp_path / 'lab.db'}", 12)
    space = s.config.space
    lo, span = space.points.min(axis=0), np.ptp(space.points, axis=0)
    feasible: list[tuple[str, np.ndarray]] = []  # (key, scaled point), in the order made
    seen: set[str] = set()
    checked = 0
    for e in s.events():
        if e.kind not in ("gait_made", "gait_infeasible"):
            continue
        p = e.payload
        x = (space.point(p["action"]) - lo) / span
        if p["key"] not in seen:  # made here, not found in the cache under a width label
            if not feasible:
                assert p["warm_start"] is None
            else:
                d = [(k, float(np.sum((v - x) ** 2))) for k, v in feasible]
                from_warm = [dk for k, dk in d if k == p["warm_start"]]
                assert from_warm and min(from_warm) == pytest.approx(min(dk for _, dk in d))
                checked += 1
        seen.add(p["key"])
        if e.kind == "gait_made":
            feasible.append((p["key"], x))
    assert checked >= 3
    # and the generator was handed those gaits
    assert [w is None for _, w in FakeSteps.calls][:1] == [True]
    assert all(w is not None and w >= FakeSteps.below for _, w in FakeSteps.calls[1:])


def test_a_width_label_shares_its_gait_and_its_cache_entry(tmp_path: Path) -> None:
    s = _run(f"sqlite:///{tmp_path / 'lab.db'}", 12)
    logged = [e.payload for e in s.events() if e.kind in ("gait_made", "gait_infeasible")]
    by_key: dict[str, set[str]] = {}
    for p in logged:
        by_key.setdefault(p["key"], set()).add(p["gait_id"])
    lengths = {round(p["values"]["step_length"], 9) for p in logged}
    assert len(by_key) == len(lengths)  # one key per step length, whatever the width
    assert len({length for length, _ in FakeSteps.calls}) == len(FakeSteps.calls)


def test_blind_validation_shows_only_gaits_that_were_made(tmp_path: Path) -> None:
    s = _run(f"sqlite:///{tmp_path / 'lab.db'}", 10)
    made = {e.payload["action"] for e in s.events() if e.kind == "gait_made"}
    plan = s.start_validation()
    assert {g.action for g in plan.gaits} <= made
    assert len(made) < len(s.config.space)  # the unrestricted plan could pick an unmade one
    mean = np.asarray(s.posterior().mean)
    assert max(mean[a] for a in made) == max(mean[g.action] for g in plan.gaits)


def test_a_memory_database_reopens_from_the_log_without_making_gaits_again() -> None:
    from gaitpref.storage import MemoryStorage

    storage = MemoryStorage()
    s = _run(storage, 6)  # type: ignore[arg-type]
    made = len(FakeSteps.calls)
    again = Session.open(storage, s.id)
    assert len(FakeSteps.calls) == made
    assert again.trials() == s.trials()
    old = Session.open(storage, logged_as_version_1(storage, s.id))  # the log has no gaits
    assert len(FakeSteps.calls) == 2 * made
    assert old.trials() == s.trials()


def test_a_compass_gait_that_cannot_be_made_never_reaches_the_subject(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The real HZD optimisation: 0.02 m steps at 0.2 m/s have no gait (docs/gaits.md, "Gaits on
    demand")."""
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, parse_config(COMPASS), subject="S01")
    for _ in range(4):
        q = s.next_query()
        s.answer(q.id, [(q.actions[0], q.buffer[0], "first")] if q.buffer else [])
    (bad,) = s.infeasible_gaits()
    assert bad.gait_id == "L0.020-V0.200" and bad.reason.startswith("infeasible: ")
    assert all(s.gait_name(t.action) != bad.gait_id for t in s.trials())
    made = [e.payload for e in s.events() if e.kind == "gait_made"]
    assert all(p["cot"] > 0 for p in made) and len(made) == len({p["key"] for p in made})
    shutil.rmtree(tmp_path / "lab.db.gaits")
    old = logged_as_version_1(s.storage, s.id)
    with monkeypatch.context() as m:
        m.setattr(CompassHZD, "make", never_made)
        again = Session.open(url, s.id)  # every gait from the log
    assert again.infeasible_gaits() == [bad] and again.trials() == s.trials()
    shutil.rmtree(tmp_path / "lab.db.gaits")
    remade = Session.open(url, old)  # a version-1 log: every gait optimised again
    assert [g.gait_id for g in remade.infeasible_gaits()] == [bad.gait_id]
    assert remade.trials() == s.trials()


def test_a_session_recorded_before_the_iteration_budget_keeps_its_rule(tmp_path: Path) -> None:
    """A session recorded under the 0.4 defaults (no ``[gaits] max_iterations``) stores that
    version, makes its gaits without a budget (their keys are the unbudgeted ones) and replays
    so; a session under the current defaults makes them within the budget, under other keys."""
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    old = Session.create(url, parse_config(COMPASS, defaults="0.4"), subject="S01")
    new = Session.create(url, parse_config(COMPASS), subject="S02")
    assert old.record.meta["config_defaults"] == "0.4"
    assert new.record.meta["config_defaults"] == DEFAULTS_VERSION
    for s in (old, new):
        q = s.next_query()
        s.answer(q.id, [])
        s.next_query()
    space = old.config.space
    unbounded = make_generator("compass-hzd", ["step_length"], {"speed": 0.2})
    bounded = make_generator("compass-hzd", ["step_length"], {"speed": 0.2, "max_iterations": 60})
    for s, generator in ((old, unbounded), (new, bounded)):
        made = [e.payload for e in s.events() if e.kind == "gait_made"]
        assert made and all(p["key"] == generator.key(space.point(p["action"])) for p in made)
    shutil.rmtree(tmp_path / "lab.db.gaits")
    again = Session.open(url, old.id)  # made again, without a budget: the same keys
    assert again.events() == old.events() and again.pending == old.pending


def test_on_the_line_path_an_infeasible_gait_keeps_its_point(tmp_path: Path) -> None:
    """The proposal is withdrawn and its row of the point table goes to the next point, so the
    row names another point later; ``InfeasibleGait.values`` is the refused point's."""
    FakeSteps.below = 0.5
    s = Session.create(f"sqlite:///{tmp_path / 'lab.db'}", parse_config(CONTINUOUS), "S01")
    prefer_short_steps(s, 14)
    bad = s.infeasible_gaits()
    assert bad, "the subject's short steps reach infeasible gaits"
    logged = {e.seq: e.payload["values"] for e in s.events() if e.kind == "gait_infeasible"}
    for g in bad:
        assert g.values == logged[g.seq] and g.values["step_length"] < FakeSteps.below
        assert g.gait_id.startswith(f"S{g.values['step_length']:.3f}-")
    # the rows were given to points proposed after (as documented): look up by values
    assert any(s.space.values_of(g.action) != g.values for g in bad)


def test_the_terminal_says_which_gaits_were_skipped(tmp_path: Path) -> None:
    from io import StringIO

    from rich.console import Console

    from gaitpref.terminal import Terminal

    s = Session.create(f"sqlite:///{tmp_path / 'lab.db'}", parse_config(CONFIG), subject="S01")
    out = StringIO()
    length = s.config.space.values_of

    def read(_: str) -> str:
        last = out.getvalue().splitlines()[-1]
        q = s.pending
        if len(s.trials()) >= 12:
            return "q"
        if "this one" in last and q is not None:
            a, b = q.actions[0], q.buffer[0]
            return "1" if length(a)["step_length"] <= length(b)["step_length"] else "2"
        return "y" if last.startswith("Write") else "0"

    Terminal(s, Console(file=out, width=200), read=read).run()
    text = out.getvalue()
    assert s.infeasible_gaits()
    for bad in s.infeasible_gaits():
        assert f"gait {bad.gait_id} cannot be made; skipped" in text
        assert f"run {bad.gait_id}" not in text


def test_a_generator_session_takes_no_library() -> None:
    from gaitpref.storage import MemoryStorage

    with pytest.raises(ValueError, match=r"on demand.*takes no gait library"):
        Session.create(MemoryStorage(), parse_config(CONFIG), "S01", library=["a"] * 42)


def test_a_query_that_could_not_be_written_is_derived_again_from_the_log(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from gaitpref.storage import StorageError

    FakeSteps.below = 0.9  # most proposals cannot be made
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, parse_config(CONFIG), subject="S01")
    real = s.storage.append

    def fail(*args: object, **kwargs: object) -> object:
        raise StorageError("disk full")

    monkeypatch.setattr(s.storage, "append", fail)
    with pytest.raises(StorageError):
        s.next_query()  # gaits were made and avoided, nothing was written
    monkeypatch.setattr(s.storage, "append", real)
    q = s.next_query()
    logged = [e.kind for e in s.events()]
    assert logged.count("gait_infeasible") >= 1  # logged this time, with the query
    again = Session.open(url, s.id)
    assert again.pending == q and again.infeasible_gaits() == s.infeasible_gaits()
