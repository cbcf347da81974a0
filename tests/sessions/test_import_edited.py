"""An export edited by hand (its hashes fixed up too) is refused by name, and nothing written."""

from __future__ import annotations

import hashlib
import json
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from gaitpref import Session
from gaitpref.errors import ExportError, ReplayError
from gaitpref.sessions import export as export_module
from gaitpref.sessions.export import export_session, import_session
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG, Drive
from tests.sessions.test_line_session import TEXT as LINE_CONFIG

Lines = list[str]


@pytest.fixture
def exported(tmp_path: Path, sqlite_url: str, drive: Drive) -> Path:
    s = Session.create(sqlite_url, CONFIG, "S07", seed=3)
    drive(s, 4)
    s.note("end of the first block")
    out = tmp_path / "export"
    export_session(s, out, "csv")
    s.close()
    return out


def _edit_events(out: Path, edit: Callable[[Lines], Lines | bytes]) -> None:
    """Apply ``edit`` to events.jsonl's lines and fix the manifest's hash to match."""
    lines = (out / "events.jsonl").read_text().splitlines(keepends=True)
    edited = edit(lines)
    data = edited if isinstance(edited, bytes) else "".join(edited).encode()
    (out / "events.jsonl").write_bytes(data)
    _edit_manifest(out, lambda m: m["files"].__setitem__("events.jsonl", _sha(data)))


def _edit_manifest(out: Path, edit: Callable[[dict[str, Any]], object]) -> None:
    manifest = json.loads((out / "manifest.json").read_text())
    edit(manifest)
    (out / "manifest.json").write_text(json.dumps(manifest))


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _set(line: int, key: str, value: object) -> Callable[[Lines], Lines]:
    def edit(lines: Lines) -> Lines:
        row = json.loads(lines[line])
        row[key] = value
        lines[line] = json.dumps(row) + "\n"
        return lines

    return edit


def _refused(out: Path, tmp_path: Path, match: str) -> None:
    target = MemoryStorage()
    with pytest.raises(ExportError, match=match):
        import_session(target, out)
    assert target.list_sessions() == []
    db = tmp_path / "target.db"
    with pytest.raises(ExportError, match=match):
        import_session(f"sqlite:///{db}", out)
    assert not db.exists()


EVENT_EDITS: dict[str, tuple[Callable[[Lines], Lines | bytes], str]] = {
    "last event dropped": (
        lambda lines: lines[:-1],
        r"events.jsonl holds \d+ events but manifest.json's session.last_seq is \d+",
    ),
    "an event twice": (
        lambda lines: [*lines[:4], lines[3], *lines[4:]],
        r"events.jsonl line 5: seq 4 where 5 was expected",
    ),
    "two events swapped": (
        lambda lines: [*lines[:3], lines[4], lines[3], *lines[5:]],
        r"events.jsonl line 4: seq 5 where 4 was expected",
    ),
    "an extra key": (_set(2, "extra", 1), r"line 3: has keys an export does not write: extra"),
    "a missing key": (
        lambda lines: [json.dumps({"seq": 1, "kind": "created"}) + "\n", *lines[1:]],
        r"line 1: lacks at, payload",
    ),
    "seq as a float": (_set(0, "seq", 1.0), r"line 1: seq must be an integer, got 1.0"),
    "seq as a text": (_set(0, "seq", "1"), r"line 1: seq must be an integer, got '1'"),
    "version as a text": (_set(1, "version", "1"), r"line 2: version must be an integer"),
    "at as a number": (_set(1, "at", 5), r"line 2: at must be an ISO time text, got 5"),
    "kind as a number": (_set(1, "kind", 5), r"line 2: kind must be a string"),
    "a list for a line": (
        lambda lines: [lines[0], "[1, 2]\n", *lines[2:]],
        r"line 2: a JSON list, not an object",
    ),
    "nested past the recursion limit": (
        lambda lines: [lines[0], "[" * 100_000 + "]" * 100_000 + "\n", *lines[2:]],
        r"line 2: not JSON \(maximum recursion depth",
    ),
    "not UTF-8": (
        lambda lines: "".join(lines).encode() + b"\xff\n",
        r"events.jsonl is not UTF-8 text",
    ),
}


