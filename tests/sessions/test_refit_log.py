"""Hyperparameter refits are logged with the answer that triggered them and checked on replay."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitpref import Session, load_config
from gaitpref.sessions.demo import SimulatedSubject, bump_utility

FITTED = """
[space.step_length]
min = 0.08
max = 0.18
num = 15
unit = "m"

[model]
lengthscale = { step_length = 0.03 }
signal_variance = 0.005
jitter = 1e-7
noise = 0.02
fit = "evidence"
refit_every = 3

[cospar]
n = 1
buffer = 1
strategy = "self-sparring"
"""


def _answered(tmp_path: Path, text: str, answers: int) -> tuple[str, Session, SimulatedSubject]:
    """A session of config ``text`` (its database url, it, its subject) after ``answers``."""
    path = tmp_path / "config.toml"
    path.write_text(text)
    url = f"sqlite:///{tmp_path / 'refit.db'}"
    config = load_config(path)
    session = Session.create(url, config, "S01", seed=4)
    subject = SimulatedSubject(config.space, bump_utility(config.space), seed=2)
    for _ in range(answers):
        q = session.next_query()
        session.answer(q.id, *subject.respond(q))
    return url, session, subject


def test_refits_are_logged_and_replayed_exactly(tmp_path: Path) -> None:
    url, session, _ = _answered(tmp_path, FITTED, 10)
    refits = [e for e in session.events() if e.kind == "hyperparameters_refit"]
    assert len(refits) == 3  # after answers 3, 6 and 9
    told = session._state.loop.refits
    assert [e.payload["after"] for e in refits] == [r.to_json()["after"] for r in told]
    answered = [e.payload["query"] for e in session.events() if e.kind == "trial_executed"]
    assert [e.payload["query"] for e in refits] == [answered[2], answered[5], answered[8]]
    mean, hyper = np.asarray(session.posterior().mean).copy(), session._state.loop.hyper
    session.close()

    again = Session.open(url, session.id)  # replays and checks every refit
    np.testing.assert_array_equal(again.posterior().mean, mean)
    assert again._state.loop.hyper == hyper
    again.undo()  # the 10th answer (no refit)
    again.undo()  # the 9th, which refitted: back to the hyperparameters of the 6th's refit
    assert again._state.loop.hyper == told[1].after


def test_averaged_refits_log_their_hypotheses_and_replay_exactly(tmp_path: Path) -> None:
    text = FITTED.replace("refit_every = 3", 'refit_every = 3\nhyper = "average"')
    url, session, subject = _answered(tmp_path, text.replace("self-sparring", "gated-eubo"), 10)
    assert session._state.loop.learning.hyper == "average"
    refits = [e for e in session.events() if e.kind == "hyperparameters_refit"]
    told = session._state.loop.refits
    assert len(refits) == 3
    assert [e.payload["hypotheses"] for e in refits] == [r.to_json()["hypotheses"] for r in told]
    weights = [h["weight"] for h in refits[-1].payload["hypotheses"]]
    assert len(weights) == 5 and sum(weights) == pytest.approx(1.0)
    trials = [e.payload["action"] for e in session.events() if e.kind == "trial_executed"]
    mean = np.asarray(session.posterior().mean).copy()
    session.close()

    again = Session.open(url, session.id)  # replays: re-derives every proposal and refit
    np.testing.assert_array_equal(again.posterior().mean, mean)
    assert again._state.loop.hypotheses == session._state.loop.hypotheses
    q = again.next_query()
    again.answer(q.id, *subject.respond(q))
    assert [e.payload["action"] for e in again.events() if e.kind == "trial_executed"][
        :-1
    ] == trials


def test_map_refits_are_written_without_hypotheses(tmp_path: Path) -> None:
    _, session, _ = _answered(tmp_path, FITTED, 3)
    (refit,) = [e for e in session.events() if e.kind == "hyperparameters_refit"]
    assert "hypotheses" not in refit.payload
