"""The ``gaitpref`` command on a PostgreSQL URL: a password in it is never printed, and a
database that cannot be reached is an error (exit status 2), for ``db status`` too."""

from __future__ import annotations

import shlex
import subprocess
from pathlib import Path

import pytest
from typer.testing import CliRunner

from gaitpref.cli import app
from gaitpref.cli.session import _flag_hint, _resume_hint
from gaitpref.storage import StorageConnectError, open_storage

CONFIG = "exo-1d-step-length"
#: a password with the characters a URL must encode: @ : / % # and a space
PASSWORD, ENCODED = "p@ss:w/rd% #", "p%40ss%3Aw%2Frd%25%20%23"


def _run(*args: str, env: dict[str, str] | None = None) -> tuple[int, str]:
    result = CliRunner().invoke(app, list(args), env=env)
    return result.exit_code, result.output


def test_the_hints_to_type_again_show_the_password_as_stars() -> None:
    """``session new`` printed ``run it with: gaitpref session run 1 --db URL`` with the
    password of the URL as it was given; the terminal's resume and flag hints too."""
    url = f"postgresql+psycopg://lab:{ENCODED}@db.example:5433/gaitlab"
    for hint in (_resume_hint(3, url), _flag_hint(3, url)(2, "knee gave way")):
        assert ENCODED not in hint and "p%40ss" not in hint and PASSWORD not in hint, hint
        assert "--db 'postgresql+psycopg://lab:***@db.example:5433/gaitlab'" in hint, hint
    plain = "postgresql+psycopg://lab@db.example/gaitlab"  # no password: as given
    assert _resume_hint(3, plain) == f"gaitpref session run 3 --db {plain}"
    assert _resume_hint(3, "my lab.db") == "gaitpref session run 3 --db 'my lab.db'"


def test_a_port_that_is_not_a_number_is_refused_without_the_password() -> None:
    """The ``--db`` check raised a ValueError traceback (exit status 1), and opening the URL
    named it whole, password and all."""
    url = "postgresql+psycopg://lab:topsecret@127.0.0.1:notaport/lab"
    code, out = _run("session", "list", "--db", url)
    assert code == 2 and "not a database URL" in out and "Traceback" not in out, out
    assert "topsecret" not in out and "lab:***@127.0.0.1:notaport" in out, out
    with pytest.raises(StorageConnectError) as err:
        open_storage(url)
    assert "topsecret" not in str(err.value), err.value


def test_db_status_of_a_server_that_does_not_answer_is_an_error() -> None:
    """It printed a status line (exit status 0) naming the URL twice."""
    url = "postgresql+psycopg://lab:topsecret@127.0.0.1:1/lab"
    for command in (("db", "status"), ("session", "list"), ("db", "check")):
        code, out = _run(*command, "--db", url)
        assert code == 2, (command, out)
        assert "cannot connect to postgresql+psycopg://lab:***@127.0.0.1:1/lab" in out, out
        assert "topsecret" not in out and out.count("127.0.0.1:1/lab") == 1, out


@pytest.mark.postgres
def test_a_session_on_postgres_from_the_command_line(postgres_url: str) -> None:
    """``session new``, ``list``, ``show`` and ``db status``/``check`` with a password of
    special characters, URL-encoded, in ``--db`` and in ``$GAITPREF_DB``: none prints it."""
    url = postgres_url.replace("gaitpref@", f"gaitpref:{ENCODED}@")  # the server trusts
    code, out = _run("session", "new", "--config", CONFIG, "--subject", "S01", "--db", url)
    assert code == 0, out
    assert "run it with: gaitpref session run 1 --db 'postgresql+psycopg://gaitpref:***@" in out
    outputs = [out]
    for command in (
        ("session", "list"),
        ("session", "show", "1", "--no-figure", "--json"),
        ("db", "status"),
        ("db", "check"),
    ):
        code, out = _run(*command, env={"GAITPREF_DB": url})
        assert code == 0, (command, out)
        outputs.append(out)
    assert "1 session, 1 subject" in " ".join(outputs[3].split())
    code, out = _run("db", "backup", "copy.db", "--db", url)
    assert code == 2 and "pg_dump" in out, out
    outputs.append(out)
    for out in outputs:
        assert ENCODED not in out and "p%40ss" not in out and PASSWORD not in out, out


