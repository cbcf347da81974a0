"""Gait library files and gait cache entries, written atomically (a temporary file renamed over
the target), get the mode a plain ``open(path, "w")`` would give them: 0666 less the umask for
a new file, the old file's mode for one rewritten.  They were ``tempfile.mkstemp``'s 0600, so on
a shared lab machine the group could not read a library or a cache entry (``gaitpref.atomic``).
"""

from __future__ import annotations

import json
import os
import stat
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from gaitpref.gaits import CachedGait, GaitCache, GaitLibrary

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX modes and umask")


@pytest.fixture
def umask() -> Iterator[None]:
    """Restore the process umask after a test that sets it."""
    old = os.umask(0o022)
    os.umask(old)
    yield
    os.umask(old)


def _mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


@pytest.mark.usefixtures("umask")
@pytest.mark.parametrize("mask", [0o022, 0o002, 0o077])
def test_a_saved_library_has_the_mode_open_would_give_it(
    duration_library: GaitLibrary, tmp_path: Path, mask: int
) -> None:
    os.umask(mask)
    target = tmp_path / "lib.json"
    duration_library.save(target)
    assert _mode(target) == 0o666 & ~mask
    assert [p.name for p in tmp_path.iterdir()] == ["lib.json"]  # no temporary file left


@pytest.mark.usefixtures("umask")
def test_a_library_saved_over_another_keeps_its_mode(
    duration_library: GaitLibrary, tmp_path: Path
) -> None:
    os.umask(0o077)
    target = tmp_path / "lib.json"
    target.write_text("{}")
    target.chmod(0o640)  # the lab's group may read it
    duration_library.save(target)
    assert _mode(target) == 0o640 and target.read_text() != "{}"


@pytest.mark.usefixtures("umask")
@pytest.mark.parametrize("mask", [0o022, 0o002])
def test_a_gait_cache_entry_has_the_mode_open_would_give_it(
    duration_library: GaitLibrary, tmp_path: Path, mask: int
) -> None:
    os.umask(mask)
    cache = GaitCache(tmp_path / "gaits")
    key = "ab" * 32
    cache.put(CachedGait(key, duration_library.gaits[0], None), {"generator": "test"})
    entry = tmp_path / "gaits" / f"{key}.json"
    assert _mode(entry) == 0o666 & ~mask
    assert [p.name for p in entry.parent.iterdir()] == [entry.name]
    assert json.loads(entry.read_text())["key"] == key  # written whole
