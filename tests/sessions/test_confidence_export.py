"""The export's ``confidence`` table: the confidence after every answer, undo and exclusion,
exactly as the session stated it at the time (its own generator, replayed afresh)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from gaitpref import Session
from gaitpref.sessions import preference_learned
from gaitpref.sessions.export import export_session
from gaitpref.storage import MemoryStorage
from tests.sessions.sessionkit import CONFIG, Drive

COLUMNS = {
    "seq", "answers", "trials", "learned", "action", "gait", "made", "probability", "regret",
    "relative_regret", "tolerance", "samples", "at",
}  # fmt: skip


def test_the_confidence_table_repeats_what_was_stated_after_every_step(
    tmp_path: Path, drive: Drive
) -> None:
    s = Session.create(MemoryStorage(), CONFIG, "S07", seed=5)
    stated: list[tuple[int, int, int | None, float | None]] = []
    for _ in range(5):
        drive(s, 1)
        if preference_learned(s.posterior().mean):  # as the terminal and the console state it
            sure = s.confidence()
            stated.append((s.last_seq, len(s.trials()), sure.recommended, sure.probability))
        else:  # the first trial, with nothing to compare: no confidence stated, no gait named
            stated.append((s.last_seq, len(s.trials()), None, None))
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
    assert rows[0]["learned"] is False and all(r["learned"] for r in rows[1:])
    assert all(0.0 <= r["probability"] <= 1.0 and r["regret"] >= 0.0 for r in rows[1:])

    export_session(s, tmp_path / "csv", "csv")
    with open(tmp_path / "csv" / "confidence.csv", newline="") as f:
        table = list(csv.DictReader(f))
    features = {f.name for f in s.space.features}  # the recommended gait's values then
    assert set(table[0]) == COLUMNS | features and len(table) == len(rows)
    assert {k: table[0][k] for k in features} == dict.fromkeys(features, "")  # none named
    assert {k: float(table[1][k]) for k in features} == s.space.values_of(rows[1]["action"])
    assert [float(r["probability"]) for r in table[1:]] == [r["probability"] for r in rows[1:]]
    assert table[0]["probability"] == "" and table[0]["learned"] == "false"
    assert table[1]["gait"] == s.gait_name(rows[1]["action"]) and table[0]["at"]
    assert {r["made"] for r in rows} == {None}  # no gaits made on demand: nothing to make
    export_session(s, tmp_path / "json", "json")
    assert (
        json.loads((tmp_path / "json" / "confidence.json").read_text())[-1]["seq"]
        == rows[-1]["seq"]
    )


def test_a_row_after_an_answer_that_taught_nothing_names_no_gait(tmp_path: Path) -> None:
    """After a first trial (nothing to compare) and a tie the posterior mean is flat: the
    recommendation would be the first gait for no reason, and the terminal and the console
    state no confidence.  The table still has a row for each answer, saying so (``learned``
    false) and naming no gait; it named G0 with a probability before."""
    from fastapi.testclient import TestClient

    from gaitpref.console import create_app

    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with Session.create(url, CONFIG, "S01", seed=3) as s:
        q = s.next_query()
        assert not q.buffer  # the first trial: nothing to compare
        s.answer(q.id, [])
        q = s.next_query()
        a, b = q.actions[0], q.buffer[0]
        s.answer(q.id, [(a, b, "none")])  # a tie: nothing told apart
        assert not preference_learned(s.posterior().mean)
        sid = s.id
        with TestClient(create_app(url)) as client:  # the console states nothing either
            shown = client.get(f"/api/sessions/{sid}/posterior").json()
        assert shown["learned"] is False and shown["confidence"] is None
        tied = s.confidence_history()
        q = s.next_query()
        a, b = q.actions[0], q.buffer[0]
        s.answer(q.id, [(a, b, "first")])  # a preference: now a gait is recommended
        rows = s.confidence_history()
        sure = s.confidence()
        export_session(s, tmp_path / "out", "csv")
    assert tied == rows[:2] and [r["answers"] for r in rows] == [1, 2, 3]
    for row in rows[:2]:
        assert row["learned"] is False
        assert row["action"] is row["gait"] is row["probability"] is row["regret"] is None
        assert set(row["values"].values()) == {None}
    assert rows[2]["learned"] is True and rows[2]["action"] == sure.recommended
    assert rows[2]["probability"] == sure.probability
    with (tmp_path / "out" / "confidence.csv").open(newline="", encoding="utf-8") as f:
        table = list(csv.DictReader(f))
    assert [r["learned"] for r in table] == ["false", "false", "true"]
    assert [r["gait"] for r in table] == ["", "", s.gait_name(sure.recommended)]
