"""The same study on a local Ray runtime gives the same tables as on joblib processes."""

from __future__ import annotations

import ray

from gaitpref.simulate.study import Study
from gaitpref.simulate.sweep import run_study


def test_ray_and_joblib_give_identical_tables(ray_runtime: None, small_study: Study) -> None:
    on_joblib = run_study(small_study, backend="joblib", jobs=2)
    on_ray = run_study(small_study, backend="ray", jobs=2)
    assert ray.is_initialized()  # the shared runtime is left running for other tests
    assert on_ray.backend == "ray"
    assert on_ray.table.equals(on_joblib.table)
    assert len(on_ray.table) == len(small_study) * small_study.trials