def test_without_psycopg_the_install_command_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    """psycopg is the ``postgres`` extra: without it every command said the driver could not
    be loaded, and not how to install it."""
    import sys

    monkeypatch.setitem(sys.modules, "psycopg", None)  # an import of it fails
    for url in ("postgresql+psycopg://lab:topsecret@db.example/lab", "postgresql://u@h/lab"):
        for command in (("session", "list"), ("db", "upgrade"), ("db", "status")):
            code, out = _run(*command, "--db", url)
            assert code == 2, (command, out)
            text = " ".join(out.split())
            assert "pip install 'gaitpref[postgres]'" in text and "topsecret" not in text, text


def test_a_traceback_lists_no_local_variables() -> None:
    """Older typer releases (``typer>=0.12`` is allowed) could print every local variable of
    an unexpected error's traceback by default, ``--db`` and its password among them."""
    assert app.pretty_exceptions_show_locals is False


def test_a_wrong_password_says_how_to_encode_one() -> None:
    """'password authentication failed' alone: a password with @ or : typed into the URL as it
    is reads as another user and host, and nothing said so."""
    from sqlalchemy.exc import OperationalError

    from gaitpref.storage.sql import _reason

    failed = OperationalError("connect", {}, Exception("FATAL:  password authentication failed"))
    assert "%40 for @" in _reason(failed)
    assert "%40" not in _reason(OperationalError("x", {}, Exception("Connection refused")))


def test_a_password_given_as_a_url_parameter_is_hidden_too() -> None:
    """libpq takes ``?password=``: the URL was printed with it, in errors and hints."""
    url = "postgresql://lab@127.0.0.1:1/lab?sslmode=disable&password=topsecret"
    for command in (("db", "status"), ("session", "list"), ("db", "backup", "x.dump")):
        code, out = _run(*command, "--db", url)
        assert code == 2 and "topsecret" not in out and "password=***" in out, (command, out)
    assert "topsecret" not in _resume_hint(1, url) and "password=***" in _resume_hint(1, url)


@pytest.mark.postgres
def test_the_pg_dump_command_keeps_the_urls_parameters_and_works(
    postgres_url: str, tmp_path: Path
) -> None:
    """The command printed for a URL with ``?sslmode=...`` and other libpq parameters left them
    out (a lab whose server requires SSL got a command that could not connect); it now carries
    them, never the password, and it dumps the database as printed."""
    from tests.conftest import _pg_bindir

    bindir = _pg_bindir()
    if bindir is None or not (bindir / "pg_dump").exists():
        pytest.skip("no pg_dump on this machine (Debian's postgresql package has it)")
    query = "sslmode=disable&connect_timeout=10&application_name=gait%27s%20lab&password=s3cret"
    url = postgres_url.replace("gaitpref@", f"gaitpref:{ENCODED}@") + "?" + query
    code, _ = _run("db", "upgrade", "--db", url)
    assert code == 0
    out = tmp_path / "lab dump"
    code, said = _run("db", "backup", str(out), "--db", url)
    assert code == 2, said
    said = " ".join(said.split())
    assert "s3cret" not in said and ENCODED not in said and PASSWORD not in said, said
    command = said.split("`")[1]
    words = shlex.split(command)
    assert words[0] == "pg_dump" and f"--file={out}" in words, command
    assert words[-1] == (
        f"dbname={postgres_url.rsplit('/', 1)[1]} sslmode=disable connect_timeout=10 "
        "application_name='gait\\'s lab'"
    ), command
    done = subprocess.run(
        ["bash", "-c", str(bindir / "pg_dump") + command.removeprefix("pg_dump")],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert out.read_bytes().startswith(b"PGDMP")  # pg_dump's custom format
