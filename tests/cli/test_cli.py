from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref.cli import app
from gaitpref.data import paper_objectives

runner = CliRunner()


@pytest.fixture
def objective_file(tmp_path: Path) -> Path:
    path = tmp_path / "objective.npy"
    np.save(path, paper_objectives()[5])
    return path


def test_simulate_json(objective_file: Path) -> None:
    args = ["simulate", "synthetic-2d", "--objective", str(objective_file), "--trials", "30"]
    args += ["--seed", "3", "--coactive", "--json"]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    payload = json.loads(result.stdout)
    assert len(payload["normalized_objective"]) == 30 and len(payload["actions"]) == 30
    obj = paper_objectives()[5].reshape(-1)
    norm = (obj[payload["actions"]] - obj.min()) / (obj.max() - obj.min())
    assert np.allclose(payload["normalized_objective"], norm)
    assert 0 <= payload["posterior_argmax"] < 900
    again = runner.invoke(app, args)
    assert json.loads(again.stdout)["actions"] == payload["actions"]


def test_simulate_minimize_on_a_1d_objective(tmp_path: Path) -> None:
    x = np.linspace(0.08, 0.18, 24)
    path = tmp_path / "cot.npy"
    np.save(path, np.polyval([-660.1898, 556.5202, -186.4672, 34.1877, -3.4090, 0.1602], x))
    result = runner.invoke(
        app,
        [
            "simulate",
            "configs/compass-gait.toml",
            "--objective",
            str(path),
            "--minimize",
            "--trials",
            "60",
            "--json",
        ],
    )
    assert result.exit_code == 0, result.output
    best = json.loads(result.stdout)["posterior_argmax"]
    assert abs(x[best] - 0.132) < 0.015


def test_simulate_human_output(objective_file: Path) -> None:
    result = runner.invoke(
        app, ["simulate", "synthetic-2d", "--objective", str(objective_file), "--trials", "12"]
    )
    assert result.exit_code == 0, result.output
    assert "mean normalized objective" in result.output and "posterior argmax" in result.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["simulate", "no-such-config", "--objective", "x.npy"], "no such file"),
        (["simulate", "synthetic-2d", "--objective", "missing.npy"], "does not exist"),
    ],
)
def test_simulate_errors(args: list[str], message: str) -> None:
    result = runner.invoke(app, args)
    assert result.exit_code == 2
    assert message in result.output


def test_simulate_wrong_shape(tmp_path: Path) -> None:
    path = tmp_path / "bad.npy"
    np.save(path, np.zeros((4, 4)))
    result = runner.invoke(app, ["simulate", "synthetic-2d", "--objective", str(path)])
    assert result.exit_code == 2 and "shape (4, 4)" in result.output


def test_configs_lists_the_shipped_configs() -> None:
    result = runner.invoke(app, ["configs"])
    assert result.exit_code == 0
    assert "exo-1d-step-length" in result.output and "synthetic-2d" in result.output
    assert "compass-continuous-3d" in result.output and "continuous:" in result.output


def test_demo_writes_its_figure(tmp_path: Path) -> None:
    result = runner.invoke(app, ["demo", "--out", str(tmp_path), "--trials", "20"])
    assert result.exit_code == 0, result.output
    # styled as Rich markup, never printed as its tags
    assert "scripted session: a simulated subject" in result.output
    assert "[bold]" not in result.output and "[/]" not in result.output
    assert f"database: {tmp_path / 'sessions.db'}" in " ".join(result.output.split())
    figure = tmp_path / "posterior.png"
    assert figure.is_file() and figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
