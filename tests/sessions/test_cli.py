"""The session commands, driven through Typer's test runner."""

from __future__ import annotations

import json
import sqlite3
from datetime import UTC
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref import Session
from gaitpref.cli import app
from tests.sessions.sessionkit import CONFIG, Drive

runner = CliRunner()


def _ok(*args: str) -> str:
    result = runner.invoke(app, list(args))
    assert result.exit_code == 0, result.output
    return result.output


def _fails(*args: str) -> str:
    result = runner.invoke(app, list(args))
    assert result.exit_code == 2, result.output
    return result.output


def test_new_list_show_note_finish(tmp_path: Path, drive: Drive) -> None:
    db = str(tmp_path / "lab.db")  # a bare path means SQLite
    out = _ok("session", "new", "--config", CONFIG, "--subject", "S01", "--seed", "4", "--db", db)
    assert "session 1" in out and "gaitpref session run 1" in out
    session = Session.open(db, 1)
    drive(session, 6)
    assert "S01" in _ok("session", "list", "--db", db)
    assert "1 session, 1 subject" in _ok("db", "status", "--db", db)  # it said "1 sessions"
    _ok("session", "note", "1", "knee strap loosened", "--db", db)
    _ok("session", "exclude", "1", "3", "--reason", "device-fault", "--detail", "E12", "--db", db)
    figure = tmp_path / "fig.png"
    info = json.loads(_ok("session", "show", "1", "--json", "--figure", str(figure), "--db", db))
    assert info["trials"] == 6 and info["excluded"] == [3] and figure.stat().st_size > 10_000
    # the fields docs/sessions.md lists for `session show --json`
    assert set(info) == {
        "id",
        "subject",
        "config",
        "seed",
        "status",
        "trials",
        "excluded",
        "comparisons",
        "unsafe",
        "posterior",
        "validations",
        "validation_rounds",
        "figure",
        "prior_from",
        "prior_rho",
    }
    assert info["figure"] == str(figure) and info["status"] == "active"
    assert set(info["posterior"]) == {
        "argmax",
        "argmax_values",
        "argmax_gait_id",
        "mean_at_argmax",
        "sd_at_argmax",
        "argmax_made",
        "recommended",
        "recommended_values",
        "recommended_gait_id",
        "mean_at_recommended",
        "sd_at_recommended",
        "recommended_made",
        "learned",
        "trials_in_force",
        "pending_query",
    }
    reopened = Session.open(db, 1)
    assert info["posterior"]["argmax"] == reopened.posterior().argmax
    assert info["posterior"]["recommended"] == reopened.recommended()
    assert info["posterior"]["learned"] is True  # answers given: a best so far is named
    # no gaits made on demand: nothing to make, as the console API's made says it (null)
    assert info["posterior"]["recommended_made"] is None is info["posterior"]["argmax_made"]
    assert "undone: the answer to trial 6" in _ok("session", "undo", "1", "--yes", "--db", db)
    assert "Unblinded" in _ok("session", "validate", "1", "--ranking", "ABC", "--yes", "--db", db)
    _ok("session", "finish", "1", "--yes", "--db", db)
    assert "finished" in _fails("session", "undo", "1", "--yes", "--db", db)
    text = _ok("session", "show", "1", "--no-figure", "--db", db)
    assert "finished" in text and "5 trials (1 excluded)" in text and "validation 1" in text


def test_export_import(tmp_path: Path, drive: Drive) -> None:
    db, other = str(tmp_path / "a.db"), f"sqlite:///{tmp_path / 'b.db'}"
    s = Session.create(db, CONFIG, "S02", seed=9)
    drive(s, 5)
    out = tmp_path / "export"
    _ok("session", "export", str(s.id), "--format", "json", "--out", str(out), "--db", db)
    assert (out / "comparisons.json").is_file() and (out / "manifest.json").is_file()
    assert "imported as session 1" in _ok("session", "import", str(out), "--db", other)
    np.testing.assert_array_equal(Session.open(other, 1).posterior().mean, s.posterior().mean)
    assert "not an empty folder" in _fails("session", "export", "1", "--out", str(out), "--db", db)
    assert "csv or json" in _fails("session", "export", "1", "--format", "xml", "--out",
                                   str(tmp_path / "x"), "--db", db)  # fmt: skip


