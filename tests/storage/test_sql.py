"""SQL backend specifics: SQLite durability settings, schema versions, connection errors."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext
from sqlalchemy import create_engine, make_url, text

from gaitpref.storage import (
    NewEvent,
    SchemaError,
    SessionNotFoundError,
    SessionSpec,
    SQLStorage,
    StorageConnectError,
    StorageError,
    open_storage,
    resolve_url,
)
from gaitpref.storage.base import check_subject
from gaitpref.storage.migrate import head_revision, known_revisions
from gaitpref.storage.schema import metadata
from gaitpref.storage.sql import upgrade_database

SPEC = SessionSpec("S01", "c", "text", "0" * 64, 0, "0.1.0")


def _sqlite(tmp_path: Path) -> str:
    return f"sqlite:///{tmp_path / 'g.db'}"


def test_sqlite_runs_in_wal_with_full_sync(tmp_path: Path) -> None:
    store = SQLStorage(_sqlite(tmp_path))
    with store.engine.connect() as conn:
        assert conn.exec_driver_sql("PRAGMA journal_mode").scalar() == "wal"
        assert conn.exec_driver_sql("PRAGMA synchronous").scalar() == 2  # FULL
        assert conn.exec_driver_sql("PRAGMA foreign_keys").scalar() == 1
        assert (conn.exec_driver_sql("PRAGMA busy_timeout").scalar() or 0) >= 1000
    store.close()


def test_committed_on_return_is_visible_to_an_independent_reader(tmp_path: Path) -> None:
    store = SQLStorage(_sqlite(tmp_path))
    sid = store.create_session(SPEC).id
    store.append(sid, 0, [NewEvent("note", {"text": "hi"})])
    with sqlite3.connect(tmp_path / "g.db") as raw:  # not through gaitpref or its pool
        assert raw.execute("SELECT kind FROM events").fetchall() == [("note",)]
    store.close()


def _url_of(request: pytest.FixtureRequest, tmp_path: Path, kind: str) -> str:
    return _sqlite(tmp_path) if kind == "sqlite" else str(request.getfixturevalue("postgres_url"))


KINDS = ["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)]


@pytest.mark.parametrize("kind", KINDS)
def test_migrations_build_exactly_the_schema(
    request: pytest.FixtureRequest, tmp_path: Path, kind: str
) -> None:
    url = _url_of(request, tmp_path, kind)
    SQLStorage(url).close()
    engine = create_engine(url)
    with engine.connect() as conn:
        diff = compare_metadata(MigrationContext.configure(conn), metadata)
        assert diff == []
        assert conn.execute(text("SELECT version_num FROM alembic_version")).scalar() == (
            head_revision()
        )
    engine.dispose()
    assert known_revisions()[-1] == head_revision()


@pytest.mark.parametrize("kind", KINDS)
def test_events_cannot_be_edited_or_deleted_even_by_hand(
    request: pytest.FixtureRequest, tmp_path: Path, kind: str
) -> None:
    url = _url_of(request, tmp_path, kind)
    store = SQLStorage(url)
    sid = store.create_session(SPEC, [NewEvent("a", {"v": 1})]).id
    for statement in ("UPDATE events SET kind = 'b'", "DELETE FROM events"):
        with pytest.raises(Exception, match="append-only"), store.engine.begin() as conn:
            conn.execute(text(statement))
    assert [e.kind for e in store.events(sid)] == ["a"]
    store.close()


@pytest.mark.parametrize("kind", KINDS)
def test_a_newer_schema_is_refused_and_left_alone(
    request: pytest.FixtureRequest, tmp_path: Path, kind: str
) -> None:
    url = _url_of(request, tmp_path, kind)
    store = SQLStorage(url)
    store.create_session(SPEC)
    with store.engine.begin() as conn:
        conn.execute(text("UPDATE alembic_version SET version_num = '9999_future'"))
    store.close()
    with pytest.raises(SchemaError, match="newer gaitpref"):
        SQLStorage(url)
    engine = create_engine(url)
    with engine.connect() as conn:
        assert conn.execute(text("SELECT version_num FROM alembic_version")).scalar() == (
            "9999_future"
        )
        assert conn.execute(text("SELECT count(*) FROM sessions")).scalar() == 1
    engine.dispose()


def test_a_newer_gaitpref_database_keeps_its_journal_and_bytes(tmp_path: Path) -> None:
    """A newer gaitpref may run its files in another journal mode; every command refuses the
    file without writing a byte (before, opening it switched it to WAL)."""
    from gaitpref.storage.sql import database_status, upgrade_database

    path = tmp_path / "g.db"
    with SQLStorage(_sqlite(tmp_path)) as store:
        store.create_session(SPEC)
    raw = sqlite3.connect(path, isolation_level=None)  # as a newer gaitpref might leave it
    raw.execute("UPDATE alembic_version SET version_num = '9999_future'")
    assert raw.execute("PRAGMA journal_mode = DELETE").fetchone()[0] == "delete"
    raw.close()
    before = path.read_bytes()
    for call in (
        lambda: SQLStorage(_sqlite(tmp_path), create=False),
        lambda: SQLStorage(_sqlite(tmp_path)),
        lambda: upgrade_database(_sqlite(tmp_path)),
    ):
        with pytest.raises(SchemaError, match="newer gaitpref"):
            call()
    assert "newer gaitpref" in database_status(_sqlite(tmp_path))
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["g.db"]


def test_a_foreign_database_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "other.db"
    with sqlite3.connect(path) as raw:
        raw.execute("CREATE TABLE patients (name TEXT)")
    with pytest.raises(SchemaError, match="not a gaitpref database"):
        SQLStorage(f"sqlite:///{path}")
    with sqlite3.connect(path) as raw:
        tables = {r[0] for r in raw.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    assert tables == {"patients"}
    with sqlite3.connect(path) as raw:  # nor its journal: it was not switched to WAL
        assert raw.execute("PRAGMA journal_mode").fetchone()[0] == "delete"
    assert path.read_bytes()[18:20] == b"\x01\x01"  # the header's legacy journal bytes


def test_a_session_id_past_sql_integers_is_no_such_session(tmp_path: Path) -> None:
    storage = SQLStorage(_sqlite(tmp_path))
    for sid in (2**63, 10**30, -(2**70)):
        with pytest.raises(SessionNotFoundError, match=f"no session {sid}"):
            storage.get_session(sid)


@pytest.mark.parametrize(
    "url, message",
    [
        ("sqlite:////nonexistent-folder/g.db", "does not exist"),
        ("postgresql+psycopg://nobody@127.0.0.1:1/none", "cannot connect"),
        ("mysql://x@localhost/db", "SQLite or PostgreSQL"),
        ("not a url ://", "not a database URL"),
        ("postgresql://u@localhost:notaport/db", "not a database URL: invalid literal"),
        ("postgresql+nosuchdriver://u@localhost/db", "driver 'postgresql\\+nosuchdriver' cannot"),
        ("sqlite+nosuchdriver:///g.db", "driver 'sqlite\\+nosuchdriver' cannot be loaded"),
    ],
)
def test_urls_that_do_not_connect_give_clear_errors(url: str, message: str) -> None:
    with pytest.raises(StorageConnectError, match=message):
        open_storage(url)
    with pytest.raises(StorageConnectError, match=message.replace("connect", "open")):
        upgrade_database(url)  # 'cannot open' for a server that does not answer


def test_a_folder_is_not_a_database_file(tmp_path: Path) -> None:
    for call in (open_storage, upgrade_database):
        with pytest.raises(StorageConnectError, match="is a folder, not a database file"):
            call(f"sqlite:///{tmp_path}")
    assert list(tmp_path.iterdir()) == []


def test_a_database_in_a_read_only_folder_is_named_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """SQLite cannot make the -wal and -shm files there ('unable to open database file'); a
    read-only mount is needed to see it happen, so the folder's check is what is tested here."""
    import gaitpref.storage.sql as sql

    SQLStorage(_sqlite(tmp_path)).close()
    refused = sqlite3.OperationalError("unable to open database file")
    monkeypatch.setattr("gaitpref.storage.sql.os.access", lambda path, mode: False)
    assert "is read-only" in sql._hint(tmp_path / "g.db", refused)
    assert "-wal" in sql._hint(tmp_path / "g.db", refused)
    # a new database cannot be made there either: said so, not a bare "unable to open"
    made = sql._hint(tmp_path / "missing.db", refused)
    assert "is read-only: a new database cannot be made in it" in made
    assert "-wal" not in made
    assert sql._hint(tmp_path / "nodir" / "g.db", refused) == ""  # said by its own check
    assert sql._hint(tmp_path / "g.db", sqlite3.OperationalError("disk I/O error")) == ""


