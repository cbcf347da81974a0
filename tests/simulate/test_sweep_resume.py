"""A study that stopped resumes from its partial run table: the finished runs are kept, only the
others run, and the table is the one an uninterrupted study gives, bit for bit; a file of
another sweep is refused naming what differs; what a machine that died mid-write left is dropped
with a warning naming the file and line, and its run runs again."""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import numpy as np
import pytest

from gaitpref.config import load_config
from gaitpref.data import paper_objectives
from gaitpref.simulate.partial import StudyRunError
from gaitpref.simulate.resume import PartialRunsWarning, ResumeError, read_partial, write_partial
from gaitpref.simulate.study import RunTask, Setting, Study
from gaitpref.simulate.sweep import StudyResult, run_study
from gaitpref.simulate.tables import read_table
from tests.simulate.breaking import Dying, Raising
from tests.simulate.resumekit import break_task

RATING = '[feedback.rating]\nlabels = ["very bad", "bad", "okay", "good"]\n'
TRIALS = 8


def _study(**changes: object) -> Study:
    """Three settings (one rating) x two objectives x two seeds, 8 trials: 12 runs."""
    kwargs: dict[str, object] = {
        "objective_ids": (0, 5),
        "seeds": (0, 1),
        "trials": TRIALS,
        "name": "resumed",
    }
    settings = changes.pop(
        "settings",
        [
            Setting("n1_b1", 1, 1),
            Setting("rated", 2, 0, rating_quantiles=(0.25, 0.5, 0.75), config=RATING),
            Setting.random(),
        ],
    )
    kwargs.update(changes)
    return Study.from_config(
        load_config("synthetic-2d"),
        settings,  # type: ignore[arg-type]
        np.asarray(paper_objectives()[[0, 5]]),
        **kwargs,
    )


@pytest.fixture(scope="module")
def study() -> Study:
    return _study()


@pytest.fixture(scope="module")
def uninterrupted(study: Study) -> StudyResult:
    return run_study(study, jobs=1)


def _stop_at(
    study: Study, partial: Path, monkeypatch: pytest.MonkeyPatch, index: int, jobs: int = 1
) -> StudyRunError:
    """Run ``study`` (resuming when ``partial`` exists) with run ``index`` failing."""
    undo = break_task(monkeypatch, Raising(), index)
    try:
        with pytest.raises(StudyRunError) as info:
            run_study(study, jobs=jobs, partial=partial, resume=partial.exists())
    finally:
        undo()
    return info.value


def _same(result: StudyResult, uninterrupted: StudyResult) -> None:
    assert result.table.columns == uninterrupted.table.columns
    for column in result.table.columns:  # bit for bit, in the same order
        a, b = getattr(result.table, column), getattr(uninterrupted.table, column)
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), column
    assert result.curves.mean.tobytes() == uninterrupted.curves.mean.tobytes()


