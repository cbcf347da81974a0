"""Every column an export writes is named in docs/sessions.md's column reference ("The tables,
column by column"), in the order written, and the documented relations between the tables and
`manifest.json` hold: an analysis that follows the docs gets the numbers `session show --json`
reports."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np

from gaitpref import Session
from gaitpref.feedback import Comparison, Outcome, Rating
from gaitpref.sessions.export import export_session

DOC = Path(__file__).resolve().parents[2] / "docs" / "sessions.md"
FEATURES = ["step_length", "step_width"]


def reference() -> dict[str, list[str]]:
    """The documented columns of each table, in order (FEATURES for the features)."""
    text = DOC.read_text(encoding="utf-8")
    section = text.split("### The tables, column by column", 1)[1]
    start = section.index("\n- ")
    bullets = section[start : section.index("\n\n", start)]  # the list, to its blank line
    out: dict[str, list[str]] = {}
    for item in re.split(r"\n- ", bullets)[1:]:
        name = re.match(r"`(\w+)`", item)
        assert name is not None, item[:40]
        found = re.findall(r"`(\w+)`|(FEATURES)", item[name.end() :])
        out[name.group(1)] = [quoted or word for quoted, word in found]
    return out


def rows(folder: Path, name: str) -> list[dict[str, str]]:
    with (folder / f"{name}.csv").open(newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def test_export_columns_are_documented_in_order(tmp_path: Path) -> None:
    with Session.create(f"sqlite:///{tmp_path / 'lab.db'}", "exo-2d-rated", subject="S01") as s:
        for i in range(6):
            q = s.next_query()
            (a,) = q.actions
            answers: list[object] = [Rating(a, ["bad", "okay", "good"][i % 3])]
            if q.buffer and q.buffer[0] != a:
                outcome: Outcome = ("first", "second", "none")[i % 3]
                answers.append(Comparison(a, q.buffer[0], outcome))
            s.answer(q.id, answers, [(a, "step_length", "+small")] if i % 2 else [])
            if i == 2:
                s.undo()
        s.exclude(s.trials()[-2].number, "stumble", detail="-tripped")
        s.flag_unsafe(s.trials()[-1].number, "knee gave way")
        plan = s.start_validation()
        s.answer_validation(plan.round, "BAC")
        export_session(s, tmp_path / "csv", "csv")
        export_session(s, tmp_path / "json", "json")
    documented = reference()
    assert set(documented) == {
        "trials", "comparisons", "suggestions", "posterior", "validation", "confidence", "ratings"
    }  # fmt: skip
    for table, columns in documented.items():
        # the documented column names, with FEATURES standing for the features; other words
        # quoted in an item (values such as `stumble`, `+big`) are not columns
        header = list(rows(tmp_path / "csv", table)[0])
        expected = [
            c for c in columns if c in header or c == "FEATURES"
        ]  # documented names, in the doc's order of first mention
        seen: list[str] = []
        for c in expected:
            for name in FEATURES if c == "FEATURES" else [c]:
                if name not in seen:
                    seen.append(name)
        assert seen == header, table
        listed = json.loads((tmp_path / "json" / f"{table}.json").read_text(encoding="utf-8"))
        assert list(listed[0]) == header, table

    # the documented relations: the manifest's argmax is the posterior table's highest mean,
    # in-force counts include the excluded trial, excluded and unsafe flags are on the trials
    manifest = json.loads((tmp_path / "csv" / "manifest.json").read_text(encoding="utf-8"))
    post = rows(tmp_path / "csv", "posterior")
    assert int(np.argmax([float(r["mean"]) for r in post])) == manifest["posterior"]["argmax"]
    trials = [r for r in rows(tmp_path / "csv", "trials") if r["undone"] == "false"]
    assert len(trials) == manifest["posterior"]["trials_in_force"] == 5
    assert [r["exclusion_detail"] for r in trials if r["excluded"] == "true"] == ["'-tripped"]
    assert [r["unsafe_reason"] for r in trials if r["unsafe"] == "true"] == ["knee gave way"]
    moves = {r["move"] for r in rows(tmp_path / "csv", "suggestions")}
    assert moves == {"'+small"}
    last = rows(tmp_path / "csv", "confidence")[-1]
    assert int(last["trials"]) == 5
    assert set(manifest) == {
        "format", "format_version", "software_version", "exported_at", "config_name",
        "config_sha256", "seed", "session", "features", "posterior", "files",
    }  # fmt: skip
    assert set(manifest["session"]) == {
        "id", "subject", "status", "software_version", "created_at", "last_seq", "meta"
    }  # fmt: skip
