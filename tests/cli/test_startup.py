"""A quick start: which modules ``import gaitpref``, ``gaitpref --help`` and ``session list`` load.

Each case runs in a fresh interpreter and reports the modules in ``sys.modules`` afterwards; the
heavy ones (web framework, matplotlib, SciPy's optimizers, SQLAlchemy) must not be among them.
Timings are not asserted here: ``benchmarks/bench_startup.py`` measures them.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

WEB = ("fastapi", "starlette", "uvicorn", "jinja2", "multipart", "python_multipart")
HEAVY = (*WEB, "matplotlib", "scipy.optimize", "sqlalchemy")

_PROBE = """
import json, sys
out, code, argv = sys.argv[1], sys.argv[2], sys.argv[3:]
sys.argv = ["gaitpref", *argv]
status = None
try:
    exec(code)
except SystemExit as exc:
    status = exc.code
with open(out, "w") as f:
    json.dump({"modules": sorted(sys.modules), "status": status}, f)
"""


def loaded(tmp_path: Path, code: str, *argv: str) -> tuple[set[str], object, str]:
    """The modules loaded by ``code`` (with ``sys.argv[1:] = argv``), its exit status and output."""
    report = tmp_path / "modules.json"
    run = subprocess.run(
        [sys.executable, "-c", _PROBE, str(report), code, *argv],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        env={**os.environ, "COLUMNS": "200", "NO_COLOR": "1"},
    )
    assert run.returncode == 0, run.stderr
    data = json.loads(report.read_text())
    return set(data["modules"]), data["status"], run.stdout + run.stderr


def present(modules: set[str], names: tuple[str, ...]) -> list[str]:
    return sorted(n for n in names if n in modules)


def test_import_gaitpref_loads_only_the_errors(tmp_path: Path) -> None:
    modules, _, _ = loaded(tmp_path, "import gaitpref")
    assert present(modules, (*HEAVY, "numpy", "scipy", "rich", "typer", "pydantic")) == []
    assert {m for m in modules if m.startswith("gaitpref")} == {"gaitpref", "gaitpref.errors"}


def test_the_storage_contract_suite_needs_pytest_only_when_imported(tmp_path: Path) -> None:
    modules, _, _ = loaded(tmp_path, "import gaitpref.storage")
    assert "pytest" not in modules and "gaitpref.storage.testing" not in modules
    modules, _, _ = loaded(tmp_path, "import gaitpref.storage.testing")
    assert "pytest" in modules


def test_the_probe_sees_what_a_public_name_loads(tmp_path: Path) -> None:
    # the check above can fail: the first use of a name loads its module and what it needs
    modules, _, _ = loaded(tmp_path, "import gaitpref; gaitpref.CoSpar; gaitpref.Session")
    assert present(modules, ("numpy", "scipy.optimize", "sqlalchemy")) == [
        "numpy",
        "scipy.optimize",
        "sqlalchemy",
    ]


@pytest.mark.parametrize("argv", [["--help"], ["session", "--help"], ["console", "--help"]])
def test_help_loads_nothing_heavy(tmp_path: Path, argv: list[str]) -> None:
    modules, status, output = loaded(tmp_path, "from gaitpref.cli import main; main()", *argv)
    assert status == 0, output
    assert "Usage:" in output
    assert present(modules, (*HEAVY, "numpy", "scipy")) == []


def test_session_list_loads_no_model_plots_or_web(tmp_path: Path) -> None:
    from gaitpref import Session
    from tests.sessions.sessionkit import CONFIG

    db = f"sqlite:///{tmp_path / 'lab.db'}"
    Session.create(db, CONFIG, "S07", seed=1).close()
    modules, status, output = loaded(
        tmp_path, "from gaitpref.cli import main; main()", "session", "list", "--db", db
    )
    assert status == 0, output
    assert "S07" in output and "exo-1d-step-length" in output
    assert present(modules, (*WEB, "matplotlib", "scipy.optimize")) == []
    assert "sqlalchemy" in modules  # it did read the database


def test_python_m_gaitpref_is_the_command_line() -> None:
    """``python -m gaitpref`` runs the same app as the ``gaitpref`` script (no __main__ before)."""
    run = subprocess.run(
        [sys.executable, "-m", "gaitpref", "configs"], capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 0, run.stderr
    assert "synthetic-2d" in run.stdout
