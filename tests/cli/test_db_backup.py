"""``gaitpref db backup OUT`` and the backup ``gaitpref db upgrade`` makes before migrating."""

from __future__ import annotations

import shutil
import sqlite3
from pathlib import Path

from typer.testing import CliRunner

from gaitpref import Session, load_config
from gaitpref.cli import app
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.storage import migrate

CONFIG = "exo-1d-step-length"
FIXTURES = Path(__file__).resolve().parent.parent / "fixtures"
#: the header fields SQLite's backup API sets in the copy: the file change counter, the schema
#: cookie and the version-valid-for number (offsets 24, 40 and 92, four bytes each)
BUMPED = (range(24, 28), range(40, 44), range(92, 96))


def _lab(tmp_path: Path) -> Path:
    path = tmp_path / "lab.db"
    space = load_config(CONFIG).space
    subject = SimulatedSubject(space, bump_utility(space), seed=1)
    for code in ("S01", "S02"):
        with Session.create(f"sqlite:///{path}", CONFIG, code, seed=4) as s:
            for _ in range(2):
                q = s.next_query()
                s.answer(q.id, *subject.respond(q))
    return path


def _dump(path: Path) -> list[str]:
    conn = sqlite3.connect(path)
    try:
        return list(conn.iterdump())
    finally:
        conn.close()


def _same_but_header_counters(a: bytes, b: bytes) -> bool:
    def masked(data: bytes) -> bytes:
        out = bytearray(data)
        for r in BUMPED:
            out[r.start : r.stop] = bytes(len(r))
        return bytes(out)

    return masked(a) == masked(b)


def test_backup_is_verified_and_the_copy_replays(tmp_path: Path) -> None:
    lab = _lab(tmp_path)
    out = tmp_path / "copy.db"
    result = CliRunner().invoke(app, ["db", "backup", str(out), "--db", str(lab)])
    assert result.exit_code == 0, result.output
    events = sum(s.last_seq for s in Session.list_sessions(str(lab)))
    assert f"backed up to {out}: schema revision {migrate.head_revision()}, 2 sessions" in (
        result.stdout
    )
    assert f"{events} events (verified)" in result.stdout
    assert _dump(out) == _dump(lab)
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []
    check = CliRunner().invoke(app, ["db", "check", "--db", str(out)])
    assert check.exit_code == 0, check.output
    assert "all 2 sessions replay" in check.stdout


def test_an_existing_out_is_refused_and_left_alone(tmp_path: Path) -> None:
    lab = _lab(tmp_path)
    out = tmp_path / "taken.db"
    out.write_bytes(b"keep me")
    result = CliRunner().invoke(app, ["db", "backup", str(out), "--db", str(lab)])
    assert result.exit_code == 2
    assert f"'{out}' exists" in result.stderr
    assert out.read_bytes() == b"keep me"


def test_postgresql_is_refused_with_the_pg_dump_command(tmp_path: Path) -> None:
    url = "postgresql+psycopg://lab:s3cret@db.example:5433/gaitlab"
    out = tmp_path / "lab.dump"
    result = CliRunner().invoke(app, ["db", "backup", str(out), "--db", url])
    assert result.exit_code == 2
    err = " ".join(result.stderr.split())
    assert "pg_dump --format=custom" in err and "gaitlab" in err
    assert "--host=db.example --port=5433 --username=lab" in err
    assert "s3cret" not in err and "***" in err
    assert not out.exists()


def test_the_pg_dump_command_of_a_socket_url_names_its_socket_and_port(tmp_path: Path) -> None:
    """The host and port of a URL through a Unix socket are its parameters: the command left
    them out, so that it dumped the database of the default socket's server, or none."""
    url = "postgresql+psycopg://lab:s3cret@/gaitlab?host=/run/lab%20pg&port=5433"
    result = CliRunner().invoke(app, ["db", "backup", str(tmp_path / "lab.dump"), "--db", url])
    assert result.exit_code == 2
    err = " ".join(result.stderr.split())
    assert "--host='/run/lab pg' --port=5433 --username=lab gaitlab`" in err, err
    assert "s3cret" not in err


