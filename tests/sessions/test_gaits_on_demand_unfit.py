"""A logged gait that fails the checks a freshly made gait passes (``made_gait_problem``: an
edited or damaged database, or a release whose checks were weaker) replays as logged, with a
GaitCacheWarning naming the session, the event and the gait, but is not put into the gait cache
nor used as a warm start: an ask of that point from the cache makes it afresh."""

from __future__ import annotations

import dataclasses
import math
import shutil
import sqlite3
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gaitpref import Session
from gaitpref.gaits import GaitCache, GaitCacheWarning, OnDemandGaits
from gaitpref.gaits.gait_cache import CachedGait, read_gait
from gaitpref.storage import EventRecord, NewEvent
from tests.sessions.gaitkit import GAIT_EVENTS, FakeSteps, copied, fresh_fake_steps, never_made
from tests.sessions.test_gaits_on_demand_log import _recorded, _sqlite, _state


@pytest.fixture(autouse=True)
def _fresh_generator() -> Iterator[None]:
    yield from fresh_fake_steps(0.5)  # half the steps have no gait


def _lone(s: Session) -> EventRecord:
    """The first ``gait_made`` of ``s`` whose key no other gait event has (gaits whose ids
    differ by a label share a key)."""
    keys = [e.payload["key"] for e in s.storage.events(s.id) if e.kind in GAIT_EVENTS]
    return next(
        e
        for e in s.storage.events(s.id)
        if e.kind == "gait_made" and keys.count(e.payload["key"]) == 1
    )


def _damaged(s: Session, change: dict[str, Any]) -> tuple[int, EventRecord]:
    """A copy of ``s`` whose first ``gait_made`` gait has ``change``: (copy's id, the event)."""
    target = _lone(s)

    def edit(e: EventRecord) -> NewEvent | None:
        if e.seq != target.seq:
            return None
        return NewEvent(e.kind, {**e.payload, "gait": {**e.payload["gait"], **change}}, e.at,
                        e.version)  # fmt: skip

    return copied(s.storage, s.id, edit), target


#: stands in for NaN when the copy is written (storage writes JSON without NaN), then replaced
#: in the SQLite file itself, as a damaged or edited database would hold it
_NAN = -123456.75


def _with_nan(db: Path, session_id: int, seq: int) -> None:
    with sqlite3.connect(db) as raw:
        (text,) = raw.execute(
            "SELECT payload FROM events WHERE session_id = ? AND seq = ?", (session_id, seq)
        ).fetchone()
        assert str(_NAN) in text
        triggers = raw.execute(
            "SELECT name, sql FROM sqlite_master WHERE type = 'trigger' AND tbl_name = 'events'"
        ).fetchall()
        for name, _ in triggers:  # the append-only guard: as an edit outside gaitpref would
            raw.execute(f"DROP TRIGGER {name}")
        raw.execute(
            "UPDATE events SET payload = ? WHERE session_id = ? AND seq = ?",
            (text.replace(str(_NAN), "NaN"), session_id, seq),
        )
        for _, sql in triggers:
            raw.execute(sql)


