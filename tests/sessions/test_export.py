"""Export -> import: plain files readable without gaitpref, and an exact round trip."""

from __future__ import annotations

import csv
import json
import os
import stat
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from gaitpref import ReplayError, Session
from gaitpref.errors import ExportError
from gaitpref.sessions.export import export_session, import_session
from gaitpref.storage import MemoryStorage, SQLStorage
from tests.sessions.sessionkit import CONFIG, Drive


def _session(url: str, drive: Drive) -> Session:
    s = Session.create(url, CONFIG, "S07", seed=17, library=[f"g{k}" for k in range(15)])
    drive(s, 7)
    s.undo()
    drive(s, 2)
    s.exclude(3, "device_fault", "left knee motor fault")
    q = s.next_query()
    s.answer(q.id, [(q.actions[0], q.buffer[0], "none")], [])
    plan = s.start_validation()
    s.answer_validation(plan.round, "ACB")
    s.next_query()  # a pending query travels too
    return s


@pytest.mark.parametrize("fmt", ["csv", "json"])
def test_round_trip_gives_the_same_posterior_and_next_query(
    tmp_path: Path, sqlite_url: str, drive: Drive, fmt: str
) -> None:
    s = _session(sqlite_url, drive)
    export_session(s, tmp_path / "export", fmt)  # type: ignore[arg-type]
    target = f"sqlite:///{tmp_path / 'other.db'}"
    Session.create(target, CONFIG, "S99").close()  # the target already has a session 1
    imported = import_session(target, tmp_path / "export")
    assert imported.id == 2 and imported.record.meta["imported_from"]["session_id"] == s.id
    np.testing.assert_allclose(imported.posterior().mean, s.posterior().mean, rtol=0, atol=1e-12)
    np.testing.assert_allclose(imported.posterior().std, s.posterior().std, rtol=0, atol=1e-12)
    assert imported.pending == s.pending and imported.next_query() == s.next_query()
    assert [(e.seq, e.kind, e.payload, e.at) for e in imported.events()] == [
        (e.seq, e.kind, e.payload, e.at) for e in s.events()
    ]
    assert imported.comparisons() == s.comparisons()
    assert imported.validations() == s.validations()
    imported.close()


