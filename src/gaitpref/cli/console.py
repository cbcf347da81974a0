"""``gaitpref console``: serve the operator console with uvicorn.

On the loopback interface (the default, 127.0.0.1) no token is needed unless one is given.
Listening anywhere else requires one: ``--token``, else ``$GAITPREF_TOKEN``, else a random token
is generated and printed with the URL to open.

The console's web dependencies (FastAPI, uvicorn, Jinja2, python-multipart) are the extra
``gaitpref[console]``; without them this command says how to install them.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from gaitpref.cli.output import err_console as _out
from gaitpref.cli.output import fail
from gaitpref.console.security import TOKEN_ENV, new_token  # the standard library only

LOOPBACK = ("127.0.0.1", "localhost", "::1")
#: the modules of the `console` extra; a missing one is reported with the install line
WEB_MODULES = ("fastapi", "starlette", "uvicorn", "jinja2", "multipart", "python_multipart")
INSTALL_HINT = "pip install 'gaitpref[console]'"


def choose_token(host: str, token: str | None) -> str | None:
    """The token the console will require (None: none, only on the loopback interface)."""
    given = token or os.environ.get(TOKEN_ENV) or None
    if given is not None:
        return given
    return None if host in LOOPBACK else new_token()


def console_url(host: str, port: int, token: str | None) -> str:
    shown = f"[{host}]" if ":" in host else host
    if host in ("0.0.0.0", "::"):
        shown = "<this machine's address>"
    return f"http://{shown}:{port}/" + (f"?token={token}" if token else "")


def new_sqlite_file(url: str) -> Path | None:
    """The SQLite file ``url`` names when there is none yet (opening it makes a new database),
    else None (a file that is there, another backend, memory, a URL that does not parse)."""
    from gaitpref.errors import StorageError
    from gaitpref.storage.sql import parse_url

    try:
        parsed = parse_url(url)
    except StorageError:
        return None  # opening it says what is wrong
    name = parsed.database
    if parsed.get_backend_name() != "sqlite" or name in (None, "", ":memory:"):
        return None
    path = Path(name)
    return None if path.exists() else path


def port_taken(host: str, port: int) -> bool:
    """Whether another program listens on ``port`` at ``host``: a bind test on each address
    ``host`` resolves to, made as uvicorn (asyncio) binds (``SO_REUSEADDR``, so a port a closed
    server left in TIME_WAIT is free; IPv6 alone on an IPv6 address).  An address that cannot be
    bound for another reason (not this machine's, a name that does not resolve) is not taken:
    uvicorn reports it, as before."""
    import errno
    import socket

    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except (OSError, UnicodeError):
        return False
    for family, kind, proto, _, address in infos:
        try:
            with socket.socket(family, kind, proto) as sock:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                if family == socket.AF_INET6 and hasattr(socket, "IPPROTO_IPV6"):
                    sock.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
                sock.bind(address)
        except OSError as exc:
            if exc.errno == errno.EADDRINUSE:
                return True
    return False


def serve(
    db: Annotated[
        str | None,
        typer.Option(
            "--db",
            help="Database URL or SQLite path (default: $GAITPREF_DB, else ./gaitpref.db).",
        ),
    ] = None,
    host: Annotated[str, typer.Option(help="Interface to listen on.")] = "127.0.0.1",
    port: Annotated[int, typer.Option(min=1, max=65535, help="Port to listen on.")] = 8000,
    token: Annotated[
        str | None,
        typer.Option(help=f"Access token (default: ${TOKEN_ENV}; generated off loopback)."),
    ] = None,
    libraries: Annotated[
        Path | None,
        typer.Option(
            help="Folder of gait libraries (uploads are kept there; default: gait-libraries/ "
            "beside a SQLite database)."
        ),
    ] = None,
) -> None:
    """Serve the operator console (FastAPI + uvicorn) over the session database."""
    try:
        import uvicorn

        from gaitpref.console.app import create_app
    except ModuleNotFoundError as exc:
        if (exc.name or "").split(".")[0] not in WEB_MODULES:
            raise
        fail(
            f"the console needs its web dependencies (module {exc.name!r} is not installed): "
            f"{INSTALL_HINT}"
        )
    from gaitpref.storage import ENV_VAR, resolve_url
    from gaitpref.storage.sql import masked_url

    if libraries is not None and libraries.exists() and not libraries.is_dir():
        fail(  # taken before: the console served, and each upload failed to make its folder
            f"--libraries {str(libraries)!r} is a file, not a folder (uploaded gait libraries "
            "are kept in it)"
        )
    if port_taken(host, port):  # before: uvicorn's "[Errno 98] address already in use", exit 3
        other = port + 1 if port < 65535 else port - 1
        fail(
            f"port {port} on {host} is already in use (another console or program is listening "
            f"there): stop it, or give another port with --port, e.g. --port {other}"
        )
    use_token = choose_token(host, token)
    hosts = None if host not in LOOPBACK else list(LOOPBACK)
    new_file = new_sqlite_file(resolve_url(db))
    app = create_app(db, use_token, allowed_hosts=hosts, library_dir=libraries)
    shown = masked_url(resolve_url(db))  # its password (if any) as ***: it printed it
    _out.print(f"[bold]gaitpref console[/] on {escape(shown)}", markup=True)
    if new_file is not None and new_file.is_file():
        # a mistyped --db or $GAITPREF_DB served an empty list: the sessions looked lost
        _out.print(
            f"no database was at {str(new_file)!r}: a new, empty one was made there (no "
            f"sessions yet; if you expected some, check --db and ${ENV_VAR})",
            soft_wrap=True,
        )
    _out.print(f"open [bold]{escape(console_url(host, port, use_token))}[/]", markup=True)
    if use_token is not None:
        _out.print(
            "every request needs this token (Authorization: Bearer <token> for the API)",
            soft_wrap=True,
        )
    uvicorn.run(app, host=host, port=port, log_level="warning")