@pytest.mark.parametrize(
    ("change", "says"),
    [
        ({"max_friction_ratio": _NAN}, "constraint residuals"),
        ({"max_friction_ratio": -0.5}, "negative friction ratio"),
    ],
    ids=["nan-residual", "negative-friction"],
)
def test_an_unfit_logged_gait_replays_but_is_not_cached_and_is_made_afresh(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, change: dict[str, Any], says: str
) -> None:
    s = _recorded(_sqlite(tmp_path))
    mean = np.asarray(s.posterior().mean)
    bad, target = _damaged(s, change)
    if change == {"max_friction_ratio": _NAN}:
        _with_nan(tmp_path / "lab.db", bad, target.seq)
    stored = next(e for e in s.storage.events(bad) if e.seq == target.seq)
    assert read_gait(stored.payload["gait"], "stored").feasible  # reads as a gait
    key = target.payload["key"]
    folder = tmp_path / "lab.db.gaits"
    shutil.rmtree(folder)
    with monkeypatch.context() as m:
        m.setattr(FakeSteps, "make", never_made)  # replay takes every gait from the log
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            again = Session.open(_sqlite(tmp_path), bad)
    said = [str(w.message) for w in caught if issubclass(w.category, GaitCacheWarning)]
    assert len(said) == 1, said
    assert f"session {bad}, event {target.seq} (gait_made)" in said[0]
    assert key in said[0] and target.payload["gait_id"] in said[0] and says in said[0]
    # replay follows the log: the same trials, infeasible gaits, query and posterior
    assert _state(again)[:3] == _state(s)[:3]
    assert np.array_equal(np.asarray(again.posterior().mean), mean)
    assert again.next_query() == s.next_query()
    # ... but the unfit gait is not cached; every other logged gait is
    assert not (folder / f"{key}.json").exists()
    assert (folder / f"{key}.json") not in set(folder.glob("*.json"))
    assert len(list(folder.glob("*.json"))) > 0
    # an ask of that point from the cache makes it afresh (as for a gait not cached)
    values = target.payload["values"]
    generator = FakeSteps(list(values), {})
    gaits = OnDemandGaits(generator, GaitCache(folder), [1.0] * len(values))
    calls = len(FakeSteps.calls)
    made, new = gaits.get(np.array([values[f] for f in values], dtype=np.float64))
    assert new and not made.from_cache and made.key == key
    assert len(FakeSteps.calls) == calls + 1
    assert made.feasible and math.isfinite(made.gait.max_friction_ratio)
    assert made.gait.max_friction_ratio >= 0


def test_an_unfit_gait_in_the_cache_folder_is_made_afresh(tmp_path: Path) -> None:
    """Pins the cache reader's side: a cache file whose gait fails the check (edited, or
    written before gaits were checked) is not used; the gait is made again and rewritten."""
    s = _recorded(_sqlite(tmp_path))
    target = _lone(s)
    key, values = target.payload["key"], target.payload["values"]
    path = tmp_path / "lab.db.gaits" / f"{key}.json"
    text = path.read_text()
    import json

    doc = json.loads(text)
    doc["gait"]["max_friction_ratio"] = -0.5
    path.write_text(json.dumps(doc))
    gaits = OnDemandGaits(FakeSteps(list(values), {}), GaitCache(path.parent), [1.0] * len(values))
    calls = len(FakeSteps.calls)
    made, _ = gaits.get(np.array([values[f] for f in values], dtype=np.float64))
    assert len(FakeSteps.calls) == calls + 1 and not made.from_cache
    assert made.gait.max_friction_ratio >= 0
    assert json.loads(path.read_text())["gait"]["max_friction_ratio"] >= 0


def test_an_unfit_recorded_gait_is_neither_cached_nor_a_warm_start(tmp_path: Path) -> None:
    """The gaits layer alone: a recorded gait with a NaN residual is handed back as recorded (so
    replay follows the log), with a warning, but the cache (folder and memory) keeps nothing of
    it, the next gait made is not warm-started from it, and a fresh view of the cache makes it."""
    generator = FakeSteps(["step_length"], {})
    cache = GaitCache(tmp_path / "cache")
    point = np.array([0.8])
    good = generator.make(point)
    bad = dataclasses.replace(good, max_friction_ratio=math.nan)
    key = generator.key(point)
    gaits = OnDemandGaits(generator, cache, [1.0])
    with pytest.warns(GaitCacheWarning, match=rf"the session's log: .* \(key {key}\) .* residuals"):
        made, new = gaits.get(point, lambda k: CachedGait(k, bad, None))
    assert new and made.gait is bad and made.from_cache  # as recorded
    path = cache.path(key)
    assert path is not None and not path.exists()
    assert cache.get(key) is None and gaits.nearest(np.array([0.9])) is None
    again, _ = gaits.get(point)
    assert again is made  # the session knows the point: replay must not make it again
    fresh = OnDemandGaits(generator, cache, [1.0])
    calls = len(FakeSteps.calls)
    remade, _ = fresh.get(point)
    assert len(FakeSteps.calls) == calls + 1 and not remade.from_cache
    assert math.isfinite(remade.gait.max_friction_ratio)
    assert cache.get(key) is not None