def test_errors_are_clear_and_write_nothing(tmp_path: Path) -> None:
    db = str(tmp_path / "lab.db")
    assert "no gaitpref database" in _fails("session", "list", "--db", db)
    assert "no gaitpref database" in _fails("session", "show", "1", "--db", db)
    assert not Path(db).exists()
    bad = tmp_path / "bad.toml"
    bad.write_text("[space.x]\nvalues = [1, 2]\n[model]\nnoise = 0.1\n")
    assert "lengthscale" in _fails("session", "new", "--config", str(bad), "--subject", "S1",
                                   "--db", db)  # fmt: skip
    assert not Path(db).exists()
    _ok("session", "new", "--config", CONFIG, "--subject", "S01", "--db", db)
    assert "no session 7" in _fails("session", "show", "7", "--db", db)
    assert "nothing to undo" in _fails("session", "undo", "1", "--yes", "--db", db)
    assert "reason must be one of" in _fails("session", "exclude", "1", "1", "--reason", "bored",
                                             "--db", db)  # fmt: skip
    assert "flat" in _fails("session", "validate", "1", "--ranking", "ABC", "-y", "--db", db)
    with sqlite3.connect(db) as raw:
        assert raw.execute("SELECT count(*) FROM events").fetchone() == (1,)
        raw.execute("UPDATE alembic_version SET version_num = 'zzzz'")
    assert "newer gaitpref" in _fails("session", "list", "--db", db)
    assert "newer gaitpref" in _fails("db", "upgrade", "--db", db)
    assert "cannot connect" in _fails("session", "list", "--db",
                                      "postgresql+psycopg://x@127.0.0.1:1/none")  # fmt: skip


def test_db_upgrade_creates_and_is_idempotent(tmp_path: Path) -> None:
    db = str(tmp_path / "new.db")
    assert "schema revision 0002" in _ok("db", "upgrade", "--db", db)
    assert "schema revision 0002" in _ok("db", "upgrade", "--db", db)
    assert "0 sessions" in _ok("db", "status", "--db", db)


def test_default_database_from_the_environment(tmp_path: Path, monkeypatch: object) -> None:
    import pytest

    assert isinstance(monkeypatch, pytest.MonkeyPatch)
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("GAITPREF_DB", raising=False)
    _ok("session", "new", "--config", CONFIG, "--subject", "S01")
    assert (tmp_path / "gaitpref.db").is_file()
    monkeypatch.setenv("GAITPREF_DB", f"sqlite:///{tmp_path / 'env.db'}")
    _ok("session", "new", "--config", CONFIG, "--subject", "S01")
    assert (tmp_path / "env.db").is_file()


def test_unsafe_flag_and_withdrawal_from_the_cli(tmp_path: Path, drive: Drive) -> None:
    db = str(tmp_path / "lab.db")
    s = Session.create(f"sqlite:///{db}", CONFIG, "S01", seed=2)
    drive(s, 3)
    s.close()
    assert "give --reason" in _fails("session", "unsafe", "1", "2", "--db", db)
    out = _ok("session", "unsafe", "1", "2", "--reason", "knee gave way", "--db", db)
    assert "trial 2 flagged unsafe (knee gave way)" in out
    # the config's unsafe_radius is 0: no neighbour is removed, and none is said to be
    assert "its gait will not be proposed again" in out and "neighbour" not in out
    assert "already flagged" in _fails("session", "unsafe", "1", "2", "--reason", "x", "--db", db)
    with Session.open(f"sqlite:///{db}", 1) as again:
        assert again.unsafe_flags()[2][1] == "knee gave way"
        action = again.unsafe_flags()[2][0]
        gait = again.gait_name(action)
    # session show lists the flag in force: in the text, and in --json as the API names it
    text = _ok("session", "show", "1", "--no-figure", "--db", db)
    assert f"flagged unsafe: trial 2, gait {gait} (knee gave way)" in text
    info = json.loads(_ok("session", "show", "1", "--json", "--no-figure", "--db", db))
    assert info["unsafe"] == [
        {"trial": 2, "action": action, "gait": gait, "reason": "knee gave way"}
    ]
    assert "withdrawn" in _ok("session", "unsafe", "1", "2", "--withdraw", "--db", db)
    with Session.open(f"sqlite:///{db}", 1) as again:
        assert again.unsafe_flags() == {}
    # withdrawn: no longer listed
    assert "flagged unsafe" not in _ok("session", "show", "1", "--no-figure", "--db", db)
    info = json.loads(_ok("session", "show", "1", "--json", "--no-figure", "--db", db))
    assert info["unsafe"] == []


