"""Gait libraries given to the console: uploaded with a config, kept for reopening, never read
from a path a client names outside the console's library folder."""

from __future__ import annotations

import io
import shutil
import threading
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from fastapi.testclient import TestClient

from gaitpref import Session
from gaitpref.config import ConfigError, load_config
from gaitpref.console import create_app
from gaitpref.console.service import SessionService
from gaitpref.errors import StorageError
from gaitpref.gaits import GaitLibrary, build_library
from tests.console.htmlforms import forms_of
from tests.lockwatch import Other, watch_locks

NAMED = """
[gaits]
library = "lib.json"
[model]
lengthscale = { step_length = 0.03, step_duration = 0.08 }
signal_variance = 0.005
noise = 0.02
[cospar]
n = 1
buffer = 1
"""
OWN_SPACE = """
[space.step_length]
values = [0.10, 0.13, 0.16]
unit = "m"
[space.step_duration]
values = %s
unit = "s"
[model]
lengthscale = { step_length = 0.03, step_duration = 0.08 }
signal_variance = 0.005
noise = 0.02
[cospar]
n = 1
buffer = 1
"""


@pytest.fixture(scope="module")
def library_bytes(tmp_path_factory: pytest.TempPathFactory) -> tuple[bytes, GaitLibrary]:
    lib = build_library([0.10, 0.13, 0.16], step_durations=[0.85, 1.15], n_jobs=1)
    path = tmp_path_factory.mktemp("lib") / "lib.json"
    lib.save(path)
    return path.read_bytes(), lib


@pytest.fixture
def console(db_url: str, tmp_path: Path) -> Iterator[TestClient]:
    with TestClient(create_app(db_url, library_dir=tmp_path / "libs"), follow_redirects=False) as c:
        yield c


def upload(c: TestClient, config: str, library: tuple[str, bytes] | None) -> httpx.Response:
    csrf = forms_of(c.get("/").text)["create-form"].fields["csrf_token"]
    files = {"config_file": ("study.toml", config.encode())}
    if library is not None:
        files["library_file"] = (library[0], library[1])
    response: httpx.Response = c.post(
        "/sessions", data={"csrf_token": csrf, "subject": "S01"}, files=files
    )
    return response


def test_a_config_naming_an_uploaded_library(
    console: TestClient, library_bytes: tuple[bytes, GaitLibrary], db_url: str, tmp_path: Path
) -> None:
    data, lib = library_bytes
    r = upload(console, NAMED, ("lib.json", data))
    assert r.status_code == 303, r.text
    q = console.get("/api/sessions/1/query").json()
    gait = q["actions"][0]
    assert gait["gait_id"] == lib.gait_id(gait["index"])
    assert gait["gait_id"] in console.get("/sessions/1").text
    kept = list((tmp_path / "libs").glob("*/lib.json"))
    assert len(kept) == 1 and kept[0].read_bytes() == data
    # another console over the same database reopens the session: it finds the library again
    other = TestClient(create_app(db_url, library_dir=tmp_path / "libs"))
    assert other.get("/api/sessions/1/query").json() == q
    # a config sent as text may name the kept library by its path inside the library folder
    inside = NAMED.replace('"lib.json"', f'"{kept[0].parent.name}/lib.json"')
    r = console.post("/api/sessions", json={"config": inside, "subject": "S02"})
    assert r.status_code == 201, r.text
    # exports carry the library at the path the config names, subfolders included
    for sid, name in ((1, "lib.json"), (r.json()["id"], f"{kept[0].parent.name}/lib.json")):
        z = console.get(f"/api/sessions/{sid}/export", params={"format": "json"})
        with zipfile.ZipFile(io.BytesIO(z.content)) as zf:
            assert zf.read(f"session-{sid}/{name}") == data


def test_a_config_with_its_own_grid_and_a_library_naming_its_gaits(
    console: TestClient, library_bytes: tuple[bytes, GaitLibrary]
) -> None:
    data, lib = library_bytes
    r = upload(console, OWN_SPACE % "[0.85, 1.15]", ("any-name.json", data))
    assert r.status_code == 303
    gait = console.get("/api/sessions/1/query").json()["actions"][0]
    assert gait["gait_id"] == lib.gait_id(gait["index"])
    r = upload(console, OWN_SPACE % "[0.85, 1.0, 1.15]", ("lib.json", data))
    assert r.status_code == 422 and "<code>library_file</code>" in r.text
    assert "3 x 2" in r.text and "3 x 3" in r.text


def test_refused_libraries_and_paths(
    console: TestClient, library_bytes: tuple[bytes, GaitLibrary], tmp_path: Path
) -> None:
    data, _ = library_bytes
    r = upload(console, NAMED, ("lib.json", b'{"format": "something else"}'))
    assert r.status_code == 422 and "not a usable gait library" in r.text
    r = upload(console, NAMED, ("other.json", data))
    assert r.status_code == 422 and "name the uploaded file" in r.text
    secret = tmp_path / "secret.json"
    secret.write_bytes(data)
    for path in (str(secret), "../secret.json", "../../../../etc/passwd"):
        body = {"config": NAMED.replace('"lib.json"', f'"{path}"'), "subject": "S01"}
        r = console.post("/api/sessions", json=body)
        assert r.status_code == 422, path
        assert r.json()["detail"][0]["loc"] == ["body", "config"]
        assert "library folder" in r.json()["detail"][0]["msg"]
    r = console.post("/api/sessions", json={"config": NAMED, "subject": "S01"})
    assert r.status_code == 422 and "no such gait library" in r.text
    assert console.get("/api/sessions").json() == []