def test_read_only_open_does_not_create_a_database(tmp_path: Path) -> None:
    with pytest.raises(StorageConnectError, match="no gaitpref database"):
        open_storage(_sqlite(tmp_path), create=False)
    assert not (tmp_path / "g.db").exists()


def test_a_reader_leaves_an_empty_file_empty(tmp_path: Path) -> None:
    """An empty file (a creation cut short, a truncated copy) is refused by a reader (session
    list, show, db check) and left as it was: setting WAL on it wrote a 4,096-byte first page,
    though db check says it leaves the file's bytes as they were.  A writer makes it a
    database."""
    (tmp_path / "g.db").write_bytes(b"")
    with pytest.raises(SchemaError, match="holds no gaitpref database"):
        open_storage(_sqlite(tmp_path), create=False)
    assert (tmp_path / "g.db").read_bytes() == b""
    assert not (tmp_path / "g.db-wal").exists()
    store = open_storage(_sqlite(tmp_path))
    sid = store.create_session(SPEC).id
    store.close()
    reader = open_storage(_sqlite(tmp_path), create=False)
    assert [r.id for r in reader.list_sessions()] == [sid]
    reader.close()


def test_sqlite_url_parameters_are_refused_by_name_not_ignored(tmp_path: Path) -> None:
    """``sqlite:///g.db?mode=ro`` opened the file read-write: the driver ignored ``mode``."""
    SQLStorage(_sqlite(tmp_path)).close()
    before = (tmp_path / "g.db").read_bytes()
    for call in (open_storage, upgrade_database):
        with pytest.raises(StorageConnectError, match=r"SQLite URL parameters \(mode\)"):
            call(_sqlite(tmp_path) + "?mode=ro")
    assert (tmp_path / "g.db").read_bytes() == before
    with pytest.raises(StorageConnectError, match=r"parameters \(cache, uri\)"):
        open_storage(f"sqlite:///file:{tmp_path / 'g.db'}?uri=true&cache=shared")
    open_storage(resolve_url(str(tmp_path / "a?b.db"))).close()  # a '?' in a name is quoted
    assert (tmp_path / "a?b.db").is_file()


