"""A session whose strategy chooses on a rescaled posterior early (gated-eubo's
``early_scale``), or runs self-sparring for a window of trials (``sparring_from``,
``sparring_until``), replays exactly, undo included, and differs from the plain strategy's."""

from __future__ import annotations

import numpy as np

from gaitpref import Session, load_config
from gaitpref.config import ExperimentConfig, parse_config
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG, state_of
from tests.sessions.test_warm_start import _earlier, _run

LOCAL = "\n[cospar.strategy_settings]\nearly_scale = 0.5\nearly_trials = 20\n"
BURST = "\n[cospar.strategy_settings]\nearly_scale = 0.5\nearly_trials = 2\n"
BURST += "sparring_from = 2\nsparring_until = 6\n"


def _config(local: bool, settings: str = LOCAL) -> ExperimentConfig:
    base = load_config(CONFIG)
    text = base.text.replace('strategy = "self-sparring"', 'strategy = "gated-eubo"')
    return parse_config(text + (settings if local else ""), default_name=base.name)


def _queries(session: Session) -> list[tuple[int, ...]]:
    return [tuple(e.payload["actions"]) for e in session.events() if e.kind == "query_issued"]


def test_a_local_challenger_session_replays_exactly_and_undoes() -> None:
    db = MemoryStorage()
    config = _config(True)
    assert config.strategy_settings == {"early_scale": 0.5, "early_trials": 20}
    subject = SimulatedSubject(config.space, bump_utility(config.space), seed=7)
    with Session.create(db, config, "S01", seed=7) as s:
        _run(s, subject, 8)
        mean, var, query, rng = state_of(s)
        sid = s.id
        local_queries = _queries(s)
    with Session.open(db, sid) as again:
        mean2, var2, query2, rng2 = state_of(again)
        assert np.array_equal(mean, mean2) and np.array_equal(var, var2)
        assert (query, rng) == (query2, rng2)
        again.undo()
        q = again.next_query()
        comparisons, suggestions = subject.respond(q)
        again.answer(q.id, comparisons, suggestions)
    with Session.open(db, sid) as third:
        assert third._state.loop.strategy == again._state.loop.strategy

    plain = MemoryStorage()
    with Session.create(plain, _config(False), "S01", seed=7) as p:
        _run(p, SimulatedSubject(config.space, bump_utility(config.space), seed=7), 8)
        assert _queries(p) != local_queries


def test_a_warm_started_local_challenger_session_replays() -> None:
    db = MemoryStorage()
    ids = _earlier(db)
    config = _config(True)
    with Session.create(db, config, "S04", seed=5, prior_from=ids) as warm:
        _run(warm, SimulatedSubject(config.space, bump_utility(config.space), seed=5), 5)
        mean, var, query, rng = state_of(warm)
        sid = warm.id
    with Session.open(db, sid) as again:
        mean2, var2, query2, rng2 = state_of(again)
        assert np.array_equal(mean, mean2) and np.array_equal(var, var2)
        assert (query, rng) == (query2, rng2)


def _burst_session(
    settings: str,
) -> tuple[list[tuple[int, ...]], tuple[np.ndarray, np.ndarray, object, object], Session]:
    """Four answers, an undo inside the window, then six more; the queries and the state."""
    db = MemoryStorage()
    config = _config(True, settings)
    subject = SimulatedSubject(config.space, bump_utility(config.space), seed=3)
    with Session.create(db, config, "S01", seed=3) as s:
        _run(s, subject, 4)  # the next query is inside the window
        sid = s.id
    with Session.open(db, sid) as again:
        again.undo()  # back into the window: the trial is asked again, the same way
        _run(again, subject, 6)  # through the window and past it
        state = state_of(again)
        queries = _queries(again)
    return queries, state, Session.open(db, sid)


def test_a_session_with_an_exploration_burst_replays_exactly_and_undoes_inside_it() -> None:
    assert _config(True, BURST).strategy_settings["sparring_until"] == 6
    queries, (mean, var, query, rng), reopened = _burst_session(BURST)
    with reopened as third:
        mean2, var2, query2, rng2 = state_of(third)
        assert np.array_equal(mean, mean2) and np.array_equal(var, var2)
        assert (query, rng) == (query2, rng2)
        assert _queries(third) == queries
    # without the window the same answers' first trials agree and the window's do not
    local, _, other = _burst_session(BURST.split("sparring_from")[0])
    other.close()
    assert local[:2] == queries[:2]
    assert local != queries
