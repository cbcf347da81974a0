"""``gaitpref simulate`` refuses options its run would ignore, naming them.

``--minimize`` with an objective over points (``PATH.py:NAME``, ``hartmann6``, ``random-gp``)
ran the same maximizing subject as without it (the point path never took the option).  It now
exits with status 2 naming the option, before any trial.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from gaitpref.cli import app

runner = CliRunner()

POINTS = "def f(x):\n    return -((x - 0.3) ** 2).sum(axis=1)\n"


@pytest.fixture
def points_spec(tmp_path: Path) -> str:
    path = tmp_path / "points.py"
    path.write_text(POINTS, encoding="utf-8")
    return f"{path}:f"


@pytest.mark.parametrize("objective", ["points", "random-gp"])
def test_minimize_with_an_objective_over_points_is_refused(
    points_spec: str, objective: str
) -> None:
    spec = points_spec if objective == "points" else objective
    args = ["simulate", "synthetic-2d", "--objective", spec, "--trials", "3", "--minimize"]
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    assert "--minimize" in result.output and "maximized" in result.output
    assert "Traceback" not in result.output
    args.remove("--minimize")
    assert runner.invoke(app, args).exit_code == 0  # and without it the run goes
