"""What an export shares (docs/sessions.md, "What an export shares"): the subject code and
every text typed at the bench, where the docs say; never the database's URL, its location or a
password."""

from __future__ import annotations

import json
from pathlib import Path

from gaitpref import Session
from gaitpref.sessions.export import export_session
from tests.sessions.sessionkit import CONFIG, Drive


def test_an_export_holds_the_typed_text_and_not_the_database(tmp_path: Path, drive: Drive) -> None:
    folder = tmp_path / "clinic-private-folder"
    folder.mkdir()
    s = Session.create(f"sqlite:///{folder / 'lab.db'}", CONFIG, "S-code-17", seed=3)
    drive(s, 3)
    s.note("note-text: knee sore today")
    s.flag_unsafe(1, "unsafe-reason: left knee buckled")
    s.flag_unsafe(2, "withdrawn-reason: mis-keyed")
    s.withdraw_unsafe(2)
    s.exclude(3, "other", "exclusion-detail: phone rang")
    s.start_validation()
    s.withdraw_validation(1, "validation-reason: subject tired")
    out = tmp_path / "export"
    export_session(s, out, "csv")
    s.close()
    files = {p.name: p.read_text() for p in out.rglob("*") if p.is_file()}
    everything = "\n".join(files.values())
    assert "clinic-private-folder" not in everything and "lab.db" not in everything
    assert "sqlite" not in everything
    manifest = json.loads(files["manifest.json"])
    assert manifest["session"]["subject"] == "S-code-17"
    events = [json.loads(line) for line in files["events.jsonl"].splitlines()]
    assert events[0]["payload"]["subject"] == "S-code-17"
    payloads = json.dumps([e["payload"] for e in events])
    for typed in ("note-text", "unsafe-reason", "withdrawn-reason", "exclusion-detail"):
        assert typed in payloads, typed
    assert "validation-reason" in payloads
    assert "unsafe-reason" in files["trials.csv"] and "exclusion-detail" in files["trials.csv"]
    assert "withdrawn-reason" not in files["trials.csv"]  # a withdrawn flag: in the log only
    assert "note-text" not in "".join(v for k, v in files.items() if k != "events.jsonl")


def test_a_warm_started_export_names_the_earlier_subjects(tmp_path: Path, drive: Drive) -> None:
    db = f"sqlite:///{tmp_path / 'lab.db'}"
    first = Session.create(db, CONFIG, "S-earlier-01", seed=3)
    drive(first, 2)
    first.close()
    s = Session.create(db, CONFIG, "S-later-02", seed=4, prior_from=[first.id])
    out = tmp_path / "export"
    export_session(s, out, "json")
    s.close()
    manifest = json.loads((out / "manifest.json").read_text())
    assert [p["subject"] for p in manifest["session"]["meta"]["prior_from"]] == ["S-earlier-01"]
    created = json.loads((out / "events.jsonl").read_text().splitlines()[0])
    assert created["payload"]["prior_from"][0]["subject"] == "S-earlier-01"


def test_the_docs_say_what_an_export_shares() -> None:
    docs = (Path(__file__).parents[2] / "docs" / "sessions.md").read_text()
    section = docs.split("### What an export shares", 1)[1].split("\n#", 1)[0]
    for named in (
        "session.subject",
        "prior_from",
        "`note`",
        "unsafe_reason",
        "exclusion_detail",
        "validation_withdrawn",
        "`at`",
        "library_path",
        "no database URL",
    ):
        assert named in section, named
