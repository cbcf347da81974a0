"""Shared fixtures: small grids, a throwaway PostgreSQL server, and the rule that CI runs all.

The PostgreSQL server is started once per test run from Debian's server binaries
(``/usr/lib/postgresql/*/bin``, installed by ``make test`` through ``.ci/system-deps``), in a
temporary folder, on a free port of 127.0.0.1, as the ``postgres`` user when running as root
(``initdb`` refuses root), and stopped at the end.  ``GAITPREF_TEST_POSTGRES_URL`` points the tests
at an existing server instead.  Without either, tests marked ``postgres`` skip with a message that
says how to enable them, and under ``CI=true`` such a skip is a failure.
"""

from __future__ import annotations

import contextlib
import glob
import os
import pwd
import shutil
import socket
import subprocess
import tempfile
from collections.abc import Callable, Iterator
from itertools import count
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

from gaitpref import Feature, Space, SquaredExponential
from gaitpref.storage import MemoryStorage, Storage, open_storage

# Property tests judge results, not speed: no per-example deadline (a loaded 2-core CI machine
# makes timings noisy; speed targets live in benchmarks/).
settings.register_profile(
    "gaitpref", deadline=None, suppress_health_check=[HealthCheck.too_slow], print_blob=True
)
settings.load_profile("gaitpref")

pytest_plugins = ("pytester", "tests.ci_rule")  # the CI rule: see tests/ci_rule.py

_HOW = (
    "install Debian's postgresql package (`make test` does it as root), or set "
    "GAITPREF_TEST_POSTGRES_URL=postgresql+psycopg://user@host:port/db"
)


def _pg_bindir() -> Path | None:
    found = sorted(
        glob.glob("/usr/lib/postgresql/*/bin/initdb"),
        key=lambda p: (
            int(Path(p).parent.parent.name) if Path(p).parent.parent.name.isdigit() else 0
        ),
    )
    if found:
        return Path(found[-1]).parent
    initdb = shutil.which("initdb")
    return Path(initdb).parent if initdb else None


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="session")
def postgres_server() -> Iterator[str]:
    """A URL (without database) of a running PostgreSQL server for this test run."""
    given = os.environ.get("GAITPREF_TEST_POSTGRES_URL")
    if given:
        yield given.rsplit("/", 1)[0]
        return
    bindir = _pg_bindir()
    if bindir is None:
        pytest.skip(f"no PostgreSQL server binaries (initdb) on this machine: {_HOW}")
    prefix: list[str] = []
    as_root = os.geteuid() == 0
    # as root, the server runs as postgres: use a folder it can reach whatever $TMPDIR is
    root = Path(tempfile.mkdtemp(prefix="gaitpref-pg-", dir="/tmp" if as_root else None))
    if as_root:
        try:
            user = pwd.getpwnam("postgres")
        except KeyError:
            shutil.rmtree(root)
            pytest.skip(f"running as root and there is no postgres user to run initdb: {_HOW}")
        os.chown(root, user.pw_uid, user.pw_gid)
        prefix = ["runuser", "-u", "postgres", "--"]
    data, port = root / "data", _free_port()

    def run(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [*prefix, *args], capture_output=True, text=True, timeout=120, check=False
        )

    init = run(str(bindir / "initdb"), "-D", str(data), "-A", "trust", "-U", "gaitpref",
               "-E", "UTF8", "--locale=C", "--no-sync")  # fmt: skip
    options = (
        f"-h 127.0.0.1 -p {port} -k {root} -c fsync=off -c full_page_writes=off "
        "-c synchronous_commit=off -c max_connections=50"
    )
    start = None
    if init.returncode == 0:
        start = run(str(bindir / "pg_ctl"), "-D", str(data), "-l", str(root / "log"),
                    "-o", options, "-w", "-t", "60", "start")  # fmt: skip
    if start is None or start.returncode != 0:
        failed = init if start is None else start
        log = (root / "log").read_text() if (root / "log").exists() else ""
        shutil.rmtree(root, ignore_errors=True)
        pytest.skip(f"could not start PostgreSQL ({failed.stderr.strip()} {log[-500:]}): {_HOW}")
    try:
        yield f"postgresql+psycopg://gaitpref@127.0.0.1:{port}"
    finally:
        run(str(bindir / "pg_ctl"), "-D", str(data), "-m", "immediate", "-w", "stop")
        shutil.rmtree(root, ignore_errors=True)


_databases = count()


@pytest.fixture
def postgres_url(postgres_server: str) -> Iterator[str]:
    """A URL of a new, empty database on the test server (dropped afterwards)."""
    import psycopg

    name = f"gaitpref_test_{os.getpid()}_{next(_databases)}"
    admin = postgres_server.replace("postgresql+psycopg://", "postgresql://") + "/postgres"
    with psycopg.connect(admin, autocommit=True) as conn:
        conn.execute(f'CREATE DATABASE "{name}"')
    try:
        yield f"{postgres_server}/{name}"
    finally:
        with (
            contextlib.suppress(psycopg.Error),
            psycopg.connect(admin, autocommit=True) as conn,
        ):
            conn.execute(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')


@pytest.fixture(params=["memory", "sqlite", pytest.param("postgres", marks=pytest.mark.postgres)])
def backend_url(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """A database URL for each backend: ``memory://``, a SQLite file, a PostgreSQL database."""
    if request.param == "memory":
        return "memory://"
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path / 'gaitpref.db'}"
    return str(request.getfixturevalue("postgres_url"))


@pytest.fixture
def open_db(backend_url: str) -> Iterator[Callable[[], Storage]]:
    """Opens the test database; each call is a new handle (one shared object for memory)."""
    opened: list[Storage] = []
    memory = MemoryStorage()

    def opener() -> Storage:
        if backend_url == "memory://":
            return memory
        store = open_storage(backend_url)
        opened.append(store)
        return store

    yield opener
    for store in opened:
        store.close()


@pytest.fixture
def small_space() -> Space:
    """A 7 x 5 grid with units, small enough for dense references."""
    return Space(
        [
            Feature.linspace("step_length", 0.08, 0.18, 7, unit="m"),
            Feature.linspace("step_duration", 0.85, 1.15, 5, unit="s"),
        ]
    )


@pytest.fixture
def small_kernel() -> SquaredExponential:
    return SquaredExponential((0.03, 0.08), 0.005, 1e-7)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture
def no_trial(monkeypatch: pytest.MonkeyPatch) -> None:
    """Any ask of the grid or line loop fails the test: for tests that a refused input runs no
    trial (``pytest.mark.usefixtures("no_trial")``)."""
    from gaitpref.loop.cospar import CoSpar
    from gaitpref.loop.line import LineCoSpar

    def ask(self: object) -> None:
        raise AssertionError("a trial ran")

    monkeypatch.setattr(CoSpar, "ask", ask)
    monkeypatch.setattr(LineCoSpar, "ask", ask)
