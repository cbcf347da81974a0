"""Fixtures for session tests: databases and a deterministic simulated subject."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from gaitpref import GaitLibrary, Session, load_config
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.storage import MemoryStorage, Storage
from tests.sessions.gaitkit import fresh_fake_steps
from tests.sessions.sessionkit import CONFIG, Drive


@pytest.fixture
def sqlite_url(tmp_path: Path) -> str:
    return f"sqlite:///{tmp_path / 'sessions.db'}"


@pytest.fixture(params=["memory", "sqlite"])
def db(request: pytest.FixtureRequest, tmp_path: Path) -> str | Storage:
    """A database for a session test: an in-memory store or a SQLite file URL."""
    if request.param == "memory":
        return MemoryStorage()
    return f"sqlite:///{tmp_path / 'sessions.db'}"


@pytest.fixture
def subject() -> SimulatedSubject:
    space = load_config(CONFIG).space
    return SimulatedSubject(space, bump_utility(space), seed=1)


@pytest.fixture
def drive(subject: SimulatedSubject) -> Drive:
    """Answer ``n`` queries of a session as the simulated subject would."""

    def run(session: Session, n: int) -> None:
        for _ in range(n):
            q = session.next_query()
            comparisons, suggestions = subject.respond(q)
            session.answer(q.id, comparisons, suggestions)

    return run


@pytest.fixture(autouse=True)
def _fresh_fake_steps() -> Iterator[None]:
    """Every test starts with the fake gait generator as :mod:`tests.sessions.gaitkit` makes it."""
    yield from fresh_fake_steps()


@pytest.fixture(scope="module")
def library() -> GaitLibrary:
    """A small gait library (four step lengths at 0.2 m/s), built once per module."""
    from gaitpref.gaits.build import build_library

    return build_library([0.10, 0.12, 0.14, 0.16], speed=0.2, n_jobs=1)
