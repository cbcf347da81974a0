"""The simulation API refuses counts past ``gaitpref.limits`` before any trial, naming them.

``run_simulation``, ``run_points`` and a ``Study`` ran any number of trials (10**12 until the
memory was full); a study took any runs x trials, and seeds or objective ids past int64 (the
run table's column: an OverflowError once every run had finished) and a study seed past it;
``resolve_jobs`` any count; ``posterior_snapshots`` any iteration; ``population_bench`` any
trials, seed and number of subjects; ``random-gp:SEED`` any seed.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

from gaitpref.config import load_config
from gaitpref.data import paper_objectives
from gaitpref.limits import (
    MAX_JOBS,
    MAX_POPULATION_NODES,
    MAX_SEED,
    MAX_SNAPSHOTS,
    MAX_STUDY_TRIALS,
    MAX_TRIALS,
)
from gaitpref.simulate.compass import compass_gait_study, compass_objective, posterior_snapshots
from gaitpref.simulate.continuous import objective_from
from gaitpref.simulate.points import PointUser, run_points
from gaitpref.simulate.population import population_bench
from gaitpref.simulate.run import run_simulation
from gaitpref.simulate.study import Study
from gaitpref.simulate.sweep import resolve_jobs
from gaitpref.simulate.users import SimulatedUser

#: every ask fails the test (``no_trial``, tests/conftest.py)
pytestmark = pytest.mark.usefixtures("no_trial")


def _replaced(study: Study, **changes: Any) -> Study:
    return dataclasses.replace(study, **changes)


def test_run_simulation_refuses_trials_past_the_maximum() -> None:
    config = load_config("exo-1d-step-length")
    objective = np.linspace(0.0, 1.0, len(config.space))
    user = SimulatedUser(config.space, objective, np.random.default_rng(0))
    for trials in (MAX_TRIALS + 1, 10**12):
        with pytest.raises(ValueError, match=f"trials must be .* at most {MAX_TRIALS}, got"):
            run_simulation(config.make_loop(seed=0), user, trials)


def test_run_points_refuses_trials_past_the_maximum() -> None:
    config = load_config("synthetic-2d")
    fn = objective_from("random-gp", config.space)
    user = PointUser(fn, np.random.default_rng(0))
    with pytest.raises(ValueError, match=f"trials must be 1 to {MAX_TRIALS}, got {10**12}"):
        run_points(config.make_loop(seed=0), fn, user, 10**12)


def test_a_study_refuses_trials_past_the_maximum(small_study: Study) -> None:
    with pytest.raises(ValueError, match=f"trials must be at most {MAX_TRIALS}, got {10**12}"):
        _replaced(small_study, trials=10**12)


def test_a_study_refuses_runs_x_trials_past_the_maximum(small_study: Study) -> None:
    """3 settings x 3 objectives x seeds runs; each run's trials are rows held in memory."""
    seeds = MAX_STUDY_TRIALS // (9 * MAX_TRIALS) + 1
    with pytest.raises(ValueError, match=f"is {9 * seeds * MAX_TRIALS} trials, more than"):
        _replaced(small_study, seeds=range(seeds), trials=MAX_TRIALS)
    fits = _replaced(small_study, seeds=range(seeds - 1), trials=MAX_TRIALS)
    assert len(fits) == 9 * (seeds - 1)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"seed": MAX_SEED + 1}, "seed must be at most"),
        ({"seed": 2**200}, "seed must be at most"),
        ({"seeds": (0, MAX_SEED + 1)}, "seeds must be at most"),
        ({"objective_ids": (0, 5, 2**64)}, "objective_ids must be at most"),
    ],
)
def test_a_study_refuses_seeds_and_ids_past_int64(
    small_study: Study, change: dict[str, Any], message: str
) -> None:
    """A run seed of 2**64 ran every run, then failed to make the run table (OverflowError)."""
    with pytest.raises(ValueError, match=f"{message} {MAX_SEED}, got"):
        _replaced(small_study, **change)
    at_most = {k: (MAX_SEED if k == "seed" else (*v[:-1], MAX_SEED)) for k, v in change.items()}
    assert _replaced(small_study, **at_most)  # the largest is taken


def test_resolve_jobs_refuses_more_than_the_maximum() -> None:
    assert resolve_jobs(MAX_JOBS) == MAX_JOBS
    with pytest.raises(ValueError, match=f"jobs must be at most {MAX_JOBS}"):
        resolve_jobs(MAX_JOBS + 1)
    assert resolve_jobs(-(10**12)) == 1  # joblib's count: all cores but |jobs| - 1, at least 1


@pytest.fixture
def compass_study() -> Study:
    return compass_gait_study(compass_objective("poly"), runs=1, trials=2, baseline=False)


def test_posterior_snapshots_refuse_iterations_past_the_maximum(compass_study: Study) -> None:
    with pytest.raises(ValueError, match=f"iterations must be at most {MAX_TRIALS}"):
        posterior_snapshots(compass_study, [1, 10**12])


def test_posterior_snapshots_refuse_more_panels_than_the_maximum(compass_study: Study) -> None:
    with pytest.raises(ValueError, match=f"at most {MAX_SNAPSHOTS} counts, got 17"):
        posterior_snapshots(compass_study, range(MAX_SNAPSHOTS + 1))


@pytest.fixture
def three() -> np.ndarray:
    return np.asarray(paper_objectives()[:3]).reshape(3, -1)


def test_population_bench_refuses_trials_past_the_maximum(three: np.ndarray) -> None:
    with pytest.raises(ValueError, match=f"trials must be 1 to {MAX_TRIALS}, got {10**12}"):
        population_bench(load_config("synthetic-2d"), three, 10**12)


def test_population_bench_refuses_a_seed_past_int64(three: np.ndarray) -> None:
    with pytest.raises(ValueError, match=f"seed must be 0 to {MAX_SEED}, got {2**64}"):
        population_bench(load_config("synthetic-2d"), three, 2, seed=2**64)


def test_population_bench_refuses_more_warm_nodes_than_the_maximum(three: np.ndarray) -> None:
    """synthetic-2d asks one gait a trial: subjects x 20 trials nodes in a warm run's fit."""
    subjects = MAX_POPULATION_NODES // 20 + 1
    many = np.resize(three, (subjects, three.shape[1]))
    with pytest.raises(ValueError, match=f"is {subjects * 20} \\(gait, subject\\) nodes"):
        population_bench(load_config("synthetic-2d"), many, 20)


def test_a_random_gp_seed_is_at_most_int64() -> None:
    space = load_config("synthetic-2d").space
    assert objective_from(f"random-gp:{MAX_SEED}", space) is not None
    for seed in (str(MAX_SEED + 1), "9" * 5000):
        with pytest.raises(ValueError, match=f"must be an integer >= 0, at most {MAX_SEED}"):
            objective_from(f"random-gp:{seed}", space)