@pytest.mark.parametrize("case", list(EVENT_EDITS))
def test_an_edited_log_is_refused_by_name(exported: Path, tmp_path: Path, case: str) -> None:
    edit, match = EVENT_EDITS[case]
    _edit_events(exported, edit)
    _refused(exported, tmp_path, match)


MANIFEST_EDITS: dict[str, tuple[Callable[[dict[str, Any]], object], str]] = {
    "a seed that is not an integer": (
        lambda m: m.__setitem__("seed", 3.5),
        r"manifest.json: seed must be an integer, got 3.5",
    ),
    "a seed as a text": (
        lambda m: m.__setitem__("seed", "3"),
        r"manifest.json: seed must be an integer, got '3'",
    ),
    "meta that is not an object": (
        lambda m: m["session"].__setitem__("meta", ["g0"]),
        r"manifest.json: session.meta must be an object, got list",
    ),
    "a session id that is not an integer": (
        lambda m: m["session"].__setitem__("id", [1]),
        r"manifest.json: session.id must be an integer",
    ),
    "a posterior summary that is not an object": (
        lambda m: m.__setitem__("posterior", [1]),
        r"manifest.json: posterior must be an object, got list",
    ),
    "a posterior mean as a text": (
        lambda m: m["posterior"].__setitem__("mean_at_argmax", "high"),
        r"manifest.json: posterior.mean_at_argmax must be a number, got 'high'",
    ),
    "a library path that is not a text": (
        lambda m: m["session"]["meta"].__setitem__("library_path", 5),
        r"manifest.json: session.meta.library_path must be a text, got 5",
    ),
    "a status the log does not end in": (
        lambda m: m["session"].__setitem__("status", "finished"),
        r"manifest.json's session.status is 'finished', but the log leaves the session active",
    ),
    "format version 0": (
        lambda m: m.__setitem__("format_version", 0),
        r"format_version must be an integer from 1 to 1, got 0",
    ),
    "format version as a text": (
        lambda m: m.__setitem__("format_version", "1"),
        r"format_version must be an integer from 1 to 1, got '1'",
    ),
}


@pytest.mark.parametrize("case", list(MANIFEST_EDITS))
def test_an_edited_manifest_is_refused_by_name(exported: Path, tmp_path: Path, case: str) -> None:
    edit, match = MANIFEST_EDITS[case]
    _edit_manifest(exported, edit)
    _refused(exported, tmp_path, match)


