"""The same study on a local Ray runtime gives the same tables as on joblib processes."""

from __future__ import annotations

from pathlib import Path

import pytest
import ray

from gaitpref.simulate.study import RunResult, Study
from gaitpref.simulate.sweep import run_study


def test_ray_and_joblib_give_identical_tables(ray_runtime: None, small_study: Study) -> None:
    on_joblib = run_study(small_study, backend="joblib", jobs=2)
    on_ray = run_study(small_study, backend="ray", jobs=2)
    assert ray.is_initialized()  # the shared runtime is left running for other tests
    assert on_ray.backend == "ray"
    assert on_ray.table.equals(on_joblib.table)
    assert len(on_ray.table) == len(small_study) * small_study.trials


def test_a_failed_run_raises_its_own_error_as_on_joblib(ray_runtime: None) -> None:
    """Ray wrapped it in a RayTaskError whose text is the remote traceback (ANSI colours and
    file lines in the CLI's 'model error: ...'): the study's error names the run and has the
    run's own error as its cause, as on joblib."""
    from gaitpref.errors import NoSafeGaitError
    from gaitpref.simulate.partial import StudyRunError
    from gaitpref.simulate.study import Setting
    from tests.simulate.test_sweep_ratings import QUARTILES, STRICT, _study

    study = _study(Setting("strict", 1, 1, rating_quantiles=QUARTILES, config=STRICT), trials=40)
    with pytest.raises(StudyRunError) as info:
        run_study(study, backend="ray", jobs=2)
    assert type(info.value.__cause__) is NoSafeGaitError
    assert str(info.value).startswith(
        "setting 'strict', objective 3, seed 0 failed (NoSafeGaitError): no gait"
    )


def test_a_run_whose_worker_dies_is_named_and_the_finished_runs_kept(
    ray_runtime: None, small_study: Study, monkeypatch: pytest.MonkeyPatch
) -> None:
    from gaitpref.simulate.partial import StudyRunError
    from tests.simulate.breaking import Dying
    from tests.simulate.test_sweep_failures import _tasks_with

    last = len(small_study) - 1  # random selection, objective 7, seed 1
    monkeypatch.setattr(Study, "tasks", _tasks_with(Study.tasks, Dying(), last))
    with pytest.raises(StudyRunError) as info:
        run_study(small_study, backend="ray", jobs=2)
    err = info.value
    assert (err.setting, err.objective_id, err.seed) == ("random", 7, 1)
    assert "the worker running it died" in str(err)
    assert ray.is_initialized()  # the shared runtime is left running
    monkeypatch.undo()
    clean = {(r.setting, r.objective_id, r.seed): r for r in _runs(small_study)}
    for r in err.finished:  # those that finished before it, as they run in a clean study
        assert (r.actions == clean[(r.setting, r.objective_id, r.seed)].actions).all()


def _runs(study: Study) -> list[RunResult]:
    from gaitpref.simulate.study import run_one

    return [run_one(t) for t in study.tasks()]


def test_an_address_where_nothing_listens_is_refused_at_once(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """ray.init retried HOST:PORT with no cluster for minutes, Ray's warnings the only output."""
    import socket

    from gaitpref.simulate.sweep import start_ray

    with socket.socket() as free:  # a port nothing listens on once closed
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]

    def init(*args: object, **kwargs: object) -> None:
        raise AssertionError("ray.init was called: it retries for minutes")

    monkeypatch.setattr(ray, "is_initialized", lambda: False)
    monkeypatch.setattr(ray, "init", init)
    with pytest.raises(RuntimeError, match="nothing answers there"):
        start_ray(f"127.0.0.1:{port}")


def test_a_study_stopped_on_joblib_resumes_on_ray_with_the_same_table(
    ray_runtime: None, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Runs are seeded by their coordinates only: where the rest run does not matter."""
    from gaitpref.simulate.partial import StudyRunError
    from tests.simulate.breaking import Raising
    from tests.simulate.resumekit import break_task
    from tests.simulate.test_sweep_resume import _same, _study

    study = _study()
    whole = run_study(study, backend="joblib", jobs=1)
    partial = tmp_path / "runs.partial.csv"
    undo = break_task(monkeypatch, Raising(), 5)
    with pytest.raises(StudyRunError):
        run_study(study, backend="joblib", jobs=1, partial=partial)
    undo()
    _same(run_study(study, backend="ray", jobs=2, partial=partial, resume=True), whole)
    assert not partial.exists()
