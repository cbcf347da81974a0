"""The gait cache's files keep their own fields: a document (generator, settings, parameters
and a generator's own fields) that names one of them is refused before anything is kept."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitpref.gaits import CachedGait, GaitCache, make_generator
from gaitpref.gaits.gait import Gait
from gaitpref.gaits.gait_cache import FILE_FIELDS, read_entry


def _gait() -> Gait:
    """An infeasible gait of step length 0.12 (what the cache keeps needs no optimisation)."""
    return Gait(
        step_length=0.12,
        step_duration=1.0,
        alpha=np.zeros((1, 7)),
        phase_start=-0.1,
        phase_end=0.1,
        orbit_state=np.zeros(4),
        cot=1.0,
        delta_squared=0.9,
        feasible=False,
        status=8,
        message="infeasible: made up",
        min_normal_force=100.0,
        max_friction_ratio=0.1,
    )


@pytest.mark.parametrize("field", ["format", "schema_version", "key", "warm_start", "gait"])
def test_a_document_naming_a_field_of_the_file_is_refused_and_nothing_kept(
    tmp_path: Path, field: str
) -> None:
    g = make_generator("compass-hzd", ["step_length"], {"speed": 0.2})
    vector = np.array([0.12])
    document = {**g.document(vector), field: "mine"}
    cache = GaitCache(tmp_path)
    key = g.key(vector)
    with pytest.raises(ValueError, match=f"field {field!r}"):
        cache.put(CachedGait(key, _gait(), None), document)
    assert cache.get(key) is None and list(tmp_path.iterdir()) == []
    assert field in FILE_FIELDS


def test_a_document_with_fields_of_its_own_is_kept_beside_the_file_fields(tmp_path: Path) -> None:
    g = make_generator("compass-hzd", ["step_length"], {"speed": 0.2})
    vector = np.array([0.12])
    key = g.key(vector)
    GaitCache(tmp_path).put(CachedGait(key, _gait(), None), {**g.document(vector), "notes": 1})
    entry, document = read_entry(tmp_path / f"{key}.json", key)
    assert entry.key == key and entry.gait.step_length == 0.12 and not entry.gait.feasible
    assert document == g.document(vector)


def test_an_entry_over_the_size_limit_is_not_read_whole_and_is_not_used(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A cache file of any size was read whole (one gait is a few kB)."""
    from gaitpref.errors import GaitLibraryError
    from gaitpref.gaits import gait_cache

    g = make_generator("compass-hzd", ["step_length"], {"speed": 0.2})
    vector = np.array([0.12])
    key = g.key(vector)
    GaitCache(tmp_path).put(CachedGait(key, _gait(), None), g.document(vector))
    path = tmp_path / f"{key}.json"
    size = path.stat().st_size
    assert gait_cache.MAX_ENTRY_BYTES == 16 * 2**20
    monkeypatch.setattr(gait_cache, "MAX_ENTRY_BYTES", size - 1)
    with pytest.raises(GaitLibraryError, match=rf"{key}\.json: larger than the {size - 1:,} bytes"):
        read_entry(path, key)
    assert GaitCache(tmp_path).get(key) is None  # refused: made again, not loaded
    monkeypatch.setattr(gait_cache, "MAX_ENTRY_BYTES", size)
    assert GaitCache(tmp_path).get(key) is not None