@pytest.mark.parametrize("jobs", [1, 2])
def test_a_resumed_study_gives_the_uninterrupted_table(
    study: Study,
    uninterrupted: StudyResult,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    jobs: int,
) -> None:
    partial = tmp_path / "runs.partial.csv"
    err = _stop_at(study, partial, monkeypatch, 7, jobs)
    kept = len(err.finished)
    assert 0 < kept < len(study) and len(read_table(partial)) == kept * TRIALS
    ran: list[RunTask] = []
    import gaitpref.simulate.sweep as sweep

    real = sweep.run_tasks

    def counting(fn: object, tasks: list[RunTask], *args: object) -> object:
        ran.extend(tasks)
        return real(fn, tasks, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(sweep, "run_tasks", counting)
    result = run_study(study, jobs=jobs, partial=partial, resume=True)
    assert len(ran) == len(study) - kept  # the kept runs did not run again
    _same(result, uninterrupted)
    assert not partial.exists()  # removed once every run finished, as without resuming


def test_a_study_stopped_twice_resumes_twice(
    study: Study, uninterrupted: StudyResult, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = tmp_path / "runs.partial.csv"
    first = _stop_at(study, partial, monkeypatch, 3)
    second = _stop_at(study, partial, monkeypatch, 9)  # resumed, then stopped again
    assert len(first.finished) == 3 and len(second.finished) == 9
    assert "9 of 12 runs finished" in str(second)
    assert len(read_table(partial)) == 9 * TRIALS
    _same(run_study(study, jobs=1, partial=partial, resume=True), uninterrupted)


def test_a_study_whose_worker_died_resumes(
    study: Study, uninterrupted: StudyResult, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = tmp_path / "runs.partial.csv"
    undo = break_task(monkeypatch, Dying(), 5)
    with pytest.raises(StudyRunError):
        run_study(study, jobs=2, partial=partial)
    undo()
    _same(run_study(study, jobs=2, partial=partial, resume=True), uninterrupted)


def test_a_last_line_cut_short_is_dropped_with_a_warning_and_its_run_runs_again(
    study: Study, uninterrupted: StudyResult, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = tmp_path / "runs.partial.csv"
    _stop_at(study, partial, monkeypatch, 6)
    data = partial.read_bytes()
    lines = data.count(b"\n")  # the signature, the header and 6 runs of 8 rows
    assert lines == 2 + 6 * TRIALS
    partial.write_bytes(data[:-7])  # the machine died in the last row
    with pytest.warns(PartialRunsWarning) as caught:
        kept = read_partial(partial, study)
    messages = [str(w.message) for w in caught]
    assert f"{partial}:{lines}: the last line is cut short" in messages[0]
    first = lines - TRIALS + 1
    assert messages[1].startswith(
        f"{partial}:lines {first}-{lines - 1}: setting 'rated', objective 0, seed 1 has 7 of 8 "
        "trials"
    )
    assert len(kept.runs) == 5 and kept.rewrite
    with pytest.warns(PartialRunsWarning):
        result = run_study(study, jobs=1, partial=partial, resume=True)
    _same(result, uninterrupted)


def test_a_last_run_cut_at_a_line_end_is_dropped_with_a_warning(
    study: Study, uninterrupted: StudyResult, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = tmp_path / "runs.partial.csv"
    _stop_at(study, partial, monkeypatch, 6)
    text = partial.read_text(encoding="utf-8")
    rows = text.splitlines(keepends=True)
    partial.write_text("".join(rows[:-3]), encoding="utf-8")  # 5 of the last run's 8 rows
    last = len(rows) - 3
    with pytest.warns(PartialRunsWarning, match=rf":lines {last - 4}-{last}: .* has 5 of 8"):
        undo = break_task(monkeypatch, Raising(), 7)  # stops again: the file is rewritten
        with pytest.raises(StudyRunError, match="7 of 12 runs finished"):
            run_study(study, jobs=1, partial=partial, resume=True)
        undo()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # none now: the file was written again without it
        assert read_partial(partial, study).runs.keys() == set(range(7))
    _same(run_study(study, jobs=1, partial=partial, resume=True), uninterrupted)


@pytest.mark.parametrize(
    ("changes", "names"),
    [
        ({"seeds": (0, 1, 2)}, "the seeds differ: [0, 1] in the file, [0, 1, 2] here"),
        ({"trials": 6}, "the trials per run differ: 8 in the file, 6 here"),
        ({"seed": 4}, "the study seed differs: 0 in the file, 4 here"),
        ({"settings": [Setting("n1_b1", 1, 2), Setting.random()]}, "the settings differ"),
        ({"user_noise": 0.1}, "the simulated subjects' noise differs: 0.0 in the file, 0.1 here"),
    ],
)
def test_a_file_of_another_sweep_is_refused_naming_what_differs(
    study: Study,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    changes: dict[str, object],
    names: str,
) -> None:
    partial = tmp_path / "runs.partial.csv"
    _stop_at(study, partial, monkeypatch, 5)
    before = partial.read_bytes()
    with pytest.raises(ResumeError) as info:
        run_study(_study(**changes), jobs=1, partial=partial, resume=True)
    text = str(info.value)
    assert text.startswith(f"{partial} holds the finished runs of another sweep: {names}")
    assert partial.read_bytes() == before  # left as it was


def test_a_setting_changed_is_named_with_its_field(
    study: Study, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = tmp_path / "runs.partial.csv"
    _stop_at(study, partial, monkeypatch, 5)
    other = _study(
        settings=[
            Setting("n1_b1", 1, 2),
            Setting("rated", 2, 0, rating_quantiles=(0.25, 0.5, 0.75), config=RATING),
            Setting.random(),
        ]
    )
    with pytest.raises(ResumeError, match="setting 'n1_b1' differs: buffer 1 in the file, 2 here"):
        run_study(other, jobs=1, partial=partial, resume=True)


def test_other_objective_values_are_refused(
    study: Study, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = tmp_path / "runs.partial.csv"
    _stop_at(study, partial, monkeypatch, 5)
    other = dataclasses.replace(study, objectives=np.asarray(paper_objectives()[[1, 5]]))
    with pytest.raises(ResumeError, match="another sweep: the objective values differ"):
        run_study(other, jobs=1, partial=partial, resume=True)


def _unsigned(partial: Path) -> None:
    """``partial`` as gaitpref 0.1.0 wrote it: no line naming the sweep."""
    text = partial.read_text(encoding="utf-8")
    assert text.startswith("# gaitpref study {")
    partial.write_text(text.partition("\n")[2], encoding="utf-8")


def test_a_file_of_the_earlier_release_resumes_checked_by_a_run(
    study: Study, uninterrupted: StudyResult, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = tmp_path / "runs.partial.csv"
    _stop_at(study, partial, monkeypatch, 6)
    _unsigned(partial)
    with pytest.warns(PartialRunsWarning, match="does not name the sweep that wrote it"):
        undo = break_task(monkeypatch, Raising(), 8)
        with pytest.raises(StudyRunError):
            run_study(study, jobs=1, partial=partial, resume=True)
        undo()
    assert partial.read_text(encoding="utf-8").startswith("# gaitpref study {")  # now signed
    _same(run_study(study, jobs=1, partial=partial, resume=True), uninterrupted)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"seed": 3}, "setting 'n1_b1', objective 0, seed 0, run again, does not give"),
        ({"seeds": (0, 2)}, "objective 0, seed 1 is not a run of this study"),
        ({"trials": 9}, "has 8 of 9 trials, and other runs follow it"),
        ({"trials": 7}, r"has trials \[1, 2, 3, 4, 5, 6, 7, 8\], this study's runs have"),
    ],
)
def test_a_file_of_the_earlier_release_from_another_sweep_is_refused(
    study: Study,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    changes: dict[str, object],
    message: str,
) -> None:
    partial = tmp_path / "runs.partial.csv"
    _stop_at(study, partial, monkeypatch, 6)
    _unsigned(partial)
    before = partial.read_bytes()
    with pytest.raises(ResumeError, match=message), warnings.catch_warnings():
        warnings.simplefilter("ignore", PartialRunsWarning)  # the check's, when it gets there
        run_study(_study(**changes), jobs=1, partial=partial, resume=True)
    assert partial.read_bytes() == before


def test_a_damaged_line_before_the_end_is_refused_naming_it(
    study: Study, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = tmp_path / "runs.partial.csv"
    _stop_at(study, partial, monkeypatch, 6)
    rows = partial.read_text(encoding="utf-8").splitlines(keepends=True)
    rows[5] = "n1_b1,0,0,4,x,0.5,0\n"
    partial.write_text("".join(rows), encoding="utf-8")
    with pytest.raises(ResumeError, match=rf"{partial}:6: not a run table's row"):
        run_study(study, jobs=1, partial=partial, resume=True)
    rows[5] = "n1_b1,0,0,4,0.5\n"
    partial.write_text("".join(rows), encoding="utf-8")
    with pytest.raises(ResumeError, match=rf"{partial}:6: 5 fields, the header has 7"):
        run_study(study, jobs=1, partial=partial, resume=True)


def test_resume_needs_the_file(study: Study, tmp_path: Path) -> None:
    partial = tmp_path / "runs.partial.csv"
    with pytest.raises(FileNotFoundError, match=f"{partial}: no such file, no finished runs"):
        run_study(study, jobs=1, partial=partial, resume=True)
    with pytest.raises(ValueError, match="resume: give the partial file"):
        run_study(study, jobs=1, resume=True)
    assert not partial.exists()


def _every_run(study: Study, uninterrupted: StudyResult, tmp_path: Path) -> Path:
    """A signed partial table holding every run of ``study``."""
    partial = tmp_path / "runs.partial.csv"
    write_partial(partial, study, uninterrupted.table)
    return partial


def test_a_file_holding_every_run_resumes_without_running_any(
    study: Study, uninterrupted: StudyResult, tmp_path: Path
) -> None:
    """What the commands keep when a study finished but its files could not be written."""
    partial = _every_run(study, uninterrupted, tmp_path)
    _same(run_study(study, jobs=1, partial=partial, resume=True), uninterrupted)
    assert not partial.exists()


def test_read_table_reads_a_signed_partial_table(
    study: Study, uninterrupted: StudyResult, tmp_path: Path
) -> None:
    partial = _every_run(study, uninterrupted, tmp_path)
    assert read_table(partial).equals(uninterrupted.table)
