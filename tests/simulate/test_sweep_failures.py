"""A study whose run fails stops naming that run (setting, objective, seed) and keeps the runs
that finished: on the error, and in the ``partial`` run table written as each run finished."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref.config import load_config
from gaitpref.data import paper_objectives
from gaitpref.simulate.partial import StudyRunError
from gaitpref.simulate.study import RunResult, RunTask, Setting, Study
from gaitpref.simulate.sweep import run_study
from gaitpref.simulate.tables import read_table
from tests.simulate.breaking import Dying, Raising

BROKEN = 6  # the run that breaks: setting 'random', objective 5, seed 0


@pytest.fixture(scope="module")
def study() -> Study:
    """Two settings x two objectives x two seeds, 8 trials: 8 runs."""
    return Study.from_config(
        load_config("synthetic-2d"),
        [Setting("n1_b1", 1, 1), Setting.random()],
        np.asarray(paper_objectives()[[0, 5]]),
        objective_ids=(0, 5),
        seeds=(0, 1),
        trials=8,
        name="breaks",
    )


@pytest.fixture(scope="module")
def clean(study: Study) -> dict[tuple[str, int, int], RunResult]:
    """Every run of the study as it runs when none breaks."""
    from gaitpref.simulate.study import run_one

    return {(t.setting.name, t.objective_id, t.seed): run_one(t) for t in study.tasks()}


def _check_finished(
    err: StudyRunError, clean: dict[tuple[str, int, int], RunResult], partial: Path
) -> None:
    """The finished runs are the clean study's, on the error and in the partial table."""
    assert err.finished, "runs finished before the broken one"
    keys = [(r.setting, r.objective_id, r.seed) for r in err.finished]
    assert ("random", 5, 0) not in keys and len(set(keys)) == len(keys)
    for r in err.finished:
        want = clean[(r.setting, r.objective_id, r.seed)]
        np.testing.assert_array_equal(r.actions, want.actions)
        np.testing.assert_array_equal(r.normalized, want.normalized)
    assert err.partial == partial
    table, written = err.table(), read_table(partial)
    assert table is not None and len(written) == len(table) == len(err.finished) * 8
    order = np.lexsort((written.trial, written.seed, written.objective, written.setting))
    mine = np.lexsort((table.trial, table.seed, table.objective, table.setting))
    for column in table.columns:
        np.testing.assert_array_equal(getattr(written, column)[order], getattr(table, column)[mine])


@pytest.mark.parametrize("jobs", [1, 2])
def test_a_run_that_raises_is_named_and_the_finished_runs_are_kept(
    study: Study,
    clean: dict[tuple[str, int, int], RunResult],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    jobs: int,
) -> None:
    monkeypatch.setattr(Study, "tasks", _tasks_with(Study.tasks, Raising()))
    partial = tmp_path / "runs.partial.csv"
    with pytest.raises(StudyRunError) as info:
        run_study(study, jobs=jobs, partial=partial)
    err = info.value
    assert (err.setting, err.objective_id, err.seed) == ("random", 5, 0)
    assert isinstance(err.__cause__, ValueError)
    text = str(err)
    assert "setting 'random', objective 5, seed 0 failed (ValueError): the objective broke" in text
    assert f"of 8 runs finished; their results are in {partial}" in text
    _check_finished(err, clean, partial)
    if jobs == 1:  # in study order: the six before it
        assert [(r.setting, r.objective_id, r.seed) for r in err.finished] == list(clean)[:BROKEN]


