"""Ratings in a session: answered with comparisons, logged, replayed (with evidence refits that
fit the thresholds), undone, excluded and exported."""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import NDArray

from gaitpref import FeedbackError, Rating, Session
from gaitpref.config import parse_config
from gaitpref.sessions import export_session, import_session

CONFIG = """
name = "rated-1d"
[space.step_length]
min = 0.08
max = 0.18
num = 15
unit = "m"
[model]
lengthscale = 0.03
signal_variance = 0.005
noise = 0.02
fit = "evidence"
refit_every = 2
[cospar]
seed = 2
strategy = "self-sparring"
[feedback.rating]
labels = ["very bad", "bad", "okay", "good"]
[safety]
avoid = ["very bad"]
lambda = 2.0
"""
LABELS = ["very bad", "bad", "okay", "good"]


def _session(url: str, answers: int = 6) -> Session:
    s = Session.create(url, parse_config(CONFIG), "S01")
    for k in range(answers):
        q = s.next_query()
        a = q.actions[0]
        given: list[object] = [Rating(a, LABELS[(k + 2) % 4])]
        if q.buffer and q.buffer[0] != a:
            given.append((a, q.buffer[0], "first" if k % 2 else "second"))
        s.answer(q.id, given)
    return s


def test_replay_with_refits_that_fit_the_thresholds(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'r.db'}"
    with _session(url) as s:
        mean = np.asarray(s.posterior().mean).copy()
        refits = [e.payload for e in s.events() if e.kind == "hyperparameters_refit"]
        ratings = [e.payload for e in s.events() if e.kind == "rating_given"]
        sid = s.id
    assert len(refits) == 3 and all("thresholds" in r["after"] for r in refits)
    assert [r["category"] for r in ratings] == [LABELS[(k + 2) % 4] for k in range(6)]
    with Session.open(url, sid) as again:
        assert np.array_equal(np.asarray(again.posterior().mean), mean)


def test_undo_exclude_export_import(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'r.db'}"
    with _session(url, 4) as s:
        s.undo()
        assert s.feedback()[-1].undone and s.feedback()[-1].kind == "rating_given"
        q = s.next_query()
        s.answer(q.id, [Rating(q.actions[0], "good")])
        s.exclude(1, "device_fault")
        assert next(e.excluded for e in s.feedback() if not e.undone)
        with pytest.raises(FeedbackError, match="not a category"):
            s.answer(s.next_query().id, [Rating(s.next_query().actions[0], "great")])
        export_session(s, tmp_path / "out")
        mean = np.asarray(s.posterior().mean).copy()
    with (tmp_path / "out" / "ratings.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [r["category"] for r in rows] == ["okay", "good", "very bad", "bad", "good"]
    assert [r["undone"] for r in rows] == ["false", "false", "false", "true", "false"]
    with import_session(f"sqlite:///{tmp_path / 'b.db'}", tmp_path / "out") as copy:
        assert np.array_equal(np.asarray(copy.posterior().mean), mean)


def test_the_posterior_rates_with_the_fitted_thresholds(tmp_path: Path) -> None:
    """After a refit fits the thresholds, rating probabilities and the region of avoidance use
    them (the thresholds the fit used), not the prior's quantiles."""
    with _session(f"sqlite:///{tmp_path / 'r.db'}") as s:
        loop = s._state.loop
        assert loop.hyper.thresholds is not None
        post = s.posterior()
        assert post.ordinal is not None
        assert post.ordinal.thresholds == loop.hyper.thresholds
        assert post.ordinal.categories == tuple(LABELS)
        assert loop.gp.ordinal is not None and loop.gp.ordinal.thresholds is None  # the config's
        probs = post.rating_probabilities([0, 7, 14])
        assert np.allclose(probs.sum(axis=1), 1.0)


def _same_region(a: NDArray[np.bool_] | None, b: NDArray[np.bool_] | None) -> bool:
    """The same allowed gaits: both None (every gait), or equal masks."""
    if a is None or b is None:
        return a is b
    return bool(np.array_equal(a, b))


def test_a_session_with_the_cautious_level_replays_and_older_ones_replay_without(
    tmp_path: Path,
) -> None:
    url = f"sqlite:///{tmp_path / 'c.db'}"
    cautious = CONFIG.replace("lambda = 2.0", "cautious = 0.6")
    with Session.create(url, parse_config(cautious), "S01") as s:
        for _ in range(6):
            q = s.next_query()
            a = q.actions[0]
            s.answer(q.id, [Rating(a, "very bad" if a <= 3 else "good" if a >= 10 else "okay")])
        loop = s._state.loop
        assert loop.safety.cautious == 0.6
        allowed = loop.allowed()
        single = dataclasses.replace(loop.safety, cautious=None).allowed(loop.posterior, None, ())
        assert allowed is not None and allowed.any() and not _same_region(allowed, single)
        pending = s.next_query().actions
        sid = s.id
    with Session.open(url, sid) as again:
        assert again._state.loop.safety == loop.safety
        assert _same_region(again._state.loop.allowed(), allowed)
        assert again.next_query().actions == pending
    # a session recorded with the 0.3 defaults (a region under risk, no cautious level)
    # replays with them, as it ran, though the defaults now add the cautious level
    plain = CONFIG.replace("lambda = 2.0\n", "")
    assert parse_config(plain).safety.cautious == 0.6
    url = f"sqlite:///{tmp_path / 'p.db'}"
    with Session.create(url, parse_config(plain, defaults="0.3"), "S02") as s:
        for _ in range(4):
            q = s.next_query()
            a = q.actions[0]
            s.answer(q.id, [Rating(a, "very bad" if a <= 3 else "good" if a >= 10 else "okay")])
        assert s._state.loop.safety.cautious is None
        allowed, pending, sid = s._state.loop.allowed(), s.next_query().actions, s.id
    with Session.open(url, sid) as again:
        assert again._state.loop.safety.cautious is None
        assert _same_region(again._state.loop.allowed(), allowed)
        assert again.next_query().actions == pending


@pytest.mark.parametrize(
    ("keys", "cautious", "frontier"),
    [("reach = 1.0", 0.6, None), ("reach = 1.0\ncautious = 0.5\nfrontier = 0.9", 0.5, 0.9)],
)
def test_a_declared_start_gait_is_walked_first_and_replays(
    tmp_path: Path, keys: str, cautious: float, frontier: float | None
) -> None:
    text = CONFIG.replace("lambda = 2.0", "start = [{step_length = 0.13}]\n" + keys)
    cfg = parse_config(text)
    assert cfg.safety.start == (7,) and cfg.safety.cautious == cautious
    assert cfg.safety.frontier == frontier
    url = f"sqlite:///{tmp_path / 'r.db'}"
    with Session.create(url, cfg, "S02") as s:
        walked = []
        for k in range(5):
            q = s.next_query()
            walked.append(q.actions[0])
            given: list[object] = [Rating(q.actions[0], LABELS[2 + k % 2])]
            if q.buffer and q.buffer[0] != q.actions[0]:
                given.append((q.actions[0], q.buffer[0], "first"))
            s.answer(q.id, given)
        mean = np.asarray(s.posterior().mean).copy()
        pending = s.next_query().actions
        sid = s.id
    assert walked[0] == 7 and len(set(walked)) > 1
    with Session.open(url, sid) as again:  # replay re-derives every proposal from the log
        assert np.array_equal(np.asarray(again.posterior().mean), mean)
        assert again.next_query().actions == pending
