"""``gaitpref bench continuous --partial FILE --resume``: a bench that stopped continues from the
runs in its partial file and prints the JSON of a bench that never stopped; a file of other
options is refused naming them; a last line cut short is dropped with a warning."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.simulate.resumekit import (
    break_seed,
    check_resume_needs_an_existing_partial_file,
    continuous_bench,
    invoke,
    read_lines,
    resume,
    write_lines,
)


@pytest.fixture()
def args(tmp_path: Path) -> list[str]:
    return [*continuous_bench(tmp_path), "--noise", "0.1", "--json"]


def _stopped(args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch, seed: int) -> Path:
    """The bench run with ``--partial tmp_path/kept.jsonl`` and the run of ``seed`` failing: it
    stops (status 1), the finished runs in that file, which is returned."""
    partial = tmp_path / "kept.jsonl"
    break_seed(monkeypatch, seed)
    assert invoke(*args, "--partial", str(partial))[0] == 1
    return partial


def test_a_resumed_bench_prints_the_uninterrupted_json(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    code, whole, _ = invoke(*args)
    assert code == 0
    partial = tmp_path / "kept.jsonl"
    break_seed(monkeypatch, 2)
    code, out, err = invoke(*args, "--partial", str(partial))
    assert code == 1 and out == "", err
    assert f"the same command with --partial '{partial}' --resume continues the bench" in err
    monkeypatch.undo()
    ran = break_seed(monkeypatch, -1)  # none breaks now; which seeds run is recorded
    code, out, err = resume(args, partial)
    assert code == 0, err
    assert ran == [2, 3]  # seeds 0 and 1 were kept
    assert out == whole  # byte for byte
    assert not partial.exists()


def test_a_last_line_cut_short_is_dropped_with_a_warning(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    code, whole, _ = invoke(*args)
    partial = _stopped(args, tmp_path, monkeypatch, 3)
    data = partial.read_bytes()
    partial.write_bytes(data[:-10])  # the machine died writing seed 2's line
    monkeypatch.undo()
    ran = break_seed(monkeypatch, -1)
    code, out, err = resume(args, partial)
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
    partial = _stopped(args, tmp_path, monkeypatch, 2)
    kept = partial.read_bytes()
    code, _, err = resume(args, partial, *change)
    assert code == 2, err
    assert f"{partial} holds the finished runs of another bench: {message}" in err
    assert partial.read_bytes() == kept


def test_an_objective_file_changed_is_refused(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = _stopped(args, tmp_path, monkeypatch, 2)
    (tmp_path / "obj.py").write_text(
        "import numpy as np\ndef f(x):\n    return -np.abs(x[:, 0] - 0.5)\n"
    )
    code, _, err = resume(args, partial)
    assert code == 2 and "another bench: objective_file_sha256 differs" in err


def test_a_file_without_its_first_line_is_refused(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """What gaitpref 0.1.0 wrote: nothing says which options wrote it."""
    partial = _stopped(args, tmp_path, monkeypatch, 2)
    lines = read_lines(partial)
    assert json.loads(lines[0])["gaitpref bench"]["runs"] == 4
    partial.write_text("".join(lines[1:]), encoding="utf-8")
    code, _, err = resume(args, partial)
    assert code == 2
    assert f"{partial}:1: the first line does not name the bench that wrote the file" in err


def test_resume_needs_an_existing_partial_file(args: list[str], tmp_path: Path) -> None:
    check_resume_needs_an_existing_partial_file(args, tmp_path)


def test_a_damaged_line_is_refused_naming_it(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = _stopped(args, tmp_path, monkeypatch, 3)
    lines = read_lines(partial)
    lines[2] = '{"seed": 1, "trials": 5}\n'
    write_lines(partial, lines)
    code, _, err = resume(args, partial)
    assert code == 2 and f"{partial}:3: not a run record of bench continuous (seed 1)" in err
    lines[2] = "{not json\n"
    write_lines(partial, lines)
    code, _, err = resume(args, partial)
    assert code == 2 and f"{partial}:3: not a JSON object" in err


def test_an_interrupt_before_any_run_finished_says_nothing_was_kept(
    args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C in the first run: status 130 saying so (it said nothing), and no partial file."""
    import gaitpref.cli.points as points

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(points, "simulate_points", interrupted)
    partial = tmp_path / "kept.jsonl"
    code, out, err = invoke(*args, "--partial", str(partial))
    assert code == 130 and out == "", err
    assert "interrupted before any run finished: nothing was kept or written" in err
    assert "--out" not in err and not partial.exists()