def test_a_log_past_the_import_limit_is_refused_before_it_is_read(
    exported: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    size = (exported / "events.jsonl").stat().st_size
    monkeypatch.setattr(export_module, "MAX_EVENTS_BYTES", size - 1)
    _refused(exported, tmp_path, rf"events.jsonl holds {size:,} bytes, more than the {size - 1:,}")
    monkeypatch.setattr(export_module, "MAX_EVENTS_BYTES", size)
    import_session(MemoryStorage(), exported).close()
    monkeypatch.setattr(export_module, "MAX_EVENTS", 3)
    _refused(exported, tmp_path, r"events.jsonl holds more than 3 events, the most an import")


def test_a_log_with_windows_line_ends_is_the_same_log(exported: Path) -> None:
    _edit_events(exported, lambda lines: [x.replace("\n", "\r\n") for x in lines])
    imported = import_session(MemoryStorage(), exported)
    assert imported.last_seq == len((exported / "events.jsonl").read_bytes().splitlines())
    imported.close()


def test_a_fresh_line_session_imports(tmp_path: Path) -> None:
    """The line path's posterior has no point before the first query: the export's summary has
    no argmax, and the import checks that (it failed on numpy's argmax of nothing)."""
    (tmp_path / "line.toml").write_text(LINE_CONFIG)
    s = Session.create(MemoryStorage(), tmp_path / "line.toml", "S01")
    export_session(s, tmp_path / "fresh", "csv")
    imported = import_session(MemoryStorage(), tmp_path / "fresh")
    assert imported.last_seq == s.last_seq == 1 and len(imported.space) == 0
    assert imported.next_query() == s.next_query()
    shutil.rmtree(tmp_path / "fresh")
    export_session(s, tmp_path / "fresh", "csv")  # with its pending query
    again = import_session(MemoryStorage(), tmp_path / "fresh")
    assert again.pending == s.pending


@pytest.mark.parametrize(
    ("where", "key", "value"),
    [(None, "seed", 5), ("session", "subject", "S99"), (None, "config_name", "renamed")],
)
def test_a_manifest_that_disagrees_with_the_created_event_is_refused(
    tmp_path: Path, where: str | None, key: str, value: object
) -> None:
    """Before: a session with no answer yet imported with the manifest's seed (its next queries
    not the original's) or subject, its row disagreeing with its own log's created event."""
    s = Session.create(MemoryStorage(), CONFIG, "S07", seed=3)
    out = tmp_path / "fresh"
    export_session(s, out, "csv")
    _edit_manifest(out, lambda m: (m if where is None else m[where]).__setitem__(key, value))
    name = key if where is None else f"{where}.{key}"
    _refused(out, tmp_path, rf"manifest.json's {name} is {value!r}, but the session's created")


def test_a_warm_start_dropped_from_the_manifest_is_refused(exported: Path, tmp_path: Path) -> None:
    """The created event still records it: the import must not rebuild the session cold."""

    def warm(lines: Lines) -> Lines:
        row = json.loads(lines[0])
        row["payload"]["prior_from"] = [{"session": 1, "subject": "S01", "last_seq": 3}]
        return [json.dumps(row) + "\n", *lines[1:]]

    _edit_events(exported, warm)
    _refused(exported, tmp_path, "records a warm start that manifest.json's session.meta lacks")


def test_gait_ids_that_disagree_with_the_log_are_refused(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    """Before: the session was imported naming the gaits it walked by the edited ids (the log
    says g7, the imported session X7), or with no library at all."""
    s = Session.create(sqlite_url, CONFIG, "S07", seed=3, library=[f"g{k}" for k in range(15)])
    drive(s, 3)
    out = tmp_path / "export"
    export_session(s, out, "csv")
    _edit_manifest(out, lambda m: m["session"]["meta"].__setitem__("gait_ids", ["X"] * 15))
    _refused(out, tmp_path, r"events.jsonl line 3: trial 1 walked gait 'g\d+' \(action \d+\), but")
    _edit_manifest(out, lambda m: m["session"]["meta"].pop("gait_ids"))
    _refused(out, tmp_path, "names no gait library .*, but the session's created event")


@pytest.mark.parametrize(
    ("meta", "match"),
    [
        ({"library_copied_from": "/lab/gaits.json"}, "library_copied_from but no library_path"),
        ({"config_defaults": [1]}, r"meta's config_defaults must be a text, got \[1\]"),
        ({"config_dir": 5}, "meta's config_dir must be a text, got 5"),
    ],
)
def test_session_meta_of_the_wrong_shape_is_refused_by_name(
    exported: Path, tmp_path: Path, meta: dict[str, object], match: str
) -> None:
    """An export's session.meta is the imported session's: a key the config is read with that
    is not a text (or a library copy with no path) is refused naming it, not a KeyError or a
    TypeError, and nothing is written."""
    _edit_manifest(exported, lambda m: m["session"]["meta"].update(meta))
    target = MemoryStorage()
    with pytest.raises(ReplayError, match=match):
        import_session(target, exported)
    assert target.list_sessions() == []


def test_a_file_listed_under_many_names_is_hashed_once(
    exported: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``./events.jsonl``, ``.//events.jsonl``, ...: a manifest (up to 64 MiB) could list one
    large file a million times, and the import hashed it every time."""
    sha = _sha((exported / "events.jsonl").read_bytes())
    aliases = {"./" * k + "events.jsonl": sha for k in range(1, 200)}
    _edit_manifest(exported, lambda m: m["files"].update(aliases))
    hashed: list[Path] = []
    real = export_module._sha256

    def counting(path: Path) -> str:
        hashed.append(path)
        return real(path)

    monkeypatch.setattr(export_module, "_sha256", counting)
    import_session(MemoryStorage(), exported).close()
    assert len(hashed) == len(set(hashed)) and len(hashed) < 10
