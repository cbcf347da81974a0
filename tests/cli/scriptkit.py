"""Run ``gaitpref`` as a shell script or ``subprocess`` does: a fresh interpreter, stdin from
``/dev/null`` unless given, stdout and stderr pipes (not terminals) and ``COLUMNS`` unset."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import gaitpref

#: the ``src`` folder this ``gaitpref`` was imported from (the worktree's, not an installed one)
SRC = str(Path(gaitpref.__file__).resolve().parents[1])


def run_script(
    *args: str, stdin: str | None = None, cwd: Path | None = None, timeout: float = 120
) -> subprocess.CompletedProcess[str]:
    """``gaitpref ARGS`` in a subprocess, ``stdin`` fed to it (None: ``/dev/null``)."""
    env = {k: v for k, v in os.environ.items() if k not in ("COLUMNS", "LINES", "FORCE_COLOR")}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, (SRC, env.get("PYTHONPATH"))))
    return subprocess.run(
        [sys.executable, "-m", "gaitpref", *args],
        input=stdin,
        stdin=subprocess.DEVNULL if stdin is None else None,
        capture_output=True,
        text=True,
        env=env,
        cwd=cwd,
        timeout=timeout,
        check=False,
    )
