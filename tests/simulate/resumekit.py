"""What the tests of benches and studies that stop and resume share: a tiny bench continuous
and bench population to run, patches that make one of their runs (or one run of a study) fail
and record which runs ran, the CLI run with its output read back, and a partial file's lines."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref.cli import app
from gaitpref.config import load_config
from gaitpref.simulate import population as population_module
from gaitpref.simulate.study import RunTask, Study

CONTINUOUS = """\
[space.a]
min = 0.0
max = 2.0
[model]
lengthscale = 0.4
signal_variance = 1.0
noise = 0.05
jitter = 1e-6
fit = "fixed"
"""
POPULATION = "exo-1d-step-length"


def invoke(*args: str) -> tuple[int, str, str]:
    """``gaitpref ARGS``: the status, stdout, and stderr on one line (Rich wraps long lines)."""
    result = CliRunner().invoke(app, list(args))
    return result.exit_code, result.stdout, " ".join(result.stderr.split())


def resume(args: list[str], partial: Path, *more: str) -> tuple[int, str, str]:
    """``gaitpref ARGS MORE --partial PARTIAL --resume``, as :func:`invoke`."""
    return invoke(*args, *more, "--partial", str(partial), "--resume")


def read_lines(partial: Path) -> list[str]:
    return partial.read_text(encoding="utf-8").splitlines(keepends=True)


def write_lines(partial: Path, lines: list[str]) -> None:
    partial.write_text("".join(lines), encoding="utf-8")


def continuous_bench(tmp_path: Path) -> list[str]:
    """The arguments of a bench continuous of 4 runs of 5 trials on a 1-D space, its config and
    objective written in ``tmp_path`` (``cont.toml``, ``obj.py``)."""
    cfg = tmp_path / "cont.toml"
    cfg.write_text(CONTINUOUS)
    obj = tmp_path / "obj.py"
    obj.write_text("import numpy as np\ndef f(x):\n    return -np.abs(x[:, 0] - 1.0)\n")
    return ["bench", "continuous", str(cfg), "--objective", f"{obj}:f", "--runs", "4",
            "--trials", "5"]  # fmt: skip


def population_objectives(tmp_path: Path) -> Path:
    """Three subjects' objectives on :data:`POPULATION`'s gaits, in ``tmp_path/objectives.npy``."""
    x = np.linspace(0, 1, len(load_config(POPULATION).space))
    path = tmp_path / "objectives.npy"
    np.save(path, np.array([-((x - p) ** 2) for p in (0.6, 0.65, 0.7)]))
    return path


def break_seed(monkeypatch: pytest.MonkeyPatch, seed: int) -> list[int]:
    """The bench continuous run of ``seed`` raises (its runs run in this process); the returned
    list holds the seeds that ran."""
    import gaitpref.cli.points as points

    real, ran = points.simulate_points, []

    def simulate_points(*args: Any, **kwargs: Any) -> Any:
        ran.append(kwargs["seed"])
        if kwargs["seed"] == seed:
            raise ValueError("the treadmill stopped")
        return real(*args, **kwargs)

    monkeypatch.setattr(points, "simulate_points", simulate_points)
    return ran


def break_subject(monkeypatch: pytest.MonkeyPatch, subject: int, arm: str) -> list[tuple[str, int]]:
    """Subject ``subject``'s ``arm`` run of bench population raises (with jobs = 1 the runs run
    in this process); the returned list holds the runs that ran, as (arm, subject)."""
    real, ran = population_module._walk, []

    def walk(*args: Any) -> Any:
        seeds, others = args[4], args[5]  # (seed, subject); the others' preferences when warm
        which = ("cold" if others is None else "warm", seeds[1])
        ran.append(which)
        if which == (arm, subject):
            raise ValueError("the subject left")
        return real(*args)

    monkeypatch.setattr(population_module, "_walk", walk)
    return ran


def break_task(
    monkeypatch: pytest.MonkeyPatch, objective: object, index: int
) -> Callable[[], None]:
    """``Study.tasks`` with run ``index``'s objective replaced by ``objective`` (one of
    :mod:`tests.simulate.breaking`'s, say); the returned function undoes it."""
    tasks = Study.tasks

    def broken(self: Study) -> list[RunTask]:
        out = tasks(self)
        out[index] = dataclasses.replace(out[index], objective=objective)  # type: ignore[arg-type]
        return out

    monkeypatch.setattr(Study, "tasks", broken)
    return monkeypatch.undo


def check_resume_needs_an_existing_partial_file(args: list[str], tmp_path: Path) -> None:
    """``--resume`` without ``--partial``, or with a file that is not there, is refused (status
    2) and creates no file."""
    code, _, err = invoke(*args, "--resume")
    assert code == 2 and "--resume needs --partial FILE" in err
    missing = tmp_path / "none.jsonl"
    code, _, err = resume(args, missing)
    assert code == 2 and f"--resume: --partial '{missing}' is not a file" in err
    assert not missing.exists()