def test_upgrade_of_an_old_database_backs_it_up_first(tmp_path: Path) -> None:
    old = tmp_path / "old.db"
    shutil.copy(FIXTURES / "gaitpref-0.1.0.db", old)
    original = old.read_bytes()
    before = _dump(old)
    result = CliRunner().invoke(app, ["db", "upgrade", "--db", str(old)])
    assert result.exit_code == 0, result.output
    saved = tmp_path / f"old.db.before-{migrate.head_revision()}.bak"
    assert f"backed up to {saved} before migrating" in result.stdout
    # the pages as they were, but for the three counters SQLite's backup sets in a copy's header
    assert _same_but_header_counters(saved.read_bytes(), original)
    assert _dump(saved) == before
    again = CliRunner().invoke(app, ["db", "upgrade", "--db", str(old)])  # at the newest: none
    assert again.exit_code == 0 and "backed up" not in again.stdout
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.endswith(".bak")) == [saved.name]


def test_no_backup_and_a_new_database_make_none(tmp_path: Path) -> None:
    old = tmp_path / "old.db"
    shutil.copy(FIXTURES / "gaitpref-0.1.0.db", old)
    result = CliRunner().invoke(app, ["db", "upgrade", "--no-backup", "--db", str(old)])
    assert result.exit_code == 0 and "backed up" not in result.stdout
    fresh = CliRunner().invoke(app, ["db", "upgrade", "--db", str(tmp_path / "new.db")])
    assert fresh.exit_code == 0 and "backed up" not in fresh.stdout
    assert [p for p in tmp_path.iterdir() if p.name.endswith(".bak")] == []


def test_a_backup_while_a_session_is_written_is_one_consistent_state(tmp_path: Path) -> None:
    import threading

    from gaitpref.storage.sql import backup_database

    lab = _lab(tmp_path)
    url = f"sqlite:///{lab}"
    stop = threading.Event()

    def write() -> None:
        with Session.open(url, 1) as s:
            while not stop.is_set():
                s.note("the console writes")

    writer = threading.Thread(target=write)
    writer.start()
    try:
        copies = [backup_database(url, tmp_path / f"copy{k}.db") for k in range(5)]
    finally:
        stop.set()
        writer.join()
    for saved in copies:
        with sqlite3.connect(saved.path) as raw:
            rows = raw.execute("SELECT count(*) FROM events").fetchone()[0]
            seqs = raw.execute("SELECT sum(last_seq) FROM sessions").fetchone()[0]
        raw.close()
        assert rows == seqs == saved.events  # the events and the sessions' counters agree


def test_one_session_and_one_event_are_counted_in_the_singular(tmp_path: Path) -> None:
    """It said "1 sessions, 1 events" (a new session's log holds one event)."""
    lab = tmp_path / "lab.db"
    Session.create(f"sqlite:///{lab}", CONFIG, "S01", seed=4).close()
    out = tmp_path / "copy.db"
    result = CliRunner().invoke(app, ["db", "backup", str(out), "--db", str(lab)])
    assert result.exit_code == 0, result.output
    assert "1 session, 1 event (verified)" in result.stdout
    check = CliRunner().invoke(app, ["db", "check", "--db", str(lab)])
    assert check.exit_code == 0, check.output
    assert "session 1: subject S01, exo-1d-step-length, 1 event, active: OK" in check.stdout


def test_the_pg_dump_command_never_shows_the_client_keys_password(tmp_path: Path) -> None:
    """The URL's libpq parameters travel in the command's conninfo, but ``sslpassword`` (the
    client key's password) is a secret as the password is: the command showed it.  (The URL
    named before the command still shows it: its masking hides the password alone.)"""
    url = (
        "postgresql+psycopg://lab@db.example/gaitlab?sslmode=verify-full&sslkey=/k/c.key"
        "&sslpassword=k3ypass"
    )
    result = CliRunner().invoke(app, ["db", "backup", str(tmp_path / "lab.dump"), "--db", url])
    assert result.exit_code == 2
    err = " ".join(result.stderr.split())
    command = err.split("e.g. `", 1)[1].split("`", 1)[0]
    assert command.startswith("pg_dump --format=custom") and "sslmode=verify-full" in command
    assert "sslkey=/k/c.key" in command
    assert "k3ypass" not in command and "sslpassword" not in command, command
