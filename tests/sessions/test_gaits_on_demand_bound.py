"""One ask with gaits made on demand is bounded: in a space where most gaits cannot be made it
stops after ``[gaits] max_infeasible`` proposals without a gait, logs each of them (and a closing
``query_stopped``) exactly as a longer ask would have, and the session goes on from there."""

from __future__ import annotations

from pathlib import Path

import pytest

from gaitpref import Session
from gaitpref.config import ConfigError, parse_config
from gaitpref.errors import InfeasibleProposalsError, NoSafeGaitError
from gaitpref.storage import MemoryStorage
from tests.sessions.gaitkit import CONFIG, CONTINUOUS, FakeSteps, never_made

#: step lengths 0.00 .. 0.90 (19 of 21) have no gait: most of the space
MOSTLY_INFEASIBLE = 0.95


def _config(limit: int | None, base: str = CONFIG) -> str:
    extra = "" if limit is None else f"max_infeasible = {limit}\n"
    return base.replace("avoid_radius = 0.1\n", f"avoid_radius = 0.1\n{extra}")


#: the grid, and the line path (continuous step length: rows withdrawn with each proposal)
PATHS = pytest.mark.parametrize("base", [CONFIG, CONTINUOUS], ids=["grid", "line"])


def _ask(s: Session) -> tuple[int, list[InfeasibleProposalsError]]:
    """Ask until a query comes, collecting the stopped asks' errors (a bounded number)."""
    stops: list[InfeasibleProposalsError] = []
    for _ in range(50):
        try:
            return s.next_query().id, stops
        except InfeasibleProposalsError as exc:
            stops.append(exc)
    raise AssertionError("50 asks in a row stopped")


def _gait_actions(s: Session) -> list[tuple[str, int]]:
    return [(e.kind, e.payload["action"]) for e in s.events() if e.kind.startswith("gait_")]


@PATHS
def test_an_ask_stops_after_max_infeasible_proposals_and_logs_each(
    tmp_path: Path, base: str
) -> None:
    FakeSteps.below = MOSTLY_INFEASIBLE
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, parse_config(_config(3, base)), subject="S01")
    with pytest.raises(InfeasibleProposalsError) as caught:
        s.next_query()
    err = caught.value
    assert isinstance(err, NoSafeGaitError)  # nothing proposed: every app already says so
    assert (err.infeasible, err.limit) == (3, 3)  # n = 1: one gait per proposal
    assert "3 gaits that cannot be made" in str(err) and "max_infeasible" in str(err)
    assert "Ask again" in str(err)
    # the gaits made are exactly the gaits logged, and no more were made than the bound
    assert len(FakeSteps.calls) == 3
    kinds = [e.kind for e in s.events()]
    assert kinds == ["created", *["gait_infeasible"] * 3, "query_stopped"]
    assert s.events()[-1].payload == {"infeasible": 3, "limit": 3}
    assert len(s.infeasible_gaits()) == 3 and s.pending is None
    # the database replays to the same state without making a gait again
    again = Session.open(url, s.id)
    assert again.infeasible_gaits() == s.infeasible_gaits() and again.pending is None
    assert len(FakeSteps.calls) == 3


@PATHS
def test_asking_again_goes_on_as_one_long_ask_would_have(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, base: str
) -> None:
    FakeSteps.below = MOSTLY_INFEASIBLE
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    bounded = Session.create(url, parse_config(_config(3, base)), subject="S01")
    _, stops = _ask(bounded)
    assert len(stops) >= 2
    unbounded = Session.create(url, parse_config(_config(1000, base)), subject="S02")
    _ask(unbounded)
    # the same proposals in the same order, the same avoided gaits and the same query
    assert _gait_actions(bounded) == _gait_actions(unbounded)
    q, long = bounded.pending, unbounded.pending
    assert q is not None and long is not None
    assert (q.loop_id, q.actions, q.buffer) == (long.loop_id, long.actions, long.buffer)
    kinds = [e.kind for e in bounded.events()]
    assert kinds.count("query_stopped") == len(stops) and kinds[-1] == "query_issued"
    # reopened from the log alone: the same state, no gait made again
    monkeypatch.setattr(FakeSteps, "make", never_made)
    import shutil

    shutil.rmtree(tmp_path / "lab.db.gaits")
    again = Session.open(url, bounded.id)
    assert again.pending == q and again.infeasible_gaits() == bounded.infeasible_gaits()


