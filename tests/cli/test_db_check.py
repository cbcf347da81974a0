"""``gaitpref db check``: every stored session replayed with this gaitpref, nothing written."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import pytest
from typer.testing import CliRunner

from gaitpref import Session, load_config
from gaitpref.cli import app
from gaitpref.sessions.demo import SimulatedSubject, bump_utility

CONFIG = "exo-1d-step-length"


def _drive(session: Session, n: int) -> None:
    space = load_config(CONFIG).space
    subject = SimulatedSubject(space, bump_utility(space), seed=1)
    for _ in range(n):
        q = session.next_query()
        comparisons, suggestions = subject.respond(q)
        session.answer(q.id, comparisons, suggestions)


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


@pytest.fixture
def three(tmp_path: Path) -> Path:
    """Sessions 1 and 2 replay; session 3's stored config text was edited, so it does not."""
    path = tmp_path / "lab.db"
    for subject, seed in (("S01", 1), ("S02", 2), ("S03", 3)):
        with Session.create(f"sqlite:///{path}", CONFIG, subject, seed=seed) as s:
            _drive(s, 2)
    with sqlite3.connect(path) as raw:
        raw.execute("UPDATE sessions SET config_text = config_text || '# edited' WHERE id = 3")
    raw.close()
    return path


def test_a_failing_session_is_named_and_the_others_still_checked(three: Path) -> None:
    before = _files(three.parent)
    names = sorted(p.name for p in three.parent.iterdir())  # lab.db.turns/ made by the answers
    result = CliRunner().invoke(app, ["db", "check", "--db", str(three)])
    assert result.exit_code == 1, result.output
    out = result.stdout
    assert "session 1: subject S01, exo-1d-step-length," in out
    assert out.count(": OK") == 2
    assert "session 3: subject S03" in out and "FAILED (ReplayError)" in out
    assert "does not match its hash" in out
    assert "1 of 3 sessions do not replay" in result.stderr
    assert _files(three.parent) == before  # the file's bytes, and nothing made beside it
    assert sorted(p.name for p in three.parent.iterdir()) == names


def test_json_gives_one_object_per_session(three: Path) -> None:
    result = CliRunner().invoke(app, ["db", "check", "--json", "--db", str(three)])
    assert result.exit_code == 1
    rows = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["id"] for r in rows] == [1, 2, 3]
    assert [r["ok"] for r in rows] == [True, True, False]
    assert set(rows[0]) == {
        "id", "subject", "config", "events", "status", "ok", "error", "error_type"
    }  # fmt: skip
    assert rows[0]["subject"] == "S01" and rows[0]["status"] == "active"
    assert rows[0]["events"] > 1 and rows[0]["error"] is None
    assert rows[2]["error_type"] == "ReplayError" and "hash" in rows[2]["error"]


def test_all_replay_exits_0(tmp_path: Path) -> None:
    good = tmp_path / "good.db"
    with Session.create(f"sqlite:///{good}", CONFIG, "S01", seed=1) as s:
        _drive(s, 1)
    result = CliRunner().invoke(app, ["db", "check", "--db", str(good)])
    assert result.exit_code == 0, result.output
    assert "session 1: subject S01" in result.stdout and "the one session replays" in result.stdout


def test_a_missing_database_is_refused_and_not_made(tmp_path: Path) -> None:
    result = CliRunner().invoke(app, ["db", "check", "--db", str(tmp_path / "none.db")])
    assert result.exit_code == 2
    assert "no gaitpref database" in result.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("kind", ["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)])
def test_on_each_backend(request: pytest.FixtureRequest, tmp_path: Path, kind: str) -> None:
    if kind == "sqlite":
        url = f"sqlite:///{tmp_path / 'lab.db'}"
    else:
        url = str(request.getfixturevalue("postgres_url"))
    for subject in ("S01", "S02"):
        with Session.create(url, CONFIG, subject, seed=1) as s:
            _drive(s, 1)
    from sqlalchemy import create_engine, text

    engine = create_engine(url)
    with engine.begin() as conn:  # a stored config edited outside gaitpref: replay refuses it
        conn.execute(text("UPDATE sessions SET config_text = config_text || '#' WHERE id = 2"))
        events = conn.execute(text("SELECT count(*) FROM events")).scalar()
    result = CliRunner().invoke(app, ["db", "check", "--json", "--db", url])
    with engine.connect() as conn:
        assert conn.execute(text("SELECT count(*) FROM events")).scalar() == events
    engine.dispose()
    assert result.exit_code == 1, result.output
    rows = [json.loads(line) for line in result.stdout.splitlines()]
    assert [(r["id"], r["ok"]) for r in rows] == [(1, True), (2, False)]
    assert "2 sessions" in result.stderr and "1 of" in result.stderr


def test_its_progress_bar_leaves_no_blank_line_off_a_terminal(tmp_path: Path) -> None:
    """A transient bar cannot vanish from a file or a pipe: it left an empty line on stderr
    before the error (and after the sessions), in logs and scripts."""
    result = CliRunner().invoke(app, ["db", "check", "--db", str(tmp_path / "missing.db")])
    assert result.exit_code == 2
    assert result.stderr.startswith("storage error: no gaitpref database at")
    path = tmp_path / "lab.db"
    with Session.create(f"sqlite:///{path}", CONFIG, "S01", seed=1) as s:
        _drive(s, 1)
    result = CliRunner().invoke(app, ["db", "check", "--db", str(path)])
    assert result.exit_code == 0, result.output
    assert "\n\n" not in "\n" + result.stderr
