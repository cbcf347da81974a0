"""The export's ``confidence`` table: the confidence after every answer, undo and exclusion,
exactly as the session stated it at the time (its own generator, replayed afresh)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from gaitpref import Session
from gaitpref.sessions.export import export_session
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG, Drive

COLUMNS = {
    "seq", "answers", "trials", "action", "gait", "made", "probability", "regret",
    "relative_regret", "tolerance", "samples", "at",
}  # fmt: skip


def test_the_confidence_table_repeats_what_was_stated_after_every_step(
    tmp_path: Path, drive: Drive
) -> None:
    s = Session.create(MemoryStorage(), CONFIG, "S07", seed=5)
    stated = []
    for _ in range(5):
        drive(s, 1)
        sure = s.confidence()
        stated.append((s.last_seq, len(s.trials()), sure.recommended, sure.probability))
    s.undo()
    after_undo = s.confidence()
    undo_seq = s.last_seq
    s.exclude(2, "device_fault")
    after_exclusion = s.confidence()
    drive(s, 1)  # a query event (no new model) and an answer

    rows = s.confidence_history()
    assert [(r["seq"], r["trials"], r["action"], r["probability"]) for r in rows[:5]] == stated
    assert rows[5]["seq"] == undo_seq and rows[5]["probability"] == after_undo.probability
    assert rows[5]["answers"] == 4
    assert rows[6]["probability"] == after_exclusion.probability
    assert rows[-1]["probability"] == s.confidence().probability and len(rows) == 8
    assert all(0.0 <= r["probability"] <= 1.0 and r["regret"] >= 0.0 for r in rows)

    export_session(s, tmp_path / "csv", "csv")
    with open(tmp_path / "csv" / "confidence.csv", newline="") as f:
        table = list(csv.DictReader(f))
    features = {f.name for f in s.space.features}  # the recommended gait's values then
    assert set(table[0]) == COLUMNS | features and len(table) == len(rows)
    assert {k: float(table[0][k]) for k in features} == s.space.values_of(rows[0]["action"])
    assert [float(r["probability"]) for r in table] == [r["probability"] for r in rows]
    assert table[0]["gait"] == s.gait_name(rows[0]["action"]) and table[0]["at"]
    assert {r["made"] for r in rows} == {None}  # no gaits made on demand: nothing to make
    export_session(s, tmp_path / "json", "json")
    assert (
        json.loads((tmp_path / "json" / "confidence.json").read_text())[-1]["seq"]
        == rows[-1]["seq"]
    )
