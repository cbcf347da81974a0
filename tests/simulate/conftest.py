from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from gaitpref.config import load_config
from gaitpref.data import paper_objectives
from gaitpref.simulate.study import Setting, Study
from gaitpref.simulate.sweep import start_ray


@pytest.fixture(scope="session")
def small_study() -> Study:
    """2 CoSpar settings (one with coactive feedback, one with n = 3) and random selection on
    3 of the paper's objectives x 2 seeds, 20 trials."""
    return Study.from_config(
        load_config("synthetic-2d"),
        [Setting("n3_b0", 3, 0), Setting("n1_b1_coactive", 1, 1, True), Setting.random()],
        np.asarray(paper_objectives()[[0, 5, 7]]),
        objective_ids=(0, 5, 7),
        seeds=(0, 1),
        trials=20,
        name="small",
    )


@pytest.fixture(scope="session")
def ray_runtime() -> Iterator[None]:
    """One local Ray runtime (2 CPUs) shared by the session's Ray tests (it takes seconds to
    start).  Ray is in the dev extra (``pip install gaitpref[ray]``): a missing Ray fails."""
    import ray

    started = start_ray(jobs=2)
    yield
    if started:
        ray.shutdown()
