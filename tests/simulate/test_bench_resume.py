"""``gaitpref bench continuous --partial FILE --resume``: a bench that stopped continues from the
runs in its partial file and prints the JSON of a bench that never stopped; a file of other
options is refused naming them; a last line cut short is dropped with a warning."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from gaitpref.cli import app

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


@pytest.fixture()
def args(tmp_path: Path) -> list[str]:
    cfg = tmp_path / "cont.toml"
    cfg.write_text(CONTINUOUS)
    obj = tmp_path / "obj.py"
    obj.write_text("import numpy as np\ndef f(x):\n    return -np.abs(x[:, 0] - 1.0)\n")
    return ["bench", "continuous", str(cfg), "--objective", f"{obj}:f", "--runs", "4",
            "--trials", "5", "--noise", "0.1", "--json"]  # fmt: skip


def _invoke(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, list(args))
    return result.exit_code, result.stdout, " ".join(result.stderr.split())


def _break_seed(monkeypatch: pytest.MonkeyPatch, seed: int) -> list[int]:
    """The run of ``seed`` raises; the returned list holds the seeds that ran."""
    import gaitpref.cli.points as points

    real, ran = points.simulate_points, []

    def simulate_points(*args: Any, **kwargs: Any) -> Any:
        ran.append(kwargs["seed"])
        if kwargs["seed"] == seed:
            raise ValueError("the treadmill stopped")
        return real(*args, **kwargs)

    monkeypatch.setattr(points, "simulate_points", simulate_points)
    return ran


def test_a_resumed_bench_prints_the_uninterrupted_json(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    code, whole, _ = _invoke(*args)
    assert code == 0
    partial = tmp_path / "kept.jsonl"
    _break_seed(monkeypatch, 2)
    code, out, err = _invoke(*args, "--partial", str(partial))
    assert code == 1 and out == "", err
    assert f"the same command with --partial '{partial}' --resume continues the bench" in err
    monkeypatch.undo()
    ran = _break_seed(monkeypatch, -1)  # none breaks now; which seeds run is recorded
    code, out, err = _invoke(*args, "--partial", str(partial), "--resume")
    assert code == 0, err
    assert ran == [2, 3]  # seeds 0 and 1 were kept
    assert out == whole  # byte for byte
    assert not partial.exists()


def test_a_last_line_cut_short_is_dropped_with_a_warning(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    code, whole, _ = _invoke(*args)
    partial = tmp_path / "kept.jsonl"
    _break_seed(monkeypatch, 3)
    assert _invoke(*args, "--partial", str(partial))[0] == 1
    data = partial.read_bytes()
    partial.write_bytes(data[:-10])  # the machine died writing seed 2's line
    monkeypatch.undo()
    ran = _break_seed(monkeypatch, -1)
    code, out, err = _invoke(*args, "--partial", str(partial), "--resume")
    assert code == 0, err
    assert f"warning: {partial}:4: the last line is cut short" in err
    assert ran == [2, 3] and out == whole


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (["--trials", "6"], "trials differs: 5 in the file, 6 here"),
        (["--noise", "0.2"], "noise differs: 0.1 in the file, 0.2 here"),
        (["--coactive"], "coactive differs: false in the file, true here"),
    ],
)
def test_a_file_of_other_options_is_refused_naming_them(
    args: list[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    change: list[str],
    message: str,
) -> None:
    partial = tmp_path / "kept.jsonl"
    _break_seed(monkeypatch, 2)
    assert _invoke(*args, "--partial", str(partial))[0] == 1
    kept = partial.read_bytes()
    code, _, err = _invoke(*args, *change, "--partial", str(partial), "--resume")
    assert code == 2, err
    assert f"{partial} holds the finished runs of another bench: {message}" in err
    assert partial.read_bytes() == kept


def test_an_objective_file_changed_is_refused(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = tmp_path / "kept.jsonl"
    _break_seed(monkeypatch, 2)
    assert _invoke(*args, "--partial", str(partial))[0] == 1
    (tmp_path / "obj.py").write_text(
        "import numpy as np\ndef f(x):\n    return -np.abs(x[:, 0] - 0.5)\n"
    )
    code, _, err = _invoke(*args, "--partial", str(partial), "--resume")
    assert code == 2 and "another bench: objective_file_sha256 differs" in err


def test_a_file_without_its_first_line_is_refused(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """What gaitpref 0.1.0 wrote: nothing says which options wrote it."""
    partial = tmp_path / "kept.jsonl"
    _break_seed(monkeypatch, 2)
    assert _invoke(*args, "--partial", str(partial))[0] == 1
    lines = partial.read_text(encoding="utf-8").splitlines(keepends=True)
    assert json.loads(lines[0])["gaitpref bench"]["runs"] == 4
    partial.write_text("".join(lines[1:]), encoding="utf-8")
    code, _, err = _invoke(*args, "--partial", str(partial), "--resume")
    assert code == 2
    assert f"{partial}:1: the first line does not name the bench that wrote the file" in err


def test_resume_needs_an_existing_partial_file(args: list[str], tmp_path: Path) -> None:
    code, _, err = _invoke(*args, "--resume")
    assert code == 2 and "--resume needs --partial FILE" in err
    missing = tmp_path / "none.jsonl"
    code, _, err = _invoke(*args, "--partial", str(missing), "--resume")
    assert code == 2 and f"--resume: --partial '{missing}' is not a file" in err
    assert not missing.exists()


def test_a_damaged_line_is_refused_naming_it(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = tmp_path / "kept.jsonl"
    _break_seed(monkeypatch, 3)
    assert _invoke(*args, "--partial", str(partial))[0] == 1
    lines = partial.read_text(encoding="utf-8").splitlines(keepends=True)
    lines[2] = '{"seed": 1, "trials": 5}\n'
    partial.write_text("".join(lines), encoding="utf-8")
    code, _, err = _invoke(*args, "--partial", str(partial), "--resume")
    assert code == 2 and f"{partial}:3: not a run record of bench continuous (seed 1)" in err
    lines[2] = "{not json\n"
    partial.write_text("".join(lines), encoding="utf-8")
    code, _, err = _invoke(*args, "--partial", str(partial), "--resume")
    assert code == 2 and f"{partial}:3: not a JSON object" in err