def test_a_worker_that_dies_names_the_runs_it_may_have_run_and_keeps_the_others(
    study: Study,
    clean: dict[tuple[str, int, int], RunResult],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(Study, "tasks", _tasks_with(Study.tasks, Dying()))
    partial = tmp_path / "runs.partial.csv"
    with pytest.raises(StudyRunError) as info:
        run_study(study, jobs=2, partial=partial)
    err = info.value
    assert ("random", 5, 0) in err.candidates  # among the runs in progress when it died
    assert "setting 'random', objective 5, seed 0" in str(err) and "died" in str(err)
    assert "TerminatedWorkerError" in str(err)
    _check_finished(err, clean, partial)


def test_without_a_partial_file_the_finished_runs_are_on_the_error(
    study: Study, clean: dict[tuple[str, int, int], RunResult], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(Study, "tasks", _tasks_with(Study.tasks, Raising()))
    with pytest.raises(StudyRunError, match=r"6 of 8 runs finished; .*StudyRunError\.finished"):
        run_study(study, jobs=1)


def test_a_study_that_finishes_leaves_no_partial_file(study: Study, tmp_path: Path) -> None:
    partial = tmp_path / "runs.partial.csv"
    result = run_study(study, jobs=1, partial=partial)
    assert not partial.exists()
    assert result.table.equals(run_study(study, jobs=1).table)


def test_the_cli_names_the_failed_run_and_keeps_the_finished_ones(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from gaitpref.cli import app

    monkeypatch.setattr(Study, "tasks", _tasks_with(Study.tasks, Raising(), 3))
    args = ["bench", "paper-2d", "--runs", "2", "--trials", "6", "--settings", "n1_b1"]
    result = CliRunner().invoke(app, [*args, "--jobs", "1", "--out", str(tmp_path)])
    assert result.exit_code == 1, result.output
    text = " ".join(result.output.split())  # Rich wraps long lines
    assert "setting 'random', objective 1, seed 0 failed (ValueError): the objective" in text
    assert "3 of 4 runs finished; their results are in" in text and "runs.partial.csv" in text
    table = read_table(tmp_path / "runs.partial.csv")
    assert len(table) == 3 * 6  # the three runs before it
    assert not (tmp_path / "runs.csv").exists() and not (tmp_path / "curves.csv").exists()
    monkeypatch.undo()
    again = CliRunner().invoke(app, [*args, "--jobs", "1", "--out", str(tmp_path)])
    assert again.exit_code == 2, again.output  # the kept runs are not written over
    assert "holds runs.partial.csv" in " ".join(again.output.split())
    assert read_table(tmp_path / "runs.partial.csv").equals(table)
    (tmp_path / "runs.partial.csv").rename(tmp_path / "earlier.csv")
    ok = CliRunner().invoke(app, [*args, "--jobs", "1", "--out", str(tmp_path)])
    assert ok.exit_code == 0, ok.output
    assert not (tmp_path / "runs.partial.csv").exists()  # a study that finished: its tables
    assert (tmp_path / "runs.csv").exists()


@pytest.mark.parametrize("command", ["paper-2d", "compass-gait"])
def test_a_partial_table_left_in_out_is_not_written_over(tmp_path: Path, command: str) -> None:
    """``OUT/runs.partial.csv`` holds the finished runs of a study that stopped: a new study
    into that folder truncated it as it started and removed it when it finished (or when it was
    interrupted before any run finished), the earlier runs lost.  Refused before any run."""
    from gaitpref.cli import app

    kept = tmp_path / "runs.partial.csv"
    kept.write_text("setting,objective\nearlier,1\n", encoding="utf-8")
    args = ["bench", command, "--runs", "1", "--trials", "3", "--jobs", "1", "--out", str(tmp_path)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    text = " ".join(result.output.split())
    assert f"--out '{tmp_path}' holds runs.partial.csv" in text and "Traceback" not in text
    assert kept.read_text(encoding="utf-8") == "setting,objective\nearlier,1\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["runs.partial.csv"]


def test_run_study_refuses_a_partial_file_that_exists(study: Study, tmp_path: Path) -> None:
    """``run_study(partial=...)`` opened the file for writing: an existing one was truncated."""
    kept = tmp_path / "runs.partial.csv"
    kept.write_text("earlier runs\n", encoding="utf-8")
    with pytest.raises(FileExistsError, match=r"already exists .* would be written over"):
        run_study(study, jobs=1, partial=kept)
    assert kept.read_text(encoding="utf-8") == "earlier runs\n"


def _tasks_with(tasks: object, objective: object, index: int = BROKEN) -> object:
    """``Study.tasks`` with run ``index``'s objective replaced by ``objective``."""

    def broken(self: Study) -> list[RunTask]:
        out: list[RunTask] = tasks(self)  # type: ignore[operator]
        out[index] = dataclasses.replace(out[index], objective=objective)  # type: ignore[arg-type]
        return out

    return broken


class _Interrupting:
    """An objective whose reading is interrupted (Ctrl-C while its run runs)."""

    def __array__(self, dtype: object = None, copy: object = None) -> object:
        raise KeyboardInterrupt


def test_an_interrupted_study_says_where_the_finished_runs_are(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C kept OUT/runs.partial.csv but said nothing (a bench's file is a new name in the
    temporary folder): status 130 and the file named."""
    from gaitpref.cli import app

    monkeypatch.setattr(Study, "tasks", _tasks_with(Study.tasks, _Interrupting(), 2))
    args = ["bench", "paper-2d", "--runs", "2", "--trials", "4", "--settings", "n1_b1"]
    result = CliRunner().invoke(app, [*args, "--jobs", "1", "--out", str(tmp_path)])
    assert result.exit_code == 130, result.output
    kept = tmp_path / "runs.partial.csv"
    assert f"interrupted; the runs that finished are in {kept}" in " ".join(result.output.split())
    assert len(read_table(kept)) == 2 * 4  # the two runs before it
