"""Listing sessions and subjects, and catching up with another writer, through the Session API."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitpref import Session, load_config
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from tests.sessions.sessionkit import CONFIG


def test_list_sessions_and_subjects(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    ids = [Session.create(url, CONFIG, s, seed=1).id for s in ("S02", "S01", "S02")]
    assert [r.id for r in Session.list_sessions(url)] == sorted(ids)
    assert [r.subject for r in Session.list_sessions(url, "S02")] == ["S02", "S02"]
    assert [s.code for s in Session.list_subjects(url)] == ["S01", "S02"]


def test_sync_replays_only_what_another_writer_appended(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    writer = Session.create(url, CONFIG, "S01", seed=3)
    reader = Session.open(url, writer.id)
    assert reader.sync() is False
    subject = SimulatedSubject(writer.config.space, bump_utility(writer.config.space), seed=0)
    for _ in range(4):
        q = writer.next_query()
        writer.answer(q.id, *subject.respond(q))
    writer.undo()
    assert reader.sync() is True
    assert reader.last_seq == writer.last_seq
    np.testing.assert_array_equal(reader.posterior().mean, writer.posterior().mean)
    assert reader.next_query() == writer.next_query()
    assert reader.sync() is False


def test_sync_says_it_caught_up_after_an_ask_that_proposed_nothing(tmp_path: Path) -> None:
    """An ask that raises (no gait left to propose) leaves the object to be rebuilt by its
    next call; ``sync`` rebuilt it, caught up with another writer's note, and said False."""
    from gaitpref.config import parse_config
    from gaitpref.errors import NoSafeGaitError

    text = load_config(CONFIG).text + "\n[safety]\nunsafe_radius = 1.0\n"
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with Session.create(url, parse_config(text), "S01", seed=3) as live:
        q = live.next_query()
        live.answer(q.id, [])
        live.flag_unsafe(1, "knee")  # within the radius of every gait
        with pytest.raises(NoSafeGaitError):
            live.next_query()
        with Session.open(url, live.id) as other:
            other.note("from another writer")
        assert live.sync() is True
        assert live.notes()[-1][1] == "from another writer"
        assert live.sync() is False
