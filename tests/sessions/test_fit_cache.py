"""A session's remembered fits beside its SQLite database (``sessions/fit_cache.py``): reopening
with them rebuilds exactly the state a reopening without them does, checks fits instead of
making them, and a missing, damaged or foreign file is only a cache missed."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from gaitpref import Session, load_config
from gaitpref.model import fit_memo
from gaitpref.model.fit_memo import FitMemo
from gaitpref.sessions import fit_cache
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.sessions.fit_cache import FITS_SUFFIX, load_memo, memo_path
from gaitpref.storage import MemoryStorage, open_storage
from tests.sessions.sessionkit import CONFIG, state_of


def _answer(session: Session, subject: SimulatedSubject, answers: int) -> None:
    for _ in range(answers):
        q = session.next_query()
        comparisons, suggestions = subject.respond(q)
        session.answer(q.id, comparisons, suggestions)


@pytest.fixture(autouse=True)
def _every_fit_remembered(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fit_memo, "MEMO_FROM", 1)  # this config's fits visit a few gaits


def _warm_session(url: str) -> int:
    space = load_config(CONFIG).space
    for code, seed in (("S01", 1), ("S02", 2)):
        with Session.create(url, CONFIG, code, seed=seed) as s:
            _answer(s, SimulatedSubject(space, bump_utility(space), seed=seed), 5)
    with Session.create(url, CONFIG, "S03", seed=5, prior_from=["S01", "S02"]) as s:
        subject = SimulatedSubject(space, bump_utility(space), seed=5)
        _answer(s, subject, 4)
        s.undo()
        _answer(s, subject, 2)
        return s.id


def _hits(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Counts the fits answered from a memo (``[hits]``)."""
    hits = [0]
    real = FitMemo.get

    def counted(self: FitMemo, key: bytes) -> fit_memo.Remembered | None:
        out = real(self, key)
        hits[0] += out is not None
        return out

    monkeypatch.setattr(FitMemo, "get", counted)
    return hits


def test_reopening_with_the_remembered_fits_rebuilds_the_same_state(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    db = tmp_path / "lab.db"
    url = f"sqlite:///{db}"
    sid = _warm_session(url)
    cache = memo_path(open_storage(url), sid)
    assert cache == Path(f"{db}{FITS_SUFFIX}") / f"{sid}.npz"
    assert cache.is_file() and len(load_memo(cache)) > 10
    hits = _hits(monkeypatch)
    with Session.open(url, sid) as s:
        remembered = state_of(s)
    with_memo, hits[0] = hits[0], 0
    shutil.rmtree(cache.parent)
    with Session.open(url, sid) as s:
        fresh = state_of(s)
    # without the file only the fits a replay makes twice are checked (the same problem met
    # again within it); with it, every fit the recording made
    assert with_memo > hits[0] + 10
    assert cache.is_file()  # and remembered for the next opening
    for a, b in zip(remembered[:2], fresh[:2], strict=True):
        assert np.array_equal(a, b)
    assert remembered[2:] == fresh[2:]


@pytest.mark.parametrize(
    "content", [b"not an npz", b"", b"PK\x03\x04 truncated zip"], ids=["text", "empty", "zip"]
)
def test_a_damaged_memo_is_a_cache_missed(tmp_path: Path, content: bytes) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    sid = _warm_session(url)
    cache = memo_path(open_storage(url), sid)
    assert cache is not None
    with Session.open(url, sid) as s:
        expected = state_of(s)
    cache.write_bytes(content)
    assert len(load_memo(cache)) == 0
    with Session.open(url, sid) as s:
        got = state_of(s)
    assert np.array_equal(got[0], expected[0]) and got[2:] == expected[2:]


def test_a_memo_of_other_shapes_is_ignored(tmp_path: Path) -> None:
    path = tmp_path / "x.npz"
    np.savez(path, keys=np.zeros((2, 31), np.uint8), norms=np.zeros(2),
             offsets=np.array([0, 1, 2]), modes=np.zeros(2))  # fmt: skip
    assert len(load_memo(path)) == 0
    np.savez(path, keys=np.zeros((1, 32), np.uint8), norms=np.zeros(1),
             offsets=np.array([0, 5]), modes=np.zeros(2))  # fmt: skip
    assert len(load_memo(path)) == 0


def test_a_database_that_is_not_a_local_file_keeps_the_memo_in_the_process() -> None:
    storage = MemoryStorage()
    assert memo_path(storage, 1) is None
    space = load_config(CONFIG).space
    with Session.create(storage, CONFIG, "S01", seed=1) as s:
        _answer(s, SimulatedSubject(space, bump_utility(space), seed=1), 3)
        assert len(s._memo) > 0


def test_a_memo_with_values_that_are_not_finite_is_ignored(tmp_path: Path) -> None:
    path = tmp_path / "x.npz"
    np.savez(path, keys=np.zeros((1, 32), np.uint8), norms=np.zeros(1),
             offsets=np.array([0, 2]), modes=np.array([0.0, np.nan]))  # fmt: skip
    assert len(load_memo(path)) == 0


def test_undo_with_the_factors_dropped_and_the_fits_remembered_reopens_as_it_ran(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from gaitpref.loop import cospar

    monkeypatch.setattr(cospar, "STRIP_FROM_VISITED", 0)  # every answer keeps no factors
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    sid = _warm_session(url)
    space = load_config(CONFIG).space
    with Session.open(url, sid) as s:
        s.undo()
        s.undo()
        _answer(s, SimulatedSubject(space, bump_utility(space), seed=9), 2)
        s.undo()
        live = state_of(s)
    with Session.open(url, sid) as s:  # replayed with the remembered fits
        again = state_of(s)
    assert np.array_equal(live[0], again[0]) and np.array_equal(live[1], again[1])
    assert live[2:] == again[2:]


def test_a_memo_that_unpacks_past_the_limit_is_ignored_before_it_is_unpacked(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A compressed memo is small on disk and large unpacked: only its file size was checked,
    so a 256 MiB file could unpack to far more.  Its members' unpacked sizes count now."""
    monkeypatch.setattr(fit_cache, "MAX_FILE_BYTES", 1_000_000)
    path = tmp_path / "x.npz"
    n = 200_000  # 1.6 MB of modes, a few kB compressed
    np.savez_compressed(path, keys=np.zeros((1, 32), np.uint8), norms=np.zeros(1),
                        offsets=np.array([0, n]), modes=np.zeros(n))  # fmt: skip
    assert path.stat().st_size < 100_000
    assert len(load_memo(path)) == 0
    np.savez_compressed(path, keys=np.zeros((1, 32), np.uint8), norms=np.zeros(1),
                        offsets=np.array([0, 1000]), modes=np.zeros(1000))  # fmt: skip
    assert len(load_memo(path)) == 1  # within the limit, compressed or not
