"""``gaitpref db status`` tells a missing database from one whose upgrade was interrupted."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

from gaitpref.storage import SessionSpec
from gaitpref.storage.sql import SQLStorage, database_status, upgrade_database

KILLED_UPGRADE = textwrap.dedent(
    """
    import os, sys
    from gaitpref.storage import migrate
    from gaitpref.storage.sql import upgrade_database
    real = migrate.upgrade
    def killed(connection, revision="head"):
        real(connection, revision)  # the tables are made, the transaction is not committed
        os._exit(9)
    migrate.upgrade = killed
    upgrade_database(sys.argv[1])
    """
)


def test_an_interrupted_upgrade_is_named_as_such(tmp_path: Path) -> None:
    path = tmp_path / "lab.db"
    url = f"sqlite:///{path}"
    done = subprocess.run([sys.executable, "-c", KILLED_UPGRADE, url], capture_output=True)
    assert done.returncode == 9, done.stderr.decode()[-2000:]
    assert path.exists()
    line = database_status(url)
    assert "does not exist" not in line
    assert "interrupted" in line and "gaitpref db upgrade" in line
    upgrade_database(url)  # the advice works
    assert "0 sessions" in database_status(url)


def test_an_empty_file_and_a_missing_one(tmp_path: Path) -> None:
    (tmp_path / "empty.db").touch()
    assert "interrupted" in database_status(f"sqlite:///{tmp_path / 'empty.db'}")
    missing = database_status(f"sqlite:///{tmp_path / 'none.db'}")
    assert "does not exist" in missing and not (tmp_path / "none.db").exists()


def test_a_database_from_a_newer_gaitpref(tmp_path: Path) -> None:
    import sqlite3

    url = f"sqlite:///{tmp_path / 'new.db'}"
    upgrade_database(url)
    with sqlite3.connect(tmp_path / "new.db") as raw:
        raw.execute("UPDATE alembic_version SET version_num = 'ffff_future'")
    assert "newer gaitpref" in database_status(url)


def test_the_db_status_command_says_so(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from gaitpref.cli import app

    (tmp_path / "lab.db").touch()
    result = CliRunner().invoke(app, ["db", "status", "--db", f"sqlite:///{tmp_path / 'lab.db'}"])
    assert result.exit_code == 0, result.output
    assert "interrupted" in result.output and "does not exist" not in result.output


def _db_status(url: str, *command: str) -> tuple[int, str]:
    from typer.testing import CliRunner

    from gaitpref.cli import app

    result = CliRunner().invoke(app, [*(command or ("db", "status")), "--db", url])
    return result.exit_code, " ".join(result.output.split())


def test_an_unknown_driver_is_refused_as_by_every_command(tmp_path: Path) -> None:
    """With the file there and leftover -wal/-journal files, the check for tables made an engine
    of the unknown driver itself: a NoSuchModuleError traceback.  Without them the line was a
    status (exit 0) naming the URL twice."""
    upgrade_database(f"sqlite:///{tmp_path / 'x.db'}")
    url = f"sqlite+unknowndriver:///{tmp_path / 'x.db'}"
    code, out = _db_status(url)
    same = "its driver 'sqlite+unknowndriver' cannot be loaded"
    assert code == 2 and out.startswith(f"storage error: cannot open {url}: {same}"), out
    for suffix in ("-wal", "-journal"):
        (tmp_path / f"x.db{suffix}").touch()
    assert _db_status(url) == (code, out)
    assert _db_status(url, "session", "list") == (code, out)  # the same error


def test_a_file_that_is_not_a_database_with_leftovers_is_named(tmp_path: Path) -> None:
    """The check for tables raised 'file is not a database' as a traceback."""
    (tmp_path / "x.db").write_text("not a database, a page of text " * 40)
    (tmp_path / "x.db-journal").touch()
    code, out = _db_status(f"sqlite:///{tmp_path / 'x.db'}")
    assert code == 0 and "x.db: file is not a database (the file is not a SQLite" in out, out
    assert out.endswith(
        "restore it from a backup (gaitpref db backup makes them) and keep this file as it is)"
    ), out


def test_a_damaged_database_says_to_restore_it_from_a_backup(tmp_path: Path) -> None:
    """A file cut short (a copy interrupted, a disk fault) read as 'database disk image is
    malformed' and a text file as 'file is not a database', and nothing more: each now says what
    to do, for every command, and the file is left as it was."""
    db = tmp_path / "lab.db"
    upgrade_database(f"sqlite:///{db}")
    storage = SQLStorage(f"sqlite:///{db}")
    for k in range(40):  # enough pages that cutting the file leaves their index pointing past it
        storage.create_session(SessionSpec(f"S{k:02d}", "c", "x" * 2000, "0" * 64, 0, "t"), [])
    storage.close()
    size = db.stat().st_size
    with open(db, "r+b") as f:
        f.truncate(size // 2)
    cut = db.read_bytes()
    for args in (("session", "list"), ("session", "show", "1", "--no-figure"), ("db", "check")):
        code, out = _db_status(f"sqlite:///{db}", *args)
        assert code == 2, (args, out)
        assert "database disk image is malformed (the file is damaged: restore it from a " in out
        assert "backup (gaitpref db backup makes them) and keep this file as it is)" in out
    assert db.read_bytes() == cut
