"""An export of a session with gaits made on demand carries its made gaits: an import opens it
on a fresh database without making a gait again, checks each gait file (its SHA-256, its key
and its verdict against the log) and names a file that does not fit; an export without them
(written before they were carried) is imported by making the gaits again."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.errors import ExportError
from gaitpref.gaits import Gait
from gaitpref.sessions.export import export_session, import_session
from gaitpref.space import FloatArray
from tests.sessions.gaitkit import (
    CONFIG,
    CONTINUOUS,
    FakeSteps,
    logged_as_version_1,
    prefer_short_steps,
)


@pytest.fixture(autouse=True)
def _fresh_generator() -> Iterator[None]:
    FakeSteps.below, FakeSteps.calls = 0.3, []
    yield
    FakeSteps.below, FakeSteps.calls = 0.3, []


def _never(self: FakeSteps, vector: FloatArray, warm_start: Gait | None = None) -> Gait:
    raise AssertionError(f"the import made the gait of {vector} again")


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
    keys = {e.payload["key"] for e in s.events() if e.kind in ("gait_made", "gait_infeasible")}
    manifest = json.loads((folder / "manifest.json").read_text())
    assert set(manifest["made_gaits"]) == keys
    assert all(manifest["files"][f] for f in manifest["made_gaits"].values())
    monkeypatch.setattr(FakeSteps, "make", _never)
    url = f"sqlite:///{tmp_path / 'b' / 'lab.db'}"  # a fresh database directory
    imported = import_session(url, folder)
    assert imported.pending == s.pending and imported.next_query() == s.next_query()
    assert np.array_equal(imported.posterior().mean, s.posterior().mean)
    assert imported.infeasible_gaits() == s.infeasible_gaits()
    # the gaits went into the new database's cache: reopening makes none either
    assert {p.stem for p in (tmp_path / "b" / "lab.db.gaits").glob("*.json")} == keys
    again = Session.open(url, imported.id)
    assert again.pending == s.pending


def _rewrite(folder: Path, name: str, edit: dict[str, object], manifest_too: bool) -> None:
    """Change the gait file ``name``'s ``gait`` fields (and its SHA-256 in the manifest)."""
    path = folder / name
    doc = json.loads(path.read_text())
    doc["gait"].update(edit)
    path.write_text(json.dumps(doc))
    if manifest_too:
        manifest = json.loads((folder / "manifest.json").read_text())
        manifest["files"][name] = hashlib.sha256(path.read_bytes()).hexdigest()
        (folder / "manifest.json").write_text(json.dumps(manifest))


def _a_gait_file(folder: Path, feasible: bool) -> str:
    manifest = json.loads((folder / "manifest.json").read_text())
    for name in manifest["made_gaits"].values():
        if json.loads((folder / name).read_text())["gait"]["feasible"] == feasible:
            return str(name)
    raise AssertionError("no such gait in the export")


def test_a_tampered_gait_file_is_refused_naming_it(tmp_path: Path) -> None:
    _, folder = _exported(tmp_path, CONFIG)
    name = _a_gait_file(folder, feasible=True)
    _rewrite(folder, name, {"cot": 0.0}, manifest_too=False)
    url = f"sqlite:///{tmp_path / 'b' / 'lab.db'}"
    with pytest.raises(ExportError, match=rf"{name} does not match its SHA-256"):
        import_session(url, folder)
    assert not (tmp_path / "b" / "lab.db.gaits").exists()


def test_a_gait_file_whose_verdict_is_not_the_logs_is_refused(tmp_path: Path) -> None:
    _, folder = _exported(tmp_path, CONFIG)
    name = _a_gait_file(folder, feasible=False)  # made feasible, its hash made to match
    _rewrite(folder, name, {"feasible": True}, manifest_too=True)
    with pytest.raises(ExportError, match=rf"{name}: the log says the gait .* is infeasible"):
        import_session(f"sqlite:///{tmp_path / 'b' / 'lab.db'}", folder)


def test_a_gait_file_under_another_key_is_refused(tmp_path: Path) -> None:
    _, folder = _exported(tmp_path, CONFIG)
    manifest = json.loads((folder / "manifest.json").read_text())
    (first, name), (second, _) = list(manifest["made_gaits"].items())[:2]
    doc = json.loads((folder / name).read_text())
    doc["parameters"] = json.loads((folder / manifest["made_gaits"][second]).read_text())[
        "parameters"
    ]  # another gait's parameters under this key
    (folder / name).write_text(json.dumps(doc))
    manifest["files"][name] = hashlib.sha256((folder / name).read_bytes()).hexdigest()
    (folder / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(ExportError, match=rf"{name}: its generator, .* do not hash to its key"):
        import_session(f"sqlite:///{tmp_path / 'b' / 'lab.db'}", folder)
    assert first in name


def test_an_export_without_its_gaits_is_imported_by_making_them_again(tmp_path: Path) -> None:
    """A version-1 log (its events carry no gait) exported as before gaits were carried."""
    s, _ = _exported(tmp_path, CONFIG)
    old = Session.open(s.storage, logged_as_version_1(s.storage, s.id))
    folder = export_session(old, tmp_path / "old", "json").parent
    manifest = json.loads((folder / "manifest.json").read_text())
    for name in manifest.pop("made_gaits").values():  # as exports were written before
        del manifest["files"][name]
        (folder / name).unlink()
    (folder / "manifest.json").write_text(json.dumps(manifest))
    made = len(FakeSteps.calls)
    imported = import_session(f"sqlite:///{tmp_path / 'b' / 'lab.db'}", folder)
    assert imported.pending == s.pending
    assert len(FakeSteps.calls) > made  # made again
