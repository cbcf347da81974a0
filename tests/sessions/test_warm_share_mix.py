"""Warm starts under defaults 0.6 (the share a mixture of hypotheses) and before (one MAP share):
each records what it did, and replays exactly; a session recorded by the 0.4 release replays as
it was run."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gaitpref import Session, load_config
from gaitpref.config import DEFAULTS_VERSION, parse_config
from gaitpref.loop.stopping import StopRule
from gaitpref.model.share_mix import ALONE_PRIOR
from gaitpref.sessions.confidence import session_confidence
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG, state_of
from tests.sessions.test_replay_rounding import rewrite_logged
from tests.sessions.test_warm_start import _earlier, _run, _snapshot

FIXTURES = Path(__file__).resolve().parent.parent / "fixtures"


def _warm(db: MemoryStorage, defaults: str | None) -> Session:
    ids = _earlier(db)
    config = load_config(CONFIG)
    if defaults is not None:
        config = parse_config(config.text, default_name=config.name, defaults=defaults)
    warm = Session.create(db, config, "S04", seed=5, prior_from=ids)
    _run(warm, SimulatedSubject(config.space, bump_utility(config.space), seed=5), 5)
    return warm


def _replays_exactly(db: MemoryStorage, warm: Session) -> None:
    mean, var, query, rng = state_of(warm)
    sure = session_confidence(warm._state, StopRule())
    with Session.open(db, warm.id) as again:
        assert again._state.loop.learning == warm._state.loop.learning
        mean2, var2, query2, rng2 = state_of(again)
        assert np.array_equal(mean, mean2) and np.array_equal(var, var2)
        assert (query, rng) == (query2, rng2)
        assert session_confidence(again._state, StopRule()) == sure


def test_a_warm_start_under_0_6_records_the_share_hypotheses_and_replays() -> None:
    db = MemoryStorage()
    warm = _warm(db, None)
    assert warm.record.meta["config_defaults"] == DEFAULTS_VERSION  # 0.6 or later
    loop = warm._state.loop
    assert loop.learning.share == "average"
    refits = [e.payload for e in warm.events() if e.kind == "share_refit"]
    assert len(refits) == 5 and all(len(r["hypotheses"]) == 5 for r in refits)
    last = refits[-1]
    assert last["hypotheses"][0]["share"] == 0.0
    assert last["hypotheses"][0]["prior"] == ALONE_PRIOR
    weights = [h["weight"] for h in last["hypotheses"]]
    assert sum(weights) == pytest.approx(1.0) and weights[0] < ALONE_PRIOR
    mean_share = sum(h["weight"] * h["share"] for h in last["hypotheses"])
    assert last["after"] == pytest.approx(mean_share) and loop.warm is not None
    assert loop.warm.share == last["after"]
    assert loop.share_mixture() is not None
    _replays_exactly(db, warm)


@pytest.mark.parametrize("defaults", ["0.4", "0.5"])
def test_a_warm_start_under_earlier_defaults_keeps_one_map_share_and_replays(defaults: str) -> None:
    db = MemoryStorage()
    warm = _warm(db, defaults)
    assert warm.record.meta["config_defaults"] == defaults
    loop = warm._state.loop
    assert loop.learning.share == "map" and loop.share_mixture() is None
    refits = [e.payload for e in warm.events() if e.kind == "share_refit"]
    assert len(refits) == 5 and not any("hypotheses" in r for r in refits)
    _replays_exactly(db, warm)


def test_a_warm_session_recorded_by_0_4_replays_as_it_was_run(tmp_path: Path) -> None:
    path = tmp_path / "warm.db"
    shutil.copy(FIXTURES / "warm-0.4.db", path)
    url = f"sqlite:///{path}"
    recorded = json.loads((FIXTURES / "warm-0.4.json").read_text())
    before = _snapshot(url, [1, 2, 3])
    with Session.open(url, recorded["session"]) as s:  # replay re-derives every share_refit
        assert "config_defaults" not in s.record.meta  # relied on no changed default then
        loop = s._state.loop
        assert loop.learning.share == "map"
        assert loop.warm is not None and loop.warm.share == recorded["share"]
        assert np.allclose(s.posterior().mean, recorded["mean"], rtol=1e-10, atol=1e-12)
        sure = session_confidence(s._state, StopRule()).to_json()
        assert sure["recommended"] == recorded["confidence"]["recommended"]
        assert sure["probability"] == pytest.approx(recorded["confidence"]["probability"])
    assert _snapshot(url, [1, 2, 3]) == before  # the earlier sessions read, never written


def test_share_hypotheses_rounded_elsewhere_are_taken_from_the_log(tmp_path: Path) -> None:
    path = tmp_path / "s.db"
    url = f"sqlite:///{path}"
    ids = _earlier(url)
    space = load_config(CONFIG).space
    with Session.create(url, CONFIG, "S04", seed=5, prior_from=ids) as warm:
        _run(warm, SimulatedSubject(space, bump_utility(space), seed=5), 4)
        wid = warm.id

    def nudge(payload: dict[str, Any]) -> None:  # another machine's last bits
        payload["after"] *= 1 + 4e-16
        for h in payload["hypotheses"]:
            h["weight"] *= 1 + 4e-16

    payload = rewrite_logged(path, wid, "share_refit", nudge, last=True)
    with Session.open(url, wid) as again:
        loop = again._state.loop
        assert loop.warm is not None and loop.warm.share == payload["after"]
        assert [h.weight for h in loop.share_hypotheses] == [
            h["weight"] for h in payload["hypotheses"]
        ]


@pytest.mark.parametrize(("defaults", "first"), [(None, "recommended"), ("0.7", "strategy")])
def test_a_warm_sessions_first_trial_follows_its_defaults_and_replays(
    defaults: str | None, first: str
) -> None:
    db = MemoryStorage()
    ids = _earlier(db)
    config = load_config(CONFIG)
    if defaults is not None:
        config = parse_config(config.text, default_name=config.name, defaults=defaults)
    warm = Session.create(db, config, "S04", seed=5, prior_from=ids)
    loop = warm._state.loop
    assert loop.learning.warm_first == first
    recommended = loop._warm_first(loop.allowed())
    q = warm.next_query()
    if first == "recommended":  # the earlier subjects' best guess, not the strategy's draw
        assert recommended and q.actions == recommended
    else:
        assert recommended == ()  # "strategy": the loop leaves the first trial to the strategy
    _run(warm, SimulatedSubject(config.space, bump_utility(config.space), seed=5), 3)
    with Session.open(db, warm.id) as again:
        assert again._state.loop.executed == loop.executed
        assert again._state.loop.executed[0] == q.actions[0]
