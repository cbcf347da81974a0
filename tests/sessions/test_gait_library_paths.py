"""A config naming its gait library outside its own folder: ``library = "../libs/x.json"``, an
absolute path, or a path through a symbolic link.  ``session new`` refused the first and the last
("cannot tell which folder the config's gait library path ... is relative to; load the config
from its file", for a config loaded from its file): the folder was guessed back from the
library's resolved path, which ``..`` and links do not allow.  An export of such a session held
no copy of the library (an import elsewhere could not open it); and an imported session read the
export folder's copy, so deleting the folder made it unopenable (now, in a SQLite database, it
keeps its own copy beside the database)."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref import GaitLibrary, ReplayError, Session, load_config
from gaitpref.cli import app
from gaitpref.errors import ExportError, StorageError
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.sessions.export import export_session, import_session
from gaitpref.storage import MemoryStorage, open_storage
from gaitpref.storage.sql import SQLStorage
from tests.lockwatch import BOUND_S, Other, watch_locks
from tests.sessions import test_gait_library as gait_library_test

#: test_gait_library.py's config, its library named by the test
CONFIG = gait_library_test.CONFIG.replace('library = "lib/gaits.json"', 'library = "{library}"')


def lab(root: Path, library: GaitLibrary, named: str | None = None) -> Path:
    """``root/configs/c.toml`` naming ``root/libs/x.json`` by ``named`` (default ``../libs/x.json``;
    ``{abs}`` stands for the library's absolute path); returns the config's path."""
    (root / "configs").mkdir(parents=True, exist_ok=True)
    (root / "libs").mkdir()
    library.save(root / "libs" / "x.json")
    given = (named or "../libs/x.json").replace("{abs}", str(root / "libs" / "x.json"))
    (root / "configs" / "c.toml").write_text(CONFIG.replace("{library}", str(given)))
    return root / "configs" / "c.toml"


def library_files(folder: Path) -> list[str]:
    """The names in a library folder, less its lock files (``.<sha256>.lock``: left there)."""
    return sorted(p.name for p in folder.iterdir() if not p.name.endswith(".lock"))


def drive(s: Session, n: int) -> None:
    subject = SimulatedSubject(s.config.space, bump_utility(s.config.space), seed=0)
    for _ in range(n):
        q = s.next_query()
        s.answer(q.id, *subject.respond(q))


def test_a_library_up_a_folder_starts_and_replays(
    tmp_path: Path, library: GaitLibrary, monkeypatch: pytest.MonkeyPatch
) -> None:
    config = lab(tmp_path / "study", library)
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, config, "S01")
    assert s.record.meta["config_dir"] == str((tmp_path / "study" / "configs").resolve())
    assert s.record.meta["library_path"] == str((tmp_path / "study" / "libs" / "x.json").resolve())
    assert s.gait_ids == [library.gait_id(a) for a in range(len(library))]
    drive(s, 4)
    monkeypatch.chdir(tmp_path)  # replay takes the path from the config's folder, not from here
    again = Session.open(url, s.id)
    np.testing.assert_array_equal(again.posterior().mean, s.posterior().mean)
    assert again.next_query() == s.next_query()
    # a loaded config works too
    assert Session.create(url, load_config(config), "S02").gait_ids == s.gait_ids


def test_session_new_with_a_library_up_a_folder(
    tmp_path: Path, library: GaitLibrary, monkeypatch: pytest.MonkeyPatch
) -> None:
    lab(tmp_path, library)
    monkeypatch.chdir(tmp_path)
    db = str(tmp_path / "lab.db")
    result = CliRunner().invoke(
        app, ["session", "new", "--config", "configs/c.toml", "--subject", "S01", "--db", db]
    )
    assert result.exit_code == 0, result.output
    assert "session 1" in result.output
    assert Session.open(db, 1).gait_ids == [library.gait_id(a) for a in range(len(library))]


@pytest.mark.skipif(not hasattr(os, "symlink"), reason="no symbolic links")
def test_a_library_reached_through_a_link(tmp_path: Path, library: GaitLibrary) -> None:
    config = lab(tmp_path, library, "lib/x.json")
    (config.parent / "lib").mkdir()
    (config.parent / "lib" / "x.json").symlink_to(tmp_path / "libs" / "x.json")
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, config, "S01")
    drive(s, 2)
    assert Session.open(url, s.id).gait_ids == s.gait_ids


def test_an_absolute_library_path(tmp_path: Path, library: GaitLibrary) -> None:
    config = lab(tmp_path, library, "{abs}")
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, config, "S01")
    drive(s, 2)
    assert Session.open(url, s.id).gait_ids == s.gait_ids


# -- export and import ---------------------------------------------------------------------------
def exported(
    tmp_path: Path, library: GaitLibrary, named: str | None = None
) -> tuple[Session, Path]:
    """A session over ``lab``'s config, answered 4 times and exported to ``tmp_path/export``."""
    s = Session.create(
        f"sqlite:///{tmp_path / 'lab.db'}", lab(tmp_path / "study", library, named), "S01"
    )
    drive(s, 4)
    export_session(s, tmp_path / "export", "csv")
    return s, tmp_path / "export"


def edit_manifest(out: Path, edit: Callable[[dict[str, Any]], object]) -> None:
    manifest = json.loads((out / "manifest.json").read_text())
    edit(manifest)
    (out / "manifest.json").write_text(json.dumps(manifest))


@pytest.mark.parametrize("named", ["../libs/x.json", "{abs}"])
def test_the_export_carries_a_library_named_outside_the_config_folder(
    tmp_path: Path, library: GaitLibrary, named: str
) -> None:
    """Before, an export of such a session held no copy: an import elsewhere could not open it."""
    s, out = exported(tmp_path, library, named)
    manifest = json.loads((out / "manifest.json").read_text())
    data = (tmp_path / "study" / "libs" / "x.json").read_bytes()
    sha = hashlib.sha256(data).hexdigest()
    assert manifest["gait_library"] == {"file": "gait_library/x.json", "sha256": sha}
    assert manifest["files"]["gait_library/x.json"] == sha
    assert (out / "gait_library" / "x.json").read_bytes() == data
    shutil.rmtree(tmp_path / "study")  # another machine: the original is not there
    storage = MemoryStorage()
    imported = import_session(storage, out)
    np.testing.assert_array_equal(imported.posterior().mean, s.posterior().mean)
    assert imported.gait_ids == s.gait_ids
    again = Session.open(storage, imported.id)
    assert again.next_query() == s.next_query()
    meta = imported.record.meta
    assert meta["library_path"] == str((out / "gait_library" / "x.json").resolve())
    assert meta["library_copied_from"] == s.record.meta["library_path"]


def test_an_import_beside_the_original_keeps_pointing_at_it(
    tmp_path: Path, library: GaitLibrary
) -> None:
    s, out = exported(tmp_path, library)
    imported = import_session(MemoryStorage(), out)
    assert imported.record.meta["library_path"] == s.record.meta["library_path"]
    assert "library_copied_from" not in imported.record.meta


def test_an_export_of_the_previous_release_without_a_copy_imports_as_before(
    tmp_path: Path, library: GaitLibrary
) -> None:
    """The previous release wrote no copy of a library named by '..' or an absolute path."""
    s, out = exported(tmp_path, library)
    shutil.rmtree(out / "gait_library")

    def as_before(m: dict[str, Any]) -> None:
        del m["gait_library"], m["files"]["gait_library/x.json"]

    edit_manifest(out, as_before)
    imported = import_session(MemoryStorage(), out)  # the original is there: used
    meta = {k: v for k, v in imported.record.meta.items() if k != "imported_from"}
    assert meta == s.record.meta
    np.testing.assert_array_equal(imported.posterior().mean, s.posterior().mean)
    shutil.rmtree(tmp_path / "study")
    with pytest.raises(ExportError, match="missing or changed, and the export holds no copy"):
        import_session(MemoryStorage(), out)


@pytest.mark.parametrize(
    "file",
    ["../x.json", "/tmp/x.json", "gait_library/../gait_library/x.json"],
)
def test_a_library_copy_outside_the_export_is_refused(
    tmp_path: Path, library: GaitLibrary, file: str
) -> None:
    _, out = exported(tmp_path, library)
    shutil.rmtree(tmp_path / "study")

    def move(m: dict[str, Any]) -> None:
        m["files"][file] = m["files"].pop("gait_library/x.json")
        m["gait_library"]["file"] = file

    edit_manifest(out, move)
    with pytest.raises(ExportError, match="which is not inside the export"):
        import_session(MemoryStorage(), out)


def test_a_bad_gait_library_entry_is_refused(tmp_path: Path, library: GaitLibrary) -> None:
    _, out = exported(tmp_path, library)
    shutil.rmtree(tmp_path / "study")
    edit_manifest(out, lambda m: m["gait_library"].__setitem__("file", 5))
    with pytest.raises(ExportError, match=r"manifest\.json: bad gait_library entry"):
        import_session(MemoryStorage(), out)


@pytest.mark.parametrize("named", ["../libs/x.json", "lib/x.json"])
def test_an_import_into_sqlite_keeps_its_library_beside_the_database(
    tmp_path: Path, library: GaitLibrary, named: str
) -> None:
    """Before, the imported session read the export folder's copy: deleting the folder made it
    unopenable.  Now its library is copied next to the database (as the gait cache is)."""
    if named.startswith("lib/"):  # a copy at the path the config names (every release's)
        (tmp_path / "study" / "configs" / "lib").mkdir(parents=True)
        library.save(tmp_path / "study" / "configs" / "lib" / "x.json")
    s, out = exported(tmp_path, library, named)
    sha = s.record.meta["library_sha256"]
    shutil.rmtree(tmp_path / "study")
    url = f"sqlite:///{tmp_path / 'other.db'}"
    imported = import_session(url, out)
    kept = tmp_path / "other.db.libraries" / f"{sha}.json"
    assert imported.record.meta["library_path"] == str(kept.resolve())
    assert imported.record.meta["library_copied_from"] == s.record.meta["library_path"]
    imported.close()
    shutil.rmtree(out)
    again = Session.open(url, imported.id)
    np.testing.assert_array_equal(again.posterior().mean, s.posterior().mean)
    assert again.gait_ids == s.gait_ids
    assert again.next_query() == s.next_query()
    # a second import of the same library shares the file
    export_session(again, tmp_path / "export2", "json")
    twice = import_session(url, tmp_path / "export2", as_new=True)
    assert twice.record.meta["library_path"] == str(kept.resolve())
    assert library_files(kept.parent) == [kept.name]


def test_an_import_into_a_server_database_reads_the_export_folder(
    tmp_path: Path, library: GaitLibrary
) -> None:
    """A database that is not a local file has no folder beside it: the session reads the
    export's copy, and names the library and its hash once the folder is gone."""
    s, out = exported(tmp_path, library)
    shutil.rmtree(tmp_path / "study")
    storage = MemoryStorage()
    imported = import_session(storage, out)
    assert imported.record.meta["library_path"] == str((out / "gait_library" / "x.json").resolve())
    shutil.rmtree(out)
    sha = s.record.meta["library_sha256"]
    with pytest.raises(ReplayError, match=rf"needs its gait library .*x\.json \(sha256 {sha[:12]}"):
        Session.open(storage, imported.id)


def test_an_import_that_cannot_keep_its_library_writes_nothing(
    tmp_path: Path, library: GaitLibrary
) -> None:
    _, out = exported(tmp_path, library)
    shutil.rmtree(tmp_path / "study")
    (tmp_path / "other.db.libraries").write_text("not a folder")
    url = f"sqlite:///{tmp_path / 'other.db'}"
    with pytest.raises(
        ExportError, match=r"cannot copy the gait library into .*nothing was written"
    ):
        import_session(url, out)
    from gaitpref.storage import open_storage

    with open_storage(url) as storage:
        assert storage.list_sessions() == []


# -- an import refused after its library was copied beside the database ---------------------------
def test_a_refused_import_removes_the_library_copy_it_made(
    tmp_path: Path, library: GaitLibrary
) -> None:
    """An import into the exported session's own database is refused (it is already there) in
    the transaction that would create it, after the library was copied beside the database.
    Before, the copy (and its folder) stayed: a file no session reads."""
    s, out = exported(tmp_path, library)
    s.close()
    shutil.rmtree(tmp_path / "study")  # so the import needs its own copy
    with pytest.raises(ExportError, match=r"the exported session itself.*nothing was written"):
        import_session(f"sqlite:///{tmp_path / 'lab.db'}", out)
    assert library_files(tmp_path / "lab.db.libraries") == []  # its lock file stays


def test_an_import_refused_by_the_database_removes_the_library_copy_it_made(
    tmp_path: Path, library: GaitLibrary, monkeypatch: pytest.MonkeyPatch
) -> None:
    _, out = exported(tmp_path, library)
    shutil.rmtree(tmp_path / "study")
    kept = tmp_path / "other.db.libraries"
    kept.mkdir()  # a folder of earlier imports stays, without this import's copy
    (kept / "earlier.json").write_text("{}")

    def locked(*args: object, **kwargs: object) -> None:
        assert list(kept.glob("*.json")) != [kept / "earlier.json"]  # the copy is written
        raise StorageError("database is locked")

    monkeypatch.setattr(SQLStorage, "_create", locked)  # the transaction creating the session
    with pytest.raises(StorageError, match="database is locked"):
        import_session(f"sqlite:///{tmp_path / 'other.db'}", out)
    assert library_files(kept) == ["earlier.json"]


def test_a_refused_import_keeps_a_library_copy_that_was_there(
    tmp_path: Path, library: GaitLibrary, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The copy is content-addressed: an earlier import of the same library made it, and its
    session reads it.  Neither a second import refused as already there, nor one refused by the
    database, removes it."""
    s, out = exported(tmp_path, library)
    shutil.rmtree(tmp_path / "study")
    url = f"sqlite:///{tmp_path / 'other.db'}"
    first = import_session(url, out)
    first.close()
    kept = tmp_path / "other.db.libraries" / f"{s.record.meta['library_sha256']}.json"
    data = kept.read_bytes()
    with pytest.raises(ExportError, match=r"imported before as session"):
        import_session(url, out)
    assert kept.read_bytes() == data

    def locked(*args: object, **kwargs: object) -> None:
        raise StorageError("database is locked")

    monkeypatch.setattr(SQLStorage, "_create", locked)
    with pytest.raises(StorageError, match="database is locked"):
        import_session(url, out, as_new=True)
    assert kept.read_bytes() == data
    # a copy no session of the database reads (its session deleted, or the database replaced)
    third = tmp_path / "third.db.libraries" / kept.name
    third.parent.mkdir()
    third.write_bytes(data)
    with pytest.raises(StorageError, match="database is locked"):
        import_session(f"sqlite:///{tmp_path / 'third.db'}", out)
    assert third.read_bytes() == data
    monkeypatch.undo()
    again = Session.open(url, first.id)
    assert again.gait_ids == s.gait_ids
    assert library_files(kept.parent) == [kept.name]


def test_a_refused_import_keeps_the_copy_it_made_once_another_session_reads_it(
    tmp_path: Path, library: GaitLibrary, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Two imports of the same library at once: the first writes the copy, the second finds it
    there and its session is created; the first is then refused.  The copy stays: the other
    session reads it."""
    s, out = exported(tmp_path, library)
    shutil.rmtree(tmp_path / "study")
    url = f"sqlite:///{tmp_path / 'other.db'}"
    create = SQLStorage._create

    def concurrent(self: SQLStorage, spec: Any, events: Any, status: Any, check: Any) -> None:
        create(self, spec, events, status, None)  # the other import, reading the same copy
        raise StorageError("database is locked")

    monkeypatch.setattr(SQLStorage, "_create", concurrent)
    with pytest.raises(StorageError, match="database is locked"):
        import_session(url, out)
    monkeypatch.undo()
    kept = tmp_path / "other.db.libraries" / f"{s.record.meta['library_sha256']}.json"
    assert kept.is_file()
    with open_storage(url) as storage:
        (record,) = storage.list_sessions()
    assert record.meta["library_path"] == str(kept.resolve())
    assert Session.open(url, record.id).gait_ids == s.gait_ids


def test_a_refused_import_keeps_the_copy_a_concurrent_import_found(
    tmp_path: Path, library: GaitLibrary, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Two imports of one library at once: A writes the copy, B finds it there (so does not
    write it) and is about to commit its session when A is refused.  Before, A's ``_unmake``
    saw no session reading the copy yet and removed it: B's committed session had lost its
    gait library.  Now B waits for the copy's lock until A has removed it, then writes it again
    (the test lets B commit only once A is done, as the window was)."""
    s, out = exported(tmp_path, library)
    shutil.rmtree(tmp_path / "study")
    url = f"sqlite:///{tmp_path / 'other.db'}"
    a_done = threading.Event()
    other = Other(lambda: import_session(url, out, as_new=True))
    watch_locks(monkeypatch, other)
    create = SQLStorage._create

    def refused(self: SQLStorage, spec: Any, events: Any, status: Any, check: Any) -> Any:
        if threading.current_thread() is other.thread:  # B, its copy found (or written)
            other.settled.set()
            assert a_done.wait(BOUND_S)
            return create(self, spec, events, status, check)
        other.start_and_settle()  # B waits to commit, or waits for the lock
        raise StorageError("database is locked")

    monkeypatch.setattr(SQLStorage, "_create", refused)
    with pytest.raises(StorageError, match="database is locked"):
        import_session(url, out)
    a_done.set()
    imported: Session = other.join()
    monkeypatch.undo()
    kept = tmp_path / "other.db.libraries" / f"{s.record.meta['library_sha256']}.json"
    assert kept.is_file()
    assert imported.record.meta["library_path"] == str(kept.resolve())
    imported.close()
    assert Session.open(url, imported.id).gait_ids == s.gait_ids
    # alone, a refused import still removes the copy it made

    def locked(*args: object, **kwargs: object) -> None:
        raise StorageError("database is locked")

    monkeypatch.setattr(SQLStorage, "_create", locked)
    with pytest.raises(StorageError, match="database is locked"):
        import_session(f"sqlite:///{tmp_path / 'third.db'}", out)
    assert library_files(tmp_path / "third.db.libraries") == []


def test_a_library_copy_past_the_import_limit_is_refused_before_it_is_read(
    tmp_path: Path, library: GaitLibrary, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The import reads the export's copy of the library whole (to keep it, and its replay
    parses it): before, a copy of any size was read (only events.jsonl, manifest.json and
    config.toml were bounded), so an enormous one made the import allocate without bound."""
    from gaitpref.sessions import export as export_module

    _, out = exported(tmp_path, library)
    shutil.rmtree(tmp_path / "study")  # the original is not there: the copy is used
    size = (out / "gait_library" / "x.json").stat().st_size
    monkeypatch.setattr(export_module, "MAX_LIBRARY_BYTES", size - 1, raising=False)
    target = tmp_path / "target.db"
    with pytest.raises(ExportError, match=rf"gait_library/x\.json holds {size:,} bytes, more than"):
        import_session(f"sqlite:///{target}", out)
    assert not target.exists()
    monkeypatch.setattr(export_module, "MAX_LIBRARY_BYTES", size)
    import_session(MemoryStorage(), out).close()
