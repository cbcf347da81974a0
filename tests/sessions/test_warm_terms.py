"""A warm start carries the earlier sessions' ties and ratings, not only their preferences; one
recorded before it did (no ``prior_terms``) is rebuilt from preferences only, as it was."""

from __future__ import annotations

import dataclasses

import numpy as np

from gaitpref import Rating, Session
from gaitpref.config import parse_config
from gaitpref.sessions.warm import prepare_state
from gaitpref.storage import MemoryStorage

CONFIG = """
name = "rated-ties-1d"
[space.step_length]
min = 0.08
max = 0.18
num = 15
unit = "m"
[model]
lengthscale = 0.03
signal_variance = 0.005
noise = 0.02
ties = "model"
[cospar]
seed = 2
strategy = "self-sparring"
[feedback.rating]
labels = ["bad", "okay", "good"]
"""
LABELS = ["bad", "okay", "good"]


def _earlier(storage: MemoryStorage, subject: str, seed: int) -> int:
    with Session.create(storage, parse_config(CONFIG), subject, seed=seed) as s:
        for k in range(6):
            q = s.next_query()
            a = q.actions[0]
            given: list[object] = [Rating(a, LABELS[(k + seed) % 3])]
            if q.buffer and q.buffer[0] != a:
                given.append((a, q.buffer[0], ("first", "none", "second")[k % 3]))
            s.answer(q.id, given)
        return s.id


def test_ties_and_ratings_are_carried_and_replay() -> None:
    storage = MemoryStorage()
    ids = [_earlier(storage, "S01", 1), _earlier(storage, "S02", 2)]
    s = Session.create(storage, parse_config(CONFIG), "S03", seed=4, prior_from=ids)
    created = s.events()[0].payload
    assert created["prior_terms"] == "all" and s.record.meta["prior_terms"] == "all"
    warm = s._state.loop.warm
    assert warm is not None and warm.singles is not None
    assert warm.singles.size == 12  # every rating of both sessions
    assert warm.data.tie.sum() >= 2 and warm.data.banded.all()
    q = s.next_query()
    s.answer(q.id, [Rating(q.actions[0], "good")])
    mean = np.asarray(s.posterior().mean).copy()
    with Session.open(storage, s.id) as again:  # replays with the same terms
        assert np.array_equal(np.asarray(again.posterior().mean), mean)

    # recorded without prior_terms (the first warm starts): preferences only, as written then
    meta = {k: v for k, v in s.record.meta.items() if k != "prior_terms"}
    old = prepare_state(storage, dataclasses.replace(s.record, meta=meta))
    assert old.loop.warm is not None and old.loop.warm.singles is None
    assert not old.loop.warm.data.tie.any()
    assert old.loop.warm.data.size == warm.data.size - int(warm.data.tie.sum())
    s.close()


def test_ratings_on_another_scale_are_left_out() -> None:
    storage = MemoryStorage()
    other = CONFIG.replace('labels = ["bad", "okay", "good"]', 'labels = ["no", "yes"]')
    with Session.create(storage, parse_config(other), "S01", seed=1) as e:
        for _ in range(4):
            q = e.next_query()
            given: list[object] = [Rating(q.actions[0], "yes")]
            if q.buffer and q.buffer[0] != q.actions[0]:
                given.append((q.actions[0], q.buffer[0], "first"))
            e.answer(q.id, given)
        earlier = e.id
    with Session.create(storage, parse_config(CONFIG), "S02", prior_from=[earlier]) as s:
        warm = s._state.loop.warm
        assert warm is not None and warm.singles is None and warm.data.size >= 1  # preferences
