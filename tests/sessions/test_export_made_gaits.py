"""An export of a session with gaits made on demand carries its made gaits in its log
(``events.jsonl``, ``gait_made`` version 2): an import opens it on a fresh database without making
a gait again and fills the new database's gait cache; a gait edited in the export is refused,
naming its event; a log written before (version 1) is imported by making its gaits again, also
from an export that carries them as files (``gaits/``, a format that was never released)."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from gaitpref import ReplayError, Session
from gaitpref.config import parse_config
from gaitpref.gaits import GaitCacheWarning
from gaitpref.sessions.export import export_session, import_session
from tests.sessions.gaitkit import (
    CONFIG,
    CONTINUOUS,
    GAIT_EVENTS,
    FakeSteps,
    logged_as_version_1,
    never_made,
    prefer_short_steps,
)


def _exported(tmp_path: Path, text: str) -> tuple[Session, Path]:
    """A session driven to short (infeasible) steps, a query pending, exported."""
    for sub in ("a", "b"):
        (tmp_path / sub).mkdir()
    FakeSteps.below = 0.5  # half the steps have no gait
    s = Session.create(f"sqlite:///{tmp_path / 'a' / 'lab.db'}", parse_config(text), "S01")
    prefer_short_steps(s, 14)
    s.next_query()  # pending: the import must come back to it
    assert s.infeasible_gaits(), "the subject's short steps reach infeasible gaits"
    return s, export_session(s, tmp_path / "export", "json").parent


@pytest.mark.parametrize("text", [CONTINUOUS, CONFIG], ids=["continuous", "grid"])
def test_an_import_opens_without_making_a_gait_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, text: str
) -> None:
    s, folder = _exported(tmp_path, text)
    keys = {e.payload["key"] for e in s.events() if e.kind in GAIT_EVENTS}
    manifest = json.loads((folder / "manifest.json").read_text())
    assert "made_gaits" not in manifest and not (folder / "gaits").exists()  # the log has them
    monkeypatch.setattr(FakeSteps, "make", never_made)
    url = f"sqlite:///{tmp_path / 'b' / 'lab.db'}"  # a fresh database directory
    imported = import_session(url, folder)
    assert imported.pending == s.pending and imported.next_query() == s.next_query()
    assert np.array_equal(imported.posterior().mean, s.posterior().mean)
    assert imported.infeasible_gaits() == s.infeasible_gaits()
    # the gaits went into the new database's cache too
    assert {p.stem for p in (tmp_path / "b" / "lab.db.gaits").glob("*.json")} == keys
    again = Session.open(url, imported.id)
    assert again.pending == s.pending


def _edit_log(folder: Path, kind: str, feasible: bool) -> int:
    """Make the first ``kind`` event's gait ``feasible`` in ``events.jsonl`` (its SHA-256 in
    the manifest updated): the event's seq."""
    path = folder / "events.jsonl"
    lines = [json.loads(line) for line in path.read_text().splitlines()]
    event = next(e for e in lines if e["kind"] == kind)
    event["payload"]["gait"]["feasible"] = feasible
    path.write_text("".join(json.dumps(e) + "\n" for e in lines))
    manifest = json.loads((folder / "manifest.json").read_text())
    manifest["files"]["events.jsonl"] = hashlib.sha256(path.read_bytes()).hexdigest()
    (folder / "manifest.json").write_text(json.dumps(manifest))
    return int(event["seq"])


def test_a_gait_edited_in_the_export_is_refused_naming_its_event(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    _, folder = _exported(tmp_path, CONFIG)
    seq = _edit_log(folder, "gait_infeasible", feasible=True)
    monkeypatch.setattr(FakeSteps, "make", never_made)
    with pytest.raises(ReplayError, match=rf"event {seq} \(gait_infeasible\): the logged gait"):
        import_session(f"sqlite:///{tmp_path / 'b' / 'lab.db'}", folder)
    assert not (tmp_path / "b" / "lab.db").exists()  # refused before the database is opened


def _with_gait_files(folder: Path, cache: Path, keys: set[str]) -> None:
    """Add the gait files and manifest entries an export of branch h-gaits13 carried (never
    released): ``gaits/<key>.json`` as the cache keeps it, listed with its SHA-256 under
    ``files`` and under ``made_gaits``."""
    manifest = json.loads((folder / "manifest.json").read_text())
    (folder / "gaits").mkdir()
    manifest["made_gaits"] = {}
    for key in sorted(keys):
        name = f"gaits/{key}.json"
        shutil.copyfile(cache / f"{key}.json", folder / name)
        manifest["files"][name] = hashlib.sha256((folder / name).read_bytes()).hexdigest()
        manifest["made_gaits"][key] = name
    (folder / "manifest.json").write_text(json.dumps(manifest))


@pytest.mark.parametrize("files", [False, True], ids=["log-only", "with-gait-files"])
def test_a_version_1_export_is_imported_by_making_its_gaits_again(
    tmp_path: Path, files: bool
) -> None:
    s, _ = _exported(tmp_path, CONFIG)
    old = Session.open(s.storage, logged_as_version_1(s.storage, s.id))
    folder = export_session(old, tmp_path / "old", "json").parent
    if files:
        keys = {e.payload["key"] for e in s.events() if e.kind in GAIT_EVENTS}
        _with_gait_files(folder, tmp_path / "a" / "lab.db.gaits", keys)
    made = len(FakeSteps.calls)
    imported = import_session(f"sqlite:///{tmp_path / 'b' / 'lab.db'}", folder)
    assert (imported.pending, imported.trials()) == (s.pending, s.trials())
    assert imported.infeasible_gaits() == s.infeasible_gaits()
    assert len(FakeSteps.calls) == 3 * made  # each gait made again by both replays


@pytest.mark.parametrize("how", ["folder cannot be made", "disk full"])
def test_a_gait_cache_that_cannot_be_written_does_not_stop_a_session(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, how: str
) -> None:
    """The cache is derived data (the log carries every gait): before, an import wrote the
    session and then failed with an OSError, and the session could not be opened there at all."""
    s, folder = _exported(tmp_path, CONFIG)
    url = f"sqlite:///{tmp_path / 'b' / 'lab.db'}"
    if how == "folder cannot be made":
        (tmp_path / "b" / "lab.db.gaits").write_text("a file where the folder goes")
    else:

        def full(*args: object, **kwargs: object) -> None:
            raise OSError(28, "No space left on device")

        monkeypatch.setattr("gaitpref.atomic.os.replace", full)
    with pytest.warns(GaitCacheWarning, match="gaits are kept in memory"):
        imported = import_session(url, folder)
    assert imported.pending == s.pending and imported.next_query() == s.next_query()
    assert imported._gait_cache is not None and imported._gait_cache.unwritable
    with pytest.warns(GaitCacheWarning):
        again = Session.open(url, imported.id)
        prefer_short_steps(again, 2)  # new gaits are made and logged, the cache still unwritable
    with pytest.warns(GaitCacheWarning):
        assert Session.open(url, imported.id).last_seq == again.last_seq
    assert not list((tmp_path / "b").glob("lab.db.gaits/.*"))  # no temporary file left
