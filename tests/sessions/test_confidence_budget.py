"""The confidence after each answer reads a bounded number of sampled values.

Every sample covers every gait, so ``[stop] samples = 2000`` (the default) cost 7.5 s (idle) to
15 s (loaded) after each answer on the shipped 57,750-gait ``synthetic-6d`` grid and 2 minutes on
2**20 gaits (BLAS's default threads, as the confidence drew then; on one thread, as now, 21.7 s
on 57,750 gaits at load 4-5: ``benchmarks/results/stopping.md``), and as much again for every
row of an export.  A session now reads at most
``CONFIDENCE_VALUES`` values (fewer samples on large grids, never fewer than 100); a ``[stop]
samples`` given past that is refused when a session is created, naming the key, and a session
stored with one still opens and reads the bounded count.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

import gaitpref.loop.stopping as stopping
from gaitpref import ConfigError, Session
from gaitpref.cli import app
from gaitpref.config import check_draws, load_config, parse_config
from gaitpref.loop.stopping import StopRule
from gaitpref.storage import MemoryStorage

GRID = load_config("synthetic-2d").text  # 30 x 30 gaits, no [stop] table


def test_the_rules_samples_shrink_with_the_grid_down_to_a_floor() -> None:
    rule = StopRule()
    assert rule.samples_for(900) == 2000  # the paper's grid: as before
    assert rule.samples_for(57_750) == (1 << 24) // 57_750 == 290  # synthetic-6d
    assert rule.samples_for(1 << 20) == 100  # never fewer than 100
    assert StopRule(samples=150).samples_for(57_750) == 150  # fewer asked: as asked
    for bad in (0, -1, 2.5, True):
        with pytest.raises(ValueError, match="actions must be an integer >= 1"):
            rule.samples_for(bad)  # type: ignore[arg-type]


def test_the_shipped_6d_config_reads_a_bounded_count() -> None:
    cfg = load_config("synthetic-6d")
    assert "stop.samples" in cfg.defaulted
    check_draws(cfg)  # the default is sized to the grid: nothing to refuse
    assert cfg.stop.samples_for(len(cfg.space)) * len(cfg.space) <= stopping.CONFIDENCE_VALUES


def test_a_given_samples_past_the_budget_is_refused_naming_the_key(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(stopping, "CONFIDENCE_VALUES", 900 * 150)
    cfg = parse_config(GRID + "\n[stop]\nsamples = 2000\n")
    with pytest.raises(ConfigError, match=r"^\[stop\].samples: is 2000") as err:
        check_draws(cfg)
    assert (err.value.table, err.value.key) == ("stop", "samples")
    assert "over the 900 gaits" in str(err.value) and "at most 150" in str(err.value)
    check_draws(parse_config(GRID + "\n[stop]\nsamples = 150\n"))  # at the budget: taken
    db = MemoryStorage()
    with pytest.raises(ConfigError, match="samples: is 2000"):
        Session.create(db, cfg, "S01")
    assert Session.list_sessions(db) == []  # nothing written


def test_the_cli_refuses_it_before_a_run(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setattr(stopping, "CONFIDENCE_VALUES", 900 * 150)
    path = tmp_path / "stop.toml"
    path.write_text(GRID + "\n[stop]\nsamples = 2000\n", encoding="utf-8")
    db = tmp_path / "s.db"
    result = CliRunner().invoke(
        app, ["session", "new", "--config", str(path), "--subject", "S01", "--db", str(db)]
    )
    assert result.exit_code == 2, result.output
    assert "[stop].samples: is 2000" in result.output and "at most 150" in result.output
    assert not db.exists()  # nothing written


def test_sessions_read_the_bounded_count_stored_ones_too(monkeypatch: pytest.MonkeyPatch) -> None:
    """A session made before the check (samples given past the budget) opens, and its
    confidence, live and in the export's history, reads the bounded count."""
    import gaitpref.config.new

    monkeypatch.setattr(stopping, "CONFIDENCE_VALUES", 900 * 150)
    db = MemoryStorage()
    with monkeypatch.context() as m:
        m.setattr(gaitpref.config.new, "check_draws", lambda config: None)
        made = Session.create(db, parse_config(GRID + "\n[stop]\nsamples = 2000\n"), "S01")
    for _ in range(2):  # a first trial (nothing to compare), then a preference: one stated
        q = made.next_query()
        pair = [*q.actions, *q.buffer][:2]
        made.answer(q.id, [(pair[0], pair[1], "first")] if len(pair) > 1 else [])
    again = Session.open(db, made.id)
    assert again.config.stop.samples == 2000
    assert again.confidence().samples == 150
    history = again.confidence_history()
    assert [row["samples"] for row in history if row["learned"]] == [150]
    # within the budget the rule's own count is read, as before
    fresh = Session.create(db, parse_config(GRID + "\n[stop]\nsamples = 120\n"), "S02")
    q = fresh.next_query()
    fresh.answer(q.id, [(q.actions[0], q.actions[1])] if len(q.actions) > 1 else [])
    assert fresh.confidence().samples == 120


def test_an_export_reports_its_progress_through_the_log(tmp_path: Path) -> None:
    """The confidence table replays the whole log: ``progress`` sees every event, in order."""
    from gaitpref.sessions import export_session

    db = MemoryStorage()
    session = Session.create(db, parse_config(GRID), "S01")
    for _ in range(3):
        q = session.next_query()
        session.answer(q.id, [(q.actions[0], q.actions[1])] if len(q.actions) > 1 else [])
    seen: list[tuple[int, int]] = []
    export_session(
        session, tmp_path / "out", "json", lambda done, total: seen.append((done, total))
    )
    events = len(session.events())
    assert seen[-1] == (events, events) and {total for _, total in seen} == {events}
    assert [done for done, _ in seen] == sorted({done for done, _ in seen})  # forward, once each
    assert len(seen) >= 3  # a step per answer at least