@PATHS
def test_an_ask_left_without_a_gait_before_the_limit_logs_the_gaits_it_found(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, base: str
) -> None:
    """With avoid_radius 1 two infeasible gaits leave no gait to propose, far below
    max_infeasible (20): the ask raised NoSafeGaitError and wrote nothing, so its gaits were in
    the gait cache only, and the log (a replay, the next ask) did not have them."""
    import shutil

    FakeSteps.below = MOSTLY_INFEASIBLE
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    text = _config(None, base).replace("avoid_radius = 0.1\n", "avoid_radius = 1.0\n")
    s = Session.create(url, parse_config(text), subject="S01")
    with pytest.raises(NoSafeGaitError) as caught:
        s.next_query()
    err = caught.value
    assert not isinstance(err, InfeasibleProposalsError)  # the limit was not reached
    assert "2 gaits that cannot be made" in str(err) and "no gait was left" in str(err)
    assert len(FakeSteps.calls) == 2
    kinds = [e.kind for e in s.events()]
    assert kinds == ["created", "gait_infeasible", "gait_infeasible", "query_stopped"]
    assert s.events()[-1].payload == {"infeasible": 2, "limit": 20}
    logged = [e.payload["gait_id"] for e in s.events() if e.kind == "gait_infeasible"]
    assert [g.gait_id for g in s.infeasible_gaits()] == logged and s.pending is None
    # asking again, nothing changed: no gait may be proposed, nothing written, nothing made
    with pytest.raises(NoSafeGaitError, match="no gait may be proposed"):
        s.next_query()
    assert [e.kind for e in s.events()] == kinds and len(FakeSteps.calls) == 2
    # the log alone gives the same state (no gait made again), and the same next ask
    monkeypatch.setattr(FakeSteps, "make", never_made)
    shutil.rmtree(tmp_path / "lab.db.gaits")
    again = Session.open(url, s.id)
    assert again.infeasible_gaits() == s.infeasible_gaits() and again.pending is None
    with pytest.raises(NoSafeGaitError, match="no gait may be proposed"):
        again.next_query()
    assert [e.kind for e in again.events()] == kinds


def test_a_read_does_not_ask_again_after_a_stopped_ask_until_something_is_logged(
    tmp_path: Path,
) -> None:
    """next_query(retry=False), what a page reload or a controller's poll calls: after an ask
    that stopped, with nothing logged since, it raises that stop's error again and makes no
    gait (each read made up to max_infeasible more); after any other event it asks."""
    FakeSteps.below = MOSTLY_INFEASIBLE
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, parse_config(_config(2)), subject="S01")
    with pytest.raises(InfeasibleProposalsError) as caught:
        s.next_query(retry=False)  # the first ask: nothing stopped before it
    made, events = len(FakeSteps.calls), len(s.events())
    for reader in (s, Session.open(url, s.id)):  # live, and as replayed from the log
        for _ in range(3):
            with pytest.raises(InfeasibleProposalsError) as again:
                reader.next_query(retry=False)
            assert str(again.value) == str(caught.value)
            assert (again.value.infeasible, again.value.limit) == (2, 2)
    assert (len(FakeSteps.calls), len(s.events())) == (made, events)
    s.note("the subject rests")  # something logged since: a read asks again
    with pytest.raises(InfeasibleProposalsError):
        s.next_query(retry=False)
    assert len(FakeSteps.calls) > made and s.events()[-1].kind == "query_stopped"
    made = len(FakeSteps.calls)
    with pytest.raises(InfeasibleProposalsError):
        s.next_query()  # an explicit ask goes on
    assert len(FakeSteps.calls) > made


