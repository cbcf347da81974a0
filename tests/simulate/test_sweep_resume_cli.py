"""``gaitpref bench paper-2d|compass-gait --resume``: a study that stopped (a run failed, Ctrl-C,
its files could not be written) continues from ``OUT/runs.partial.csv`` and writes the run
table and curves an uninterrupted study writes, byte for byte."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from gaitpref.cli import app
from tests.simulate.breaking import Raising
from tests.simulate.resumekit import break_task

ARGS = ("--runs", "2", "--trials", "5", "--settings", "n1_b1", "--jobs", "1")
COMPASS = ("--runs", "2", "--trials", "5", "--iterations", "1,3", "--jobs", "1")


def _invoke(command: str, out: Path, *args: str) -> tuple[int, str]:
    result = CliRunner().invoke(app, ["bench", command, *args, "--out", str(out)])
    return result.exit_code, " ".join(result.output.split())  # Rich wraps long lines


class _Interrupting:
    """An objective whose reading is interrupted (Ctrl-C while its run runs)."""

    def __array__(self, dtype: object = None, copy: object = None) -> object:
        raise KeyboardInterrupt


@pytest.mark.parametrize(
    ("command", "args", "files"),
    [
        ("paper-2d", ARGS, ("runs.csv", "curves.csv")),
        ("compass-gait", COMPASS, ("runs.csv", "curves.csv")),
    ],
)
@pytest.mark.parametrize(("stop", "status"), [(Raising(), 1), (_Interrupting(), 130)])
def test_a_stopped_study_resumed_writes_the_uninterrupted_files(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    command: str,
    args: tuple[str, ...],
    files: tuple[str, ...],
    stop: object,
    status: int,
) -> None:
    whole, resumed = tmp_path / "whole", tmp_path / "resumed"
    code, out = _invoke(command, whole, *args)
    assert code == 0, out
    break_task(monkeypatch, stop, 2)
    code, out = _invoke(command, resumed, *args)
    assert code == status, out
    assert "runs.partial.csv" in out and not (resumed / "runs.csv").exists()
    assert "the same command with --resume continues the study from them" in out
    monkeypatch.undo()
    code, out = _invoke(command, resumed, *args, "--resume")
    assert code == 0, out
    # runs 0 and 1 finished before run 2 stopped it (one job): kept, not run in the time given
    assert "runs (2 kept from runs.partial.csv) in " in out
    assert not (resumed / "runs.partial.csv").exists()
    for name in files:
        assert (resumed / name).read_bytes() == (whole / name).read_bytes(), name


@pytest.mark.parametrize(("command", "args"), [("paper-2d", ARGS), ("compass-gait", COMPASS)])
@pytest.mark.parametrize("there", [False, True])
def test_an_interrupt_before_any_run_finished_says_so(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    command: str,
    args: tuple[str, ...],
    there: bool,
) -> None:
    """Ctrl-C in the first run (one job): status 130 saying nothing was kept or written (it
    said nothing), and an --out the command made, still empty, removed; one that was there is
    left, empty, as it was."""
    out_dir = tmp_path / "a" / "out"
    if there:
        out_dir.mkdir(parents=True)
    break_task(monkeypatch, _Interrupting(), 0)
    code, out = _invoke(command, out_dir, *args)
    assert code == 130, out
    assert "interrupted before any run finished: nothing was kept or written" in out
    if there:
        assert f"--out '{out_dir}' is left as it was" in out
        assert list(out_dir.iterdir()) == []
    else:
        assert f"--out '{out_dir}', made by this command, was removed" in out
        assert not out_dir.exists()


def test_an_uninterrupted_study_names_no_kept_runs(tmp_path: Path) -> None:
    code, out = _invoke("paper-2d", tmp_path / "out", *ARGS)
    assert code == 0, out
    assert "kept from" not in out and " runs in " in out


def test_resume_without_a_partial_table_is_refused(tmp_path: Path) -> None:
    code, out = _invoke("paper-2d", tmp_path, *ARGS, "--resume")
    assert code == 2, out
    assert f"--resume: --out '{tmp_path}' holds no runs.partial.csv" in out
    assert list(tmp_path.iterdir()) == []


def test_a_partial_table_of_other_options_is_refused_naming_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    break_task(monkeypatch, Raising(), 2)
    code, out = _invoke("paper-2d", tmp_path, *ARGS)
    assert code == 1, out
    monkeypatch.undo()
    kept = (tmp_path / "runs.partial.csv").read_bytes()
    other = ("--runs", "2", "--trials", "4", "--settings", "n1_b1", "--jobs", "1")
    code, out = _invoke("paper-2d", tmp_path, *other, "--resume")
    assert code == 2, out
    assert "holds the finished runs of another sweep: the trials per run differ: 5 in the " in out
    assert "Traceback" not in out
    assert (tmp_path / "runs.partial.csv").read_bytes() == kept
    code, out = _invoke("paper-2d", tmp_path, *ARGS)  # without --resume: says how to resume
    assert code == 2, out
    assert "holds runs.partial.csv" in out and "give --resume" in out


def test_a_line_cut_short_is_dropped_with_a_warning(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    whole, resumed = tmp_path / "whole", tmp_path / "resumed"
    assert _invoke("paper-2d", whole, *ARGS)[0] == 0
    break_task(monkeypatch, Raising(), 3)
    assert _invoke("paper-2d", resumed, *ARGS)[0] == 1
    monkeypatch.undo()
    partial = resumed / "runs.partial.csv"
    data = partial.read_bytes()
    partial.write_bytes(data[:-4])  # the machine died writing the last row
    code, out = _invoke("paper-2d", resumed, *ARGS, "--resume")
    assert code == 0, out
    line = data.count(b"\n")
    assert f"warning: {partial}:{line}: the last line is cut short" in out
    assert "has 4 of 5 trials (the study stopped while writing it): dropped" in out
    assert (resumed / "runs.csv").read_bytes() == (whole / "runs.csv").read_bytes()


def test_a_study_whose_files_could_not_be_written_writes_them_resumed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import gaitpref.simulate.figures as figures

    whole, resumed = tmp_path / "whole", tmp_path / "resumed"
    assert _invoke("paper-2d", whole, *ARGS)[0] == 0
    plot = figures.plot_paper_2d

    def full(*args: object, **kwargs: object) -> None:
        raise OSError(28, "No space left on device", str(resumed / "curves.png"))

    monkeypatch.setattr(figures, "plot_paper_2d", full)
    code, out = _invoke("paper-2d", resumed, *ARGS)
    assert code == 1, out
    assert "the same command with --resume writes them" in out
    monkeypatch.setattr(figures, "plot_paper_2d", plot)
    code, out = _invoke("paper-2d", resumed, *ARGS, "--resume")
    assert code == 0, out
    for name in ("runs.csv", "curves.csv"):
        assert (resumed / name).read_bytes() == (whole / name).read_bytes(), name
    assert (resumed / "curves.png").is_file() and (resumed / "summary.md").is_file()
    assert not (resumed / "runs.partial.csv").exists()