def test_show_a_fresh_session_on_the_line_path(tmp_path: Path) -> None:
    """Before its first query a line-path session's posterior has no point: show says so."""
    db = str(tmp_path / "lab.db")
    _ok("session", "new", "--config", "compass-continuous-3d", "--subject", "S01", "--db", db)
    info = json.loads(_ok("session", "show", "1", "--json", "--no-figure", "--db", db))
    assert info["posterior"]["argmax"] is None and info["trials"] == 0
    assert info["posterior"]["learned"] is False
    assert "best so far: none yet" in _ok("session", "show", "1", "--no-figure", "--db", db)
    figure = tmp_path / "fig.png"
    _ok("session", "show", "1", "--figure", str(figure), "--db", db)
    assert figure.stat().st_size > 1_000


def test_show_refuses_a_figure_in_a_folder_that_does_not_exist(
    tmp_path: Path, drive: Drive
) -> None:
    """``--figure`` made its missing folders silently (a mistyped path scattered folders);
    like ``gaits build --out`` it now refuses, naming the option, before the session is read.
    A folder given as the figure is refused too; a folder that exists takes it."""
    db = str(tmp_path / "lab.db")
    drive(Session.create(db, CONFIG, "S01", seed=4), 2)
    missing = tmp_path / "figs" / "sub" / "fig.png"
    out = _fails("session", "show", "1", "--figure", str(missing), "--db", db)
    assert "--figure" in out and "no folder" in out and "fig.png" in out
    assert not (tmp_path / "figs").exists()
    assert "is a folder" in _fails("session", "show", "1", "--figure", str(tmp_path), "--db", db)
    (tmp_path / "figs").mkdir()
    text = _ok("session", "show", "1", "--figure", str(tmp_path / "figs" / "fig"), "--db", db)
    assert (tmp_path / "figs" / "fig.png").is_file() and "figure: " in text
    # --no-figure draws nothing, so the path is not looked at
    _ok("session", "show", "1", "--no-figure", "--figure", str(missing), "--db", db)


def test_validate_with_a_bad_ranking_writes_no_round(tmp_path: Path, drive: Drive) -> None:
    db = str(tmp_path / "lab.db")
    with Session.create(db, CONFIG, "S01", seed=4) as s:
        drive(s, 4)
        before = len(s.events())
    assert "a ranking names each of A, B, C" in _fails(
        "session", "validate", "1", "--ranking", "ZZZ", "--yes", "--db", db
    )
    with Session.open(db, 1) as s:
        assert len(s.events()) == before and s.validation_plan is None


def test_a_negative_simulation_seed_is_refused_by_its_option() -> None:
    out = _fails("simulate", "exo-1d-step-length", "--objective", "x.npy", "--seed", "-1")
    assert "--seed" in out and "greater than or equal to 0" in out


@pytest.mark.parametrize("seed", ["-1", str(2**63)])
def test_session_new_refuses_a_seed_out_of_range_by_its_option(tmp_path: Path, seed: str) -> None:
    """As simulate's: the option is named (it said 'seed must be ...', without '--'), and no
    database is made."""
    db = tmp_path / "lab.db"
    out = _fails("session", "new", "--config", CONFIG, "--subject", "S01", "--seed", seed,
                 "--db", str(db))  # fmt: skip
    assert "Invalid value for '--seed'" in " ".join(out.split())
    assert not db.exists()