def test_the_files_are_readable_without_gaitpref(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    s = _session(sqlite_url, drive)
    out = tmp_path / "csv"
    export_session(s, out, "csv")
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["software_version"] == "0.1.0" and manifest["seed"] == 17
    assert manifest["config_sha256"] == s.config.sha256
    assert manifest["posterior"]["argmax"] == s.posterior().argmax
    assert manifest["posterior"]["learned"] is True
    assert set(manifest["files"]) >= {"config.toml", "events.jsonl", "trials.csv"}
    with open(out / "comparisons.csv", newline="") as f:
        comparisons = list(csv.DictReader(f))
    assert {"tie", "undone", "excluded", "outcome", "preferred_trial"} <= set(comparisons[0])
    assert any(c["tie"] == "true" and c["preferred_trial"] == "" for c in comparisons)
    assert any(c["undone"] == "true" for c in comparisons)
    assert any(c["excluded"] == "true" for c in comparisons)
    with open(out / "trials.csv", newline="") as f:
        trials = list(csv.DictReader(f))
    excluded = [t for t in trials if t["excluded"] == "true"]
    assert [(t["trial"], t["exclusion_reason"]) for t in excluded] == [("3", "device_fault")]
    assert (
        float(trials[0]["step_length"])
        == s.config.space.values_of(int(trials[0]["action"]))["step_length"]
    )
    assert trials[0]["gait_id"] == f"g{trials[0]['action']}"
    with open(out / "posterior.csv", newline="") as f:
        posterior = list(csv.DictReader(f))
    assert len(posterior) == 15
    assert float(posterior[3]["mean"]) == float(s.posterior().mean[3])  # repr: exact
    lines = (out / "events.jsonl").read_text().splitlines()
    assert [json.loads(x)["seq"] for x in lines] == list(range(1, len(lines) + 1))
    out_json = tmp_path / "json"
    export_session(s, out_json, "json")
    validation = json.loads((out_json / "validation.json").read_text())
    assert sorted(v["role"] for v in validation) == ["max", "mean", "min"]


def test_a_tampered_export_is_refused_and_nothing_written(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    s = _session(sqlite_url, drive)
    out = tmp_path / "export"
    export_session(s, out, "csv")
    target = MemoryStorage()
    events = out / "events.jsonl"
    original = events.read_text()
    events.write_text(original.replace('"outcome": "first"', '"outcome": "second"', 1))
    with pytest.raises(ExportError, match="SHA-256"):
        import_session(target, out)
    # an edit that also fixes the hash is caught by replay
    manifest = json.loads((out / "manifest.json").read_text())
    import hashlib

    manifest["files"]["events.jsonl"] = hashlib.sha256(events.read_text().encode()).hexdigest()
    (out / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(ReplayError):
        import_session(target, out)
    assert target.list_sessions() == []
    with pytest.raises(ExportError, match="not a gaitpref export"):
        import_session(target, tmp_path)
    with pytest.raises(ExportError, match="not an empty folder"):
        export_session(s, out, "csv")


@pytest.mark.parametrize("table", ["trials.csv", "posterior.csv", "comparisons.csv"])
def test_every_file_in_the_manifest_is_checked(
    tmp_path: Path, sqlite_url: str, drive: Drive, table: str
) -> None:
    s = _session(sqlite_url, drive)
    out = tmp_path / "export"
    export_session(s, out, "csv")
    path = out / table
    path.write_text(path.read_text().replace("\n", "\n\n", 1))  # one edited table
    target = MemoryStorage()
    with pytest.raises(ExportError, match=f"{table} does not match its SHA-256"):
        import_session(target, out)
    path.unlink()
    with pytest.raises(ExportError, match=f"lacks {table}"):
        import_session(target, out)
    assert target.list_sessions() == []


def test_a_manifest_naming_a_file_outside_the_export_is_refused(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    s = _session(sqlite_url, drive)
    out = tmp_path / "export"
    export_session(s, out, "csv")
    (tmp_path / "elsewhere.txt").write_text("x")
    manifest = json.loads((out / "manifest.json").read_text())
    manifest["files"]["../elsewhere.txt"] = "0" * 64
    (out / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(ExportError, match="not inside the export"):
        import_session(MemoryStorage(), out)


@pytest.mark.parametrize(
    ("where", "key"),
    [("session", "software_version"), ("session", "subject"), (None, "config_name")],
)
def test_a_manifest_text_that_is_null_is_refused_by_name(
    tmp_path: Path, sqlite_url: str, drive: Drive, where: str | None, key: str
) -> None:
    s = _session(sqlite_url, drive)
    out = tmp_path / "export"
    export_session(s, out, "csv")
    manifest = json.loads((out / "manifest.json").read_text())
    (manifest if where is None else manifest[where])[key] = None
    (out / "manifest.json").write_text(json.dumps(manifest))
    target = MemoryStorage()
    name = key if where is None else f"{where}.{key}"
    with pytest.raises(ExportError, match=rf"manifest.json: {name} must be a non-empty text"):
        import_session(target, out)
    assert target.list_sessions() == []


def test_a_session_figure_without_a_suffix_is_a_png_and_a_folder_is_refused(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    from gaitpref.plots.session import save_session_figure

    s = _session(sqlite_url, drive)
    assert save_session_figure(s, tmp_path / "fig") == tmp_path / "fig.png"
    assert (tmp_path / "fig.png").is_file() and not (tmp_path / "fig").exists()
    with pytest.raises(ValueError, match="is a folder"):
        save_session_figure(s, tmp_path)
    assert not (tmp_path.parent / f"{tmp_path.name}.png").exists()


def test_learned_is_in_the_manifest_and_a_manifest_without_it_still_imports(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    """The posterior summary's ``learned`` (added after format version 1 was fixed) is written
    but never read: a fresh session's export says false and imports; a manifest without it, as
    earlier releases wrote, imports as before; the events are the same either way."""
    fresh = Session.create(sqlite_url, CONFIG, "S08", seed=5)
    export_session(fresh, tmp_path / "fresh", "json")
    manifest = json.loads((tmp_path / "fresh" / "manifest.json").read_text())
    assert manifest["format_version"] == 1
    summary = manifest["posterior"]
    assert summary["learned"] is False and summary["argmax"] == summary["recommended"] == 0
    import_session(f"sqlite:///{tmp_path / 'a.db'}", tmp_path / "fresh").close()
    s = _session(sqlite_url, drive)
    out = tmp_path / "old"
    export_session(s, out, "csv")
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["posterior"].pop("learned") is True
    (out / "manifest.json").write_text(json.dumps(manifest))  # as an earlier release wrote it
    imported = import_session(f"sqlite:///{tmp_path / 'b.db'}", out)
    assert [(e.seq, e.kind, e.payload, e.at) for e in imported.events()] == [
        (e.seq, e.kind, e.payload, e.at) for e in s.events()
    ]
    imported.close()


def test_importing_the_same_export_twice_needs_as_new(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    from gaitpref.sessions.export import origin_of

    s = _session(sqlite_url, drive)
    out = tmp_path / "export"
    export_session(s, out, "json")
    target = f"sqlite:///{tmp_path / 'other.db'}"
    first = import_session(target, out)
    with pytest.raises(ExportError, match=f"imported before as session {first.id}.*--as-new"):
        import_session(target, out)
    assert [r.id for r in Session.list_sessions(target)] == [first.id]
    second = import_session(target, out, as_new=True)
    assert second.id == first.id + 1
    assert origin_of(second.record) == f"imported from session {s.id}"
    # into the database that holds the exported session itself
    with pytest.raises(ExportError, match=f"the exported session itself, as session {s.id}"):
        import_session(sqlite_url, out)
    assert origin_of(s.record) is None
    first.close()
    second.close()


def test_an_export_of_an_imported_copy_is_refused_where_its_original_is(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    """A session taken to another database and exported from there (its row created anew, its
    log's times kept) was imported back beside its original as a second copy."""
    s = _session(sqlite_url, drive)
    export_session(s, tmp_path / "first", "csv")
    elsewhere = f"sqlite:///{tmp_path / 'analysis.db'}"
    copy = import_session(elsewhere, tmp_path / "first")
    export_session(copy, tmp_path / "back", "csv")
    copy.close()
    with pytest.raises(ExportError, match=f"the session it is a copy of, as session {s.id}"):
        import_session(sqlite_url, tmp_path / "back")
    assert [r.id for r in Session.list_sessions(sqlite_url)] == [s.id]
    import_session(sqlite_url, tmp_path / "back", as_new=True).close()


def test_session_list_marks_imported_sessions(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    from typer.testing import CliRunner

    from gaitpref.cli import app

    s = _session(sqlite_url, drive)
    export_session(s, tmp_path / "export", "csv")
    target = f"sqlite:///{tmp_path / 'other.db'}"
    runner = CliRunner()
    ok = runner.invoke(app, ["session", "import", str(tmp_path / "export"), "--db", target])
    assert ok.exit_code == 0, ok.output
    again = runner.invoke(app, ["session", "import", str(tmp_path / "export"), "--db", target])
    assert again.exit_code != 0 and "--as-new" in again.output
    new = ["session", "import", str(tmp_path / "export"), "--db", target, "--as-new"]
    assert runner.invoke(app, new).exit_code == 0
    listing = runner.invoke(app, ["session", "list", "--db", target], env={"COLUMNS": "200"})
    assert listing.output.count(f"imported from session {s.id}") == 2
    plain = runner.invoke(app, ["session", "list", "--db", sqlite_url], env={"COLUMNS": "200"})
    assert "imported" not in plain.output


def _consistent(out: Path) -> None:
    """Every file of the export is of the same event."""
    manifest = json.loads((out / "manifest.json").read_text())
    events = [json.loads(x) for x in (out / "events.jsonl").read_text().splitlines()]
    with open(out / "trials.csv", newline="") as f:
        trials = list(csv.DictReader(f))
    assert manifest["session"]["last_seq"] == len(events)
    assert len(trials) == sum(e["kind"] == "trial_executed" for e in events)


def test_an_export_is_of_one_event_while_another_writer_goes_on(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    """Before: the tables were of the session as opened and the log and the posterior of the
    database as it was later (trials.csv lacked the trials another writer had added)."""
    Session.create(sqlite_url, CONFIG, "S07", seed=17).close()
    exporter, writer = Session.open(sqlite_url, 1), Session.open(sqlite_url, 1)
    drive(writer, 2)  # after the exporter opened it
    export_session(exporter, tmp_path / "after", "csv")
    _consistent(tmp_path / "after")


@pytest.mark.parametrize("when", ["events", "_tables"])
@pytest.mark.parametrize("backend", ["memory", "sqlite"])
def test_an_export_is_of_one_event_while_another_writer_writes_meanwhile(
    tmp_path: Path, drive: Drive, monkeypatch: pytest.MonkeyPatch, when: str, backend: str
) -> None:
    """Another writer appends while the export reads the log, or builds its tables (whose
    posterior caught up midway before); it is not held up (an export holds no writer turn)."""
    import gaitpref.sessions.export as export_module

    store = MemoryStorage() if backend == "memory" else f"sqlite:///{tmp_path / 'lab.db'}"
    Session.create(store, CONFIG, "S07", seed=17).close()
    exporter, writer = Session.open(store, 1), Session.open(store, 1)
    drive(exporter, 2)
    owner = exporter if when == "events" else export_module
    original = getattr(owner, when)

    def meanwhile(*args: object) -> object:
        drive(writer, 1)
        return original(*args)

    monkeypatch.setattr(owner, when, meanwhile)
    export_session(exporter, tmp_path / "during", "csv")
    assert writer.last_seq > exporter.last_seq
    _consistent(tmp_path / "during")
    manifest = json.loads((tmp_path / "during" / "manifest.json").read_text())
    assert manifest["session"]["last_seq"] == exporter.last_seq


@pytest.mark.parametrize(
    "target", ["memory", "sqlite", pytest.param("postgres", marks=pytest.mark.postgres)]
)
def test_two_imports_of_one_export_at_once_make_one_session(
    request: pytest.FixtureRequest,
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    sqlite_url: str,
    drive: Drive,
    target: str,
) -> None:
    """Two importers could both pass the 'already imported' check before either created its
    session, and the database held two copies.  The check now runs in the transaction that
    creates the session, the second importer waiting for the first: one copy, one refusal."""
    import contextlib
    import threading
    from concurrent.futures import ThreadPoolExecutor

    from gaitpref.sessions import export

    s = Session.create(sqlite_url, CONFIG, "S07", seed=3)
    drive(s, 2)
    out = tmp_path / "export"
    export_session(s, out, "json")
    s.close()
    make: dict[str, Callable[[], str | MemoryStorage]] = {
        "memory": lambda: MemoryStorage(),
        "sqlite": lambda: f"sqlite:///{tmp_path / 'other.db'}",
        "postgres": lambda: str(request.getfixturevalue("postgres_url")),
    }
    db = make[target]()
    if isinstance(db, str):
        SQLStorage(db).close()  # the schema made before the race
    check, barrier = export._check_not_imported, threading.Barrier(2, timeout=2.0)

    def rendezvous(*args: object) -> None:  # both inside the check at once, if they can be
        check(*args)  # type: ignore[arg-type]
        with contextlib.suppress(threading.BrokenBarrierError):
            barrier.wait()

    monkeypatch.setattr(export, "_check_not_imported", rendezvous)
    with ThreadPoolExecutor(2) as pool:
        runs = [pool.submit(import_session, db, out) for _ in range(2)]
    outcomes = [r.exception(timeout=60) or r.result() for r in runs]
    imported = [o for o in outcomes if isinstance(o, Session)]
    refused = [o for o in outcomes if isinstance(o, ExportError)]
    assert len(imported) == 1 and len(refused) == 1, outcomes
    assert f"imported before as session {imported[0].id}" in str(refused[0])
    assert [r.id for r in Session.list_sessions(db)] == [imported[0].id]
    imported[0].close()


def test_csv_cells_a_spreadsheet_would_run_as_formulas_are_quoted(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    """A reason typed at the bench that starts like a formula ('=cmd|...' runs a command in some
    spreadsheets) is written to the CSV tables with a leading quote; the JSON tables, the event
    log and an import keep the text as typed."""
    s = Session.create(sqlite_url, CONFIG, "S08", seed=3)
    drive(s, 4)
    typed = "=cmd|' /C calc'!A0"
    s.exclude(2, "other", typed)
    s.flag_unsafe(3, "+1 wobble")
    export_session(s, tmp_path / "csv", "csv")
    export_session(s, tmp_path / "json", "json")
    cells = [
        cell
        for path in (tmp_path / "csv").glob("*.csv")
        for row in csv.reader(path.open(encoding="utf-8"))
        for cell in row
    ]
    assert any(cell.startswith("'=cmd") for cell in cells)
    assert "'+1 wobble" in cells
    assert not any(cell.startswith(("=", "+", "@")) for cell in cells)
    words = json.dumps([json.loads(p.read_text()) for p in (tmp_path / "json").glob("*.json")])
    assert json.dumps(typed)[1:-1] in words and "'=cmd" not in words
    imported = import_session(f"sqlite:///{tmp_path / 'back.db'}", tmp_path / "csv")
    assert [e.payload for e in imported.events()] == [e.payload for e in s.events()]
    imported.close()


@pytest.mark.parametrize("fmt", ["csv", "json"])
def test_an_export_written_where_text_files_end_lines_with_crlf_imports(
    tmp_path: Path, drive: Drive, monkeypatch: pytest.MonkeyPatch, fmt: str
) -> None:
    """Each file is written as the bytes its SHA-256 in the manifest is of: written as text on
    Windows, every "\\n" became "\\r\\n" and no export there could be imported (config.toml and
    events.jsonl did not match their hashes)."""
    s = Session.create(MemoryStorage(), CONFIG, "S01", seed=3)
    drive(s, 3)
    write_text = Path.write_text

    def as_on_windows(self: Path, data: str, *args: Any, **kwargs: Any) -> int:
        return write_text(self, data, *args, **{"newline": "\r\n", **kwargs})

    monkeypatch.setattr(Path, "write_text", as_on_windows)
    export_session(s, tmp_path / "export", fmt)  # type: ignore[arg-type]
    monkeypatch.undo()
    imported = import_session(MemoryStorage(), tmp_path / "export")
    assert imported.last_seq == s.last_seq
    imported.close()


def test_an_export_folder_is_made_as_mkdir_makes_one(tmp_path: Path, drive: Drive) -> None:
    """The export folder was the hidden work folder renamed, made by mkdtemp with mode 0700: a
    colleague's account could not read it (its import: permission denied), and an empty folder
    given to export into was replaced by one with that mode."""
    s = Session.create(MemoryStorage(), CONFIG, "S01", seed=3)
    drive(s, 2)
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o750)  # a folder its group may read
    umask = os.umask(0o022)
    try:
        export_session(s, tmp_path / "new", "csv")
        export_session(s, shared, "csv")
    finally:
        os.umask(umask)
    assert stat.S_IMODE((tmp_path / "new").stat().st_mode) == 0o755
    assert stat.S_IMODE(shared.stat().st_mode) == 0o750
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new", "shared"]  # no work folder left


def test_an_import_names_a_missing_folder_a_file_and_a_folder_in_a_files_place(
    tmp_path: Path, drive: Drive
) -> None:
    """Each said the export lacks a file (a folder named events.jsonl: 'lacks events.jsonl'; a
    path that is not there, or the manifest itself given: 'no manifest.json')."""
    s = Session.create(MemoryStorage(), CONFIG, "S01", seed=3)
    drive(s, 2)
    out = tmp_path / "export"
    export_session(s, out, "csv")
    target = tmp_path / "target.db"
    cases = [
        (tmp_path / "nowhere", r"'.*nowhere' does not exist"),
        (out / "manifest.json", "is a file, not an export's folder"),
    ]
    for folder, match in cases:
        with pytest.raises(ExportError, match=match):
            import_session(f"sqlite:///{target}", folder)
    (out / "events.jsonl").unlink()
    (out / "events.jsonl").mkdir()
    with pytest.raises(ExportError, match=r"events\.jsonl, which manifest\.json lists, is a fold"):
        import_session(f"sqlite:///{target}", out)
    assert not target.exists()


def test_the_working_folder_is_refused_by_name(
    tmp_path: Path, sqlite_url: str, drive: Drive, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--out .`` failed with "[Errno 22] Invalid argument: '.'" (an empty working folder);
    the export replaces its folder, so the one the command runs in is refused by name."""
    s = _session(sqlite_url, drive)
    here = tmp_path / "empty"
    here.mkdir()
    monkeypatch.chdir(here)
    for out in (Path("."), here, Path("..") / "empty"):
        with pytest.raises(ExportError, match="is the working folder; give a new folder's name"):
            export_session(s, out, "csv")
    assert list(here.iterdir()) == [] and here.is_dir()
    export_session(s, Path("sub"), "csv")  # a new folder inside it: fine
    assert (here / "sub" / "manifest.json").is_file()


NAMED_LIKE_COLUMNS = """
name = "columns"
[space.mean]
min = 0.1
max = 0.3
num = 3
[space.action]
min = 1.0
max = 2.0
num = 2
[space.mean_value]
min = 5.0
max = 6.0
num = 2
[model]
lengthscale = 0.5
signal_variance = 1.0
noise = 0.1
"""


def test_features_named_like_a_column_keep_both_values(tmp_path: Path) -> None:
    """A feature named ``mean`` or ``action`` overwrote the posterior's mean and the trial's
    action in the tables (or was overwritten by them): now its column is ``NAME_value``."""
    from gaitpref.config import parse_config

    s = Session.create(MemoryStorage(), parse_config(NAMED_LIKE_COLUMNS), "S01", seed=1)
    q = s.next_query()
    s.answer(q.id, [(q.actions[0], q.actions[1])] if len(q.actions) > 1 else [])
    export_session(s, tmp_path / "out", "json")
    tables = {
        name: json.loads((tmp_path / "out" / f"{name}.json").read_text())
        for name in ("trials", "posterior", "confidence")
    }
    for row in tables["trials"]:
        values = s.space.values_of(row["action"])  # the action is the grid index again
        assert (row["mean_value_2"], row["action_value"], row["mean_value"]) == (
            values["mean"],
            values["action"],
            values["mean_value"],
        )
    post = s.posterior()
    for row in tables["posterior"]:
        a = row["action"]
        assert row["mean"] == pytest.approx(float(post.mean[a]))  # the posterior's, not 0.1-0.3
        assert row["mean_value_2"] == s.space.values_of(a)["mean"]
    assert {"action", "action_value", "mean_value_2"} <= set(tables["confidence"][0])


def test_paths_may_be_given_as_text(tmp_path: Path, sqlite_url: str, drive: Drive) -> None:
    """``export_session(s, "out")`` and ``import_session(db, "out")`` failed on ``str.exists``."""
    s = _session(sqlite_url, drive)
    manifest = export_session(s, str(tmp_path / "out"), "csv")
    assert manifest == tmp_path / "out" / "manifest.json" and manifest.is_file()
    again = import_session(MemoryStorage(), str(tmp_path / "out"))
    assert [e.payload for e in again.events()] == [e.payload for e in s.events()]


def test_an_export_into_a_link_to_an_empty_folder_fills_that_folder(
    tmp_path: Path, sqlite_url: str, drive: Drive
) -> None:
    """An --out that is a symbolic link to an empty folder (or a mount point: neither can be
    removed and replaced) is filled; before, it failed with '[Errno 20] Not a directory'."""
    s = Session.create(sqlite_url, CONFIG, "S01")
    drive(s, 3)
    target = tmp_path / "usb"
    target.mkdir()
    link = tmp_path / "today"
    link.symlink_to(target, target_is_directory=True)
    export_session(s, link, "csv")
    n = s.last_seq
    s.close()
    assert link.is_symlink()
    assert sorted(p.name for p in target.iterdir() if p.name.startswith(".")) == []
    assert (target / "manifest.json").is_file()
    imported = import_session(MemoryStorage(), target)
    assert imported.last_seq == n
    imported.close()


def test_features_named_learned_or_made_keep_the_confidence_columns(tmp_path: Path) -> None:
    """The confidence table's ``learned`` and ``made`` columns (added after the rule above) were
    not among the names a feature's column is renamed from: a feature named ``learned`` wrote its
    value over the column (and ``made`` likewise), so a row said a preference was learned where
    it held a step length."""
    from gaitpref.config import parse_config

    text = NAMED_LIKE_COLUMNS.replace("[space.mean]", "[space.learned]").replace(
        "[space.action]", "[space.made]"
    )
    s = Session.create(MemoryStorage(), parse_config(text), "S01", seed=1)
    for _ in range(2):
        q = s.next_query()
        s.answer(q.id, [(a, b, "first") for a, b in q.compared])
    export_session(s, tmp_path / "out", "json")
    rows = json.loads((tmp_path / "out" / "confidence.json").read_text())
    assert rows and all(isinstance(row["learned"], bool) for row in rows)
    assert all(row["made"] is None for row in rows)  # no gaits made on demand
    for row in rows:
        if row["learned"]:
            values = s.space.values_of(row["action"])
            assert (row["learned_value"], row["made_value"]) == (values["learned"], values["made"])