def test_url_resolution(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("GAITPREF_DB", raising=False)
    assert resolve_url() == "sqlite:///gaitpref.db"
    monkeypatch.setenv("GAITPREF_DB", "sqlite:////tmp/x.db")
    assert resolve_url() == "sqlite:////tmp/x.db"
    assert resolve_url("lab.db") == "sqlite:///lab.db"
    assert resolve_url("postgresql+psycopg://u@h/d") == "postgresql+psycopg://u@h/d"


def test_storage_errors_are_runtime_errors_with_the_url(tmp_path: Path) -> None:
    store = SQLStorage(_sqlite(tmp_path))
    assert "g.db" in store.url
    with pytest.raises(StorageError):
        store.append(1, 0, [NewEvent("a")])
    store.close()


@pytest.mark.postgres
def test_postgres_password_is_masked(postgres_server: str) -> None:
    with pytest.raises(StorageConnectError) as err:
        open_storage(postgres_server.replace("gaitpref@", "gaitpref:secret@") + "/missing_db")
    assert "secret" not in str(err.value) and "***" in str(err.value)


@pytest.mark.parametrize(
    "url",
    [
        "postgresql://lab:pw1@h/db?sslmode=require&sslpassword=k3ypass",
        "postgresql://lab@h/db?sslpassword=k3ypass",
        "postgresql://lab@h/db?password=pw1&sslpassword=k3ypass",
        "postgresql://lab@h/db?SSLPassword=k3ypass",  # libpq refuses it, and said so with the URL
        "postgresql://lab@h/db?oauth_client_secret=k3ypass",  # libpq 18
        "postgresql://lab@h/db?sslpassword=k3ypass&sslpassword=again",
        "postgresql://lab:pw1@h:notaport/db?sslpassword=k3ypass",  # not parsed
    ],
)
def test_every_secret_parameter_is_masked(url: str) -> None:
    """The client key's password (``sslpassword``) was shown wherever a URL is printed; the
    one helper masks every secret libpq takes, for every caller."""
    from gaitpref.storage.sql import masked_url

    shown = masked_url(url)
    assert "k3ypass" not in shown and "again" not in shown and "pw1" not in shown, shown
    assert "=***" in shown and "lab" in shown
    if "notaport" not in url:
        with pytest.raises(StorageConnectError) as err:  # the driver is not installed: named
            SQLStorage(url.replace("postgresql:", "postgresql+nodriver:"))
        assert "k3ypass" not in str(err.value) and "pw1" not in str(err.value), err.value
    assert masked_url("postgresql://lab@h/db?sslmode=require") == (
        "postgresql://lab@h/db?sslmode=require"
    )


@pytest.mark.parametrize("password", ["Zq/Xw", "Zq?Xw", "Zq#Xw", "Zq@Xw", "Zq:Xw", "Zq=Xw"])
@pytest.mark.parametrize("port", ["5432", "notaport"])
def test_a_password_typed_unencoded_is_masked_whole(password: str, port: str) -> None:
    """A URL that does not parse (a port that is not a number) was printed whole when its
    password held a '/'; one with an '@' in it parsed as a host "ss@h", printed with half the
    password, by the URL and by the driver's "failed to resolve host" (now refused before);
    password "Zq@Xw" leaked "Xw"."""
    from gaitpref.storage.sql import masked_url

    url = f"postgresql://lab:{password}@nohost.invalid:{port}/db?sslmode=require"
    shown = masked_url(url)
    assert "Zq" not in shown and "Xw" not in shown, shown
    assert shown.startswith("postgresql://lab:***@nohost.invalid:"), shown
    assert shown.endswith("/db?sslmode=require"), shown
    with pytest.raises(StorageError) as err:  # refused, or the host does not resolve
        SQLStorage(url)
    text = str(err.value)
    assert "Zq" not in text and "Xw" not in text, text


@pytest.mark.postgres
@pytest.mark.parametrize("where", ["missing_db", "port", "host"])
def test_postgres_connection_errors_show_no_secret(postgres_server: str, where: str) -> None:
    """The real server's and psycopg's messages, for a database that does not exist, a port
    nothing listens on and a host that does not resolve: no password, no client key's password."""
    url = postgres_server.replace("gaitpref@", "gaitpref:pw1@") + "/gaitpref"
    if where == "missing_db":
        url = url.rsplit("/", 1)[0] + "/missing_db"
    elif where == "port":
        url = url.replace(f":{make_url(url).port}/", ":1/")
    else:
        url = url.replace(f"@{make_url(url).host}", "@no-such-host.invalid")
    url += "?sslpassword=k3ypass&connect_timeout=5"
    with pytest.raises(StorageError) as err:
        open_storage(url)
    text = str(err.value)
    assert "pw1" not in text and "k3ypass" not in text and "sslpassword=***" in text, text


@pytest.mark.parametrize(
    ("stored", "problem"), [("{not json", "is not JSON"), ("[1, 2]", "a JSON list, not an object")]
)
def test_a_damaged_payload_names_the_session_and_the_event(
    tmp_path: Path, stored: str, problem: str
) -> None:
    url = f"sqlite:///{tmp_path / 'd.db'}"
    store = SQLStorage(url)
    sid = store.create_session(SPEC, [NewEvent("session_created", {})]).id
    store.append(sid, 1, [NewEvent("note", {"text": "a"}), NewEvent("note", {"text": "b"})])
    store.close()
    with sqlite3.connect(tmp_path / "d.db") as raw:  # damage done outside gaitpref
        triggers = raw.execute("SELECT name FROM sqlite_master WHERE type = 'trigger'").fetchall()
        for (name,) in triggers:
            raw.execute(f'DROP TRIGGER "{name}"')
        raw.execute("UPDATE events SET payload = ? WHERE seq = 3", (stored,))
    store = SQLStorage(url)
    with pytest.raises(StorageError, match=f"session {sid}, event 3 \\(note\\)") as info:
        store.events(sid)
    assert problem in str(info.value)
    assert [e.payload for e in store.events(sid, after=3)] == []
    store.close()


@pytest.mark.parametrize("how", ["deleted", "moved", "replaced"])
def test_a_write_to_a_file_deleted_while_open_is_refused(tmp_path: Path, how: str) -> None:
    """The pool's open connection would commit into the unlinked file (and report success)."""
    store = SQLStorage(_sqlite(tmp_path))
    sid = store.create_session(SPEC).id
    store.append(sid, 0, [NewEvent("note", {"text": "kept"})])
    path = tmp_path / "g.db"
    if how == "deleted":
        path.unlink()
    elif how == "moved":
        path.rename(tmp_path / "elsewhere.db")
    else:  # a copy restored over it by a rename, as a backup tool does
        (tmp_path / "copy.db").write_bytes(path.read_bytes())
        (tmp_path / "copy.db").replace(path)
    with pytest.raises(StorageError, match="was deleted, moved or replaced since it was opened"):
        store.append(sid, 1, [NewEvent("note", {"text": "lost before"})])
    with pytest.raises(StorageError, match="was deleted, moved or replaced"):
        store.create_session(SPEC)
    with pytest.raises(StorageError, match="was deleted, moved or replaced"):
        store.events(sid)  # a pooled connection would read the old file, a new one the new
    store.close()


def test_a_database_another_program_is_writing_opens_to_read(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Opening checks the schema in a read transaction: `session list`, `show` and `export` do
    not wait behind (and time out on) another program's write lock, as WAL lets them read."""
    import gaitpref.storage.sql as sql

    store = SQLStorage(_sqlite(tmp_path))
    sid = store.create_session(SPEC).id
    store.close()
    monkeypatch.setattr(sql, "BUSY_TIMEOUT_S", 0.2)  # a failure here is quick, not 30 s
    with sqlite3.connect(tmp_path / "g.db", isolation_level=None) as other:
        other.execute("BEGIN IMMEDIATE")  # another program's write, not yet committed
        other.execute("INSERT INTO subjects VALUES ('S99', '2026-01-01 00:00:00')")
        reader = SQLStorage(_sqlite(tmp_path), create=False)
        assert [r.id for r in reader.list_sessions()] == [sid]
        with pytest.raises(StorageError, match=r"database is locked; nothing was written$"):
            reader.append(sid, 0, [NewEvent("note", {"text": "waits its turn"})])
        other.execute("ROLLBACK")
    reader.append(sid, 0, [NewEvent("note", {"text": "after"})])
    reader.close()


@pytest.mark.parametrize(
    ("change", "problem"),
    [
        ("meta = '[1]'", "session 1 in .*: the stored meta is a JSON list, not an object"),
        ("meta = '{bad'", "a stored value cannot be read"),
        ("seed = 'abc'", "session 1 in .*: the stored seed 'abc' is not an integer"),
        ("status = 'zzz'", "session 1 in .*: the stored status 'zzz' is none of active"),
        ("created_at = 'yesterday'", "a stored value cannot be read .*'yesterday'"),
    ],
)
def test_a_damaged_session_row_is_named(tmp_path: Path, change: str, problem: str) -> None:
    """Before: an AttributeError traceback (meta), or a bare int()/isoformat message."""
    url = _sqlite(tmp_path)
    SQLStorage(url).create_session(SPEC)
    with sqlite3.connect(tmp_path / "g.db") as raw:  # damage done outside gaitpref
        raw.execute("PRAGMA ignore_check_constraints = ON")
        raw.execute(f"UPDATE sessions SET {change}")
    store = SQLStorage(url)
    for read in (store.list_sessions, lambda: store.get_session(1)):
        with pytest.raises(StorageError, match=problem) as info:
            read()
        assert "altered or damaged outside gaitpref" in str(info.value)
    store.close()


@pytest.mark.parametrize("name", ["lab?.db", "run%41.db", "S01#2.db", "my lab.db"])
def test_a_bare_path_is_the_file_of_that_name(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, name: str
) -> None:
    """``--db lab?.db`` (a bare path: a SQLite file) was pasted into a URL as it was, so the
    session went to another file: ``lab`` (the rest read as a query), ``runA.db`` (``%41``
    decoded)."""
    monkeypatch.chdir(tmp_path)
    storage = open_storage(name)
    try:
        storage.create_session(SPEC, [NewEvent("note", {"text": "hi"})])
    finally:
        storage.close()
    assert (tmp_path / name).is_file()
    assert sorted(p.name for p in tmp_path.iterdir() if p.is_file()) == [name]


@pytest.mark.parametrize("code", ["", "S" * 65, "S 01", "é" * 1_000_000, 7])
def test_a_refused_subject_code_is_named_in_a_short_message(code: object) -> None:
    """A pasted megabyte (the console's form, the API) was echoed back whole in the error."""
    with pytest.raises(StorageError, match="subject code") as refused:
        check_subject(code)
    assert len(str(refused.value)) < 200


def test_a_host_that_does_not_resolve_is_a_connection_error() -> None:
    """libpq's "failed to resolve host" has no "connect" in it, so it was reported as a failed
    statement (StorageFailureError) rather than a server that cannot be reached."""
    url = "postgresql+psycopg://u@no-such-host.invalid/db?connect_timeout=5"
    with pytest.raises(StorageConnectError, match=r"cannot connect to .*no-such-host\.invalid"):
        open_storage(url)