def test_the_session_answers_undoes_and_exports_after_a_stopped_ask(tmp_path: Path) -> None:
    from gaitpref.sessions.export import export_session, import_session

    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, parse_config(_config(1)), subject="S01")  # every infeasible stops
    space = s.config.space
    for _ in range(30):  # a subject who prefers short steps: the proposals reach those without
        try:
            q = s.next_query()
        except InfeasibleProposalsError:
            if s.trials():
                break
            continue
        a, b = q.actions[0], (q.buffer[0] if q.buffer else None)
        if b is None or b == a:
            s.answer(q.id, [])
            continue
        shorter = space.values_of(a)["step_length"] < space.values_of(b)["step_length"]
        s.answer(q.id, [(a, b, "first" if shorter else "second")])
    else:
        raise AssertionError("no ask stopped after an answer")
    assert s.pending is None and s.events()[-1].kind == "query_stopped"
    bad = {g.action for g in s.infeasible_gaits()}
    assert all(t.action not in bad for t in s.trials())
    # undo after the stopped ask: the last answer's query is asked again
    last = s.trials()[-1]
    pending = s.undo()
    assert pending is not None and last.query == pending.id
    # replay from the database gives the same state
    again = Session.open(url, s.id)
    assert (again.pending, again.trials(), again.infeasible_gaits()) == (
        s.pending,
        s.trials(),
        s.infeasible_gaits(),
    )
    # an export imports as the same session
    folder = tmp_path / "export"
    export_session(s, folder)
    copy = import_session(MemoryStorage(), folder, as_new=True)
    assert copy.infeasible_gaits() == s.infeasible_gaits() and copy.pending == s.pending
    # and both go on alike
    s.answer(pending.id, [])
    copy.answer(pending.id, [])
    _ask(s)
    _ask(copy)
    assert [(e.kind, e.payload) for e in s.events()] == [(e.kind, e.payload) for e in copy.events()]


def test_replay_refuses_a_stopped_ask_the_log_does_not_stop_where_it_derives(
    tmp_path: Path,
) -> None:
    """An edited log whose stopped ask claims a later limit: replay stops one proposal past
    the logged batch and names the difference (it made gaits on before)."""
    from gaitpref import ReplayError
    from gaitpref.storage import EventRecord, NewEvent
    from tests.sessions.gaitkit import copied

    FakeSteps.below = MOSTLY_INFEASIBLE
    storage = MemoryStorage()
    s = Session.create(storage, parse_config(_config(3)), subject="S01")
    with pytest.raises(InfeasibleProposalsError):
        s.next_query()

    def later_limit(e: EventRecord) -> NewEvent | None:
        if e.kind != "query_stopped":
            return None
        return NewEvent("query_stopped", {"infeasible": 3, "limit": 1000})

    edited = copied(storage, s.id, later_limit)
    made = len(FakeSteps.calls)
    with pytest.raises(ReplayError, match="query_stopped"):
        Session.open(storage, edited)
    assert len(FakeSteps.calls) <= made + 1  # one proposal past the log at most


def test_max_infeasible_is_checked_and_only_a_generator_takes_it() -> None:
    with pytest.raises(ConfigError, match=r"\[gaits\]\.max_infeasible"):
        parse_config(_config(0))
    assert parse_config(_config(None)).generator is not None
    assert parse_config(_config(None)).generator.max_infeasible == 20  # type: ignore[union-attr]
    model = CONFIG[CONFIG.index("[model]") : CONFIG.index("[cospar]")]
    library = f'[gaits]\nlibrary = "g.json"\nmax_infeasible = 5\n{model}'
    with pytest.raises(ConfigError, match=r"max_infeasible.*library takes none"):
        parse_config(library)


def test_the_terminal_names_a_stopped_ask_s_gaits_and_pauses(tmp_path: Path) -> None:
    from io import StringIO

    from rich.console import Console

    from gaitpref.terminal import Terminal

    FakeSteps.below = MOSTLY_INFEASIBLE
    s = Session.create(f"sqlite:///{tmp_path / 'lab.db'}", parse_config(_config(2)), "S01")
    out = StringIO()
    Terminal(s, Console(file=out, width=300), read=lambda _: "q").run()
    text = out.getvalue()
    assert "No gait to propose: this ask stopped without proposing" in text
    bad = s.infeasible_gaits()
    assert len(bad) == 2
    for g in bad:
        assert f"gait {g.gait_id} cannot be made; skipped" in text
    assert s.status == "paused"