def test_an_upload_past_the_json_parsers_limits_is_refused(
    console: TestClient, library_bytes: tuple[bytes, GaitLibrary]
) -> None:
    deep = b"[" * 100_000 + b"]" * 100_000
    r = upload(console, NAMED, ("lib.json", deep))  # a RecursionError: a 500 before
    assert r.status_code == 422 and "nested too deeply" in r.text
    assert b'"speed": null' in library_bytes[0]
    huge = library_bytes[0].replace(b'"speed": null', b'"speed": 1' + b"0" * 400)
    r = upload(console, NAMED, ("lib.json", huge))  # an OverflowError: a 500 before
    assert r.status_code == 422 and "speed: expected a number, got one too large" in r.text


def _files_under(folder: Path) -> list[Path]:
    """What is under ``folder``, less the uploads' lock files (``.<sha256 prefix>.lock``: left
    there, as removing one races)."""
    if not folder.exists():
        return []
    return sorted(p for p in folder.rglob("*") if not p.name.endswith(".lock"))


def test_a_refused_upload_writes_nothing(
    console: TestClient, library_bytes: tuple[bytes, GaitLibrary], tmp_path: Path
) -> None:
    data, _ = library_bytes
    libs = tmp_path / "libs"
    r = upload(console, NAMED, ("other.json", data))  # the config names another file
    assert r.status_code == 422 and "name the uploaded file" in r.text
    r = upload(console, OWN_SPACE % "[0.85, 1.0, 1.15]", ("lib.json", data))  # another grid
    assert r.status_code == 422 and "<code>library_file</code>" in r.text
    # a config and library that fit, refused later by the session (seed out of range)
    csrf = forms_of(console.get("/").text)["create-form"].fields["csrf_token"]
    files = {"config_file": ("study.toml", NAMED.encode()), "library_file": ("lib.json", data)}
    r = console.post(
        "/sessions", data={"csrf_token": csrf, "subject": "S01", "seed": str(2**64)}, files=files
    )
    assert r.status_code == 422 and "seed" in r.text
    assert _files_under(libs) == []
    assert console.get("/api/sessions").json() == []
    assert upload(console, NAMED, ("lib.json", data)).status_code == 303  # then a good one
    assert [p.name for p in _files_under(libs) if p.is_file()] == ["lib.json"]


def test_a_refused_upload_keeps_a_library_another_session_uses(
    console: TestClient, library_bytes: tuple[bytes, GaitLibrary], tmp_path: Path
) -> None:
    data, _ = library_bytes
    assert upload(console, NAMED, ("lib.json", data)).status_code == 303
    kept = [p for p in _files_under(tmp_path / "libs") if p.is_file()]
    r = upload(console, OWN_SPACE % "[0.85, 1.0, 1.15]", ("lib.json", data))
    assert r.status_code == 422
    assert [p for p in _files_under(tmp_path / "libs") if p.is_file()] == kept
    assert console.get("/api/sessions/1/query").status_code == 200


def test_a_refused_upload_keeps_the_library_a_concurrent_upload_found(
    db_url: str,
    library_bytes: tuple[bytes, GaitLibrary],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Two uploads of one library at once: A writes the file, its session is then refused.
    Before, B (which found A's file there, so did not write it) could create its session
    reading the file, and A then removed it: B's session had lost its gait library.  Now B waits
    for the library's lock until A has removed the file, then writes it again."""
    data, _ = library_bytes
    libs = tmp_path / "libs"
    service = SessionService(db_url, library_dir=libs)
    other = Other(lambda: service.create(NAMED, "S02", library=(data, "lib.json")))
    watch_locks(monkeypatch, other)
    create = Session.create

    def refused(*args: Any, **kwargs: Any) -> Session:
        if threading.current_thread() is other.thread:
            return create(*args, **kwargs)
        other.start_and_settle()  # B has created its session, or waits for the lock
        raise StorageError("database is locked")

    monkeypatch.setattr(Session, "create", refused)
    with pytest.raises(StorageError, match="database is locked"):
        service.create(NAMED, "S01", library=(data, "lib.json"))
    made: Session = other.join()
    monkeypatch.undo()
    (kept,) = [p for p in _files_under(libs) if p.is_file()]
    assert kept.read_bytes() == data
    again = Session.open(db_url, made.id)  # reads its library from the file
    assert again.gait_ids == made.gait_ids
    assert [s.id for s in service.list_sessions()] == [made.id]
    again.close()
    service.close()
    # alone, a refused upload still removes the file it wrote (and leaves only lock files)
    shutil.rmtree(libs / kept.parent.name)
    other_db = SessionService(f"sqlite:///{tmp_path / 'other.db'}", library_dir=libs)
    with pytest.raises(Exception, match="seed"):
        other_db.create(NAMED, "S03", seed=2**64, library=(data, "lib.json"))
    assert _files_under(libs) == []
    other_db.close()


def test_a_library_path_with_a_nul_is_refused_naming_config(
    console: TestClient, tmp_path: Path
) -> None:
    """A NUL in ``[gaits].library`` was a 422 saying only "embedded null byte" (Path.resolve's
    ValueError), naming no field; from a config file (the CLI) it was an unnamed ValueError."""
    config = NAMED.replace('"lib.json"', '"lib\\u0000.json"')
    r = console.post("/api/sessions", json={"config": config, "subject": "S01"})
    assert r.status_code == 422, r.text
    assert r.json()["detail"][0]["loc"] == ["body", "config"]
    assert "NUL" in r.json()["detail"][0]["msg"]
    page = upload(console, config, None)
    assert page.status_code == 422 and "<code>config</code>" in page.text and "NUL" in page.text
    assert console.get("/api/sessions").json() == []
    file = tmp_path / "study.toml"
    file.write_text(config, encoding="utf-8")
    with pytest.raises(ConfigError, match=r"\[gaits\].*library.*NUL"):
        load_config(file)