def test_a_negative_or_nan_simulated_noise_is_refused() -> None:
    for noise in ("-1", "nan"):
        out = _fails(
            "simulate", "exo-1d-step-length", "--objective", "random-gp", "--trials", "3",
            "--noise", noise,
        )  # fmt: skip
        assert "noise must be a finite number >= 0" in out


def test_undo_names_the_answer_it_undid_when_another_writer_answered_meanwhile(
    tmp_path: Path, drive: Drive, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Before: the trials were read when the command opened the session, so an answer recorded
    by another writer during the confirmation was undone and an earlier trial named."""
    from gaitpref.cli import session as session_cli

    db = str(tmp_path / "lab.db")
    drive(Session.create(db, CONFIG, "S01", seed=4), 5)
    other = Session.open(db, 1)

    def answered_meanwhile(question: str, yes: bool) -> None:
        drive(other, 1)  # trial 6, while the operator reads the question (then: yes)

    monkeypatch.setattr(session_cli, "_confirm", answered_meanwhile)
    assert "undone: the answer to trial 6" in _ok("session", "undo", "1", "--db", db)
    assert [t.number for t in Session.open(db, 1).trials()] == [1, 2, 3, 4, 5]


def test_session_new_refuses_a_blank_config_name(tmp_path: Path) -> None:
    from gaitpref import load_config

    path = tmp_path / "blank.toml"
    path.write_text(load_config(CONFIG).text.replace("exo-1d-step-length", "  "), "utf-8")
    db = str(tmp_path / "lab.db")
    out = _fails("session", "new", "--config", str(path), "--subject", "S01", "--db", db)
    assert "name: must name the config" in out and "got '  '" in out


def test_session_list_marks_its_times_utc(tmp_path: Path) -> None:
    """The times were printed bare ('2026-12-02 14:40'), read as local time at the lab."""
    db = str(tmp_path / "lab.db")
    with Session.create(db, CONFIG, "S01") as s:
        created, updated = s.record.created_at, s.record.updated_at
    out = _ok("session", "list", "--db", db)  # 80 columns: headers and times wrap
    assert out.count("(UTC)") == 2 and "created" in out and "updated" in out
    for when in (created, updated):
        utc = when.astimezone(UTC)
        assert f"{utc:%Y-%m-%d}" in out and f"{utc:%H:%M}" in out


def test_session_list_folds_long_names_instead_of_cutting_them(tmp_path: Path) -> None:
    """On 80 columns exo-2d-length-duration and exo-2d-length-width were both 'exo-2d-le…':
    an operator could not tell which session ran which config."""
    db = str(tmp_path / "lab.db")
    for config in ("exo-2d-length-duration", "exo-2d-length-width"):
        Session.create(db, config, "S01-long-code").close()
    out = CliRunner().invoke(app, ["session", "list", "--db", db], env={"COLUMNS": "80"}).output
    assert "…" not in out
    cells = [line.split("│") for line in out.splitlines() if line.count("│") > 3]
    column = "".join(cell[3].strip() for cell in cells)  # the config's pieces, row after row
    assert "exo-2d-length-duration" in column and "exo-2d-length-width" in column
    assert "S01-long-code" in "".join(cell[2].strip() for cell in cells)
    assert max(len(line) for line in out.splitlines()) <= 80


def test_show_counts_one_trial_and_one_comparison_in_the_singular(tmp_path: Path) -> None:
    """It said "1 trials (0 excluded), 1 comparisons"."""
    db = str(tmp_path / "lab.db")
    with Session.create(f"sqlite:///{db}", CONFIG, "S01", seed=1) as s:
        q = s.next_query()
        s.answer(q.id, [], [(q.actions[0], "step_length", "+big")])  # one trial, no comparison
        text = _ok("session", "show", "1", "--no-figure", "--db", db)
        assert "1 trial (0 excluded), 0 comparisons" in text
        q = s.next_query()  # the new gait against the buffered one: one comparison
        s.answer(q.id, [(q.actions[0], q.buffer[0], "first")])
    text = _ok("session", "show", "1", "--no-figure", "--db", db)
    assert "2 trials (0 excluded), 1 comparison\n" in text
