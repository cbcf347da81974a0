"""Run ``gaitpref`` as a shell script or ``subprocess`` does: a fresh interpreter, stdin from
``/dev/null`` unless given, stdout and stderr pipes (not terminals), ``COLUMNS`` unset and a
colour terminal's ``TERM``."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import gaitpref

#: what a terminal or a CI runner may set that would hide what a script sees (a width, colour
#: forced or refused)
_UNSET = ("COLUMNS", "LINES", "FORCE_COLOR", "NO_COLOR", "TTY_COMPATIBLE", "TTY_INTERACTIVE")

#: the ``src`` folder this ``gaitpref`` was imported from (the worktree's, not an installed one)
SRC = str(Path(gaitpref.__file__).resolve().parents[1])


def run_script(
    *args: str, stdin: str | None = None, cwd: Path | None = None, timeout: float = 120
) -> subprocess.CompletedProcess[str]:
    """``gaitpref ARGS`` in a subprocess, ``stdin`` fed to it (None: ``/dev/null``)."""
    env = {k: v for k, v in os.environ.items() if k not in _UNSET}
    env["TERM"] = "xterm-256color"  # a terminal's: colour would be drawn if the pipe were not seen
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
