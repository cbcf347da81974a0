"""What ``GaitCache.put`` keeps when writing its file fails.

A failure of the folder (``OSError``: read-only, a file in its place, a full disk) keeps the gait
in memory with a :class:`GaitCacheWarning` naming the file, by design: the cache is derived data
and the session's log carries the gait (``docs/gaits.md``).  Any other failure of the write (an
entry that cannot be written as JSON) keeps nothing: before, the entry was remembered before the
write, so the cache went on serving a gait its file never held.
"""

from __future__ import annotations

import errno
from pathlib import Path

import numpy as np
import pytest
from tests.gaits.test_gait_cache_fields import _gait

from gaitpref.gaits import CachedGait, GaitCache, GaitCacheWarning, gait_cache, make_generator


def _entry() -> tuple[CachedGait, dict[str, object]]:
    g = make_generator("compass-hzd", ["step_length"], {"speed": 0.2})
    vector = np.array([0.12])
    return CachedGait(g.key(vector), _gait(), None), g.document(vector)


def test_a_write_that_fails_otherwise_than_the_folder_keeps_nothing_and_names_the_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def broken(target: Path, text: str, prefix: str) -> None:
        raise ValueError("Out of range float values are not JSON compliant")

    monkeypatch.setattr(gait_cache, "write_text_atomic", broken)
    entry, document = _entry()
    cache = GaitCache(tmp_path)
    with pytest.raises(ValueError, match="not JSON compliant") as caught:
        cache.put(entry, document)
    assert str(tmp_path / f"{entry.key}.json") in str(caught.value)
    assert "nothing is cached" in str(caught.value)
    assert cache.get(entry.key) is None, "the cache serves a gait its file does not hold"
    assert cache.unwritable is None


def test_a_full_disk_keeps_the_gait_in_memory_and_warns_naming_the_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def full(target: Path, text: str, prefix: str) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(gait_cache, "write_text_atomic", full)
    entry, document = _entry()
    cache = GaitCache(tmp_path)
    with pytest.warns(GaitCacheWarning, match=f"cannot write {entry.key}.json"):
        cache.put(entry, document)
    assert cache.unwritable is not None and "No space left" in cache.unwritable
    assert cache.get(entry.key) is entry  # in memory, as the log holds it
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    assert GaitCache(tmp_path).get(entry.key) is None  # not on disk: another session makes it
