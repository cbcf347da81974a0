"""Studies as data: validation, seeding from run coordinates only, reproducibility."""

from __future__ import annotations

import dataclasses
import re
from typing import Any

import numpy as np
import pytest

from gaitpref import Feature, Space, SquaredExponential
from gaitpref.config import load_config
from gaitpref.config.schema import MAX_QUERY
from gaitpref.simulate.study import Setting, Study, run_one, run_seed_sequence
from gaitpref.simulate.sweep import resolve_jobs, run_study


@pytest.mark.parametrize(
    "kwargs",
    [
        {"name": "a", "n": 1, "buffer": 0},
        {"name": "a", "n": 0, "buffer": 1},
        {"name": "a,b", "n": 2},
        {"name": "", "n": 2},
        {"name": "r", "strategy": "random", "coactive": True},
        {"name": "x", "n": 2, "strategy": "thompson"},
        {"name": "a", "n": 2, "coactive_weight": 0.0},
    ],
)
def test_bad_settings_are_refused(kwargs: dict[str, object]) -> None:
    with pytest.raises(ValueError, match="setting"):
        Setting(**kwargs)  # type: ignore[arg-type]


def test_bad_studies_are_refused(small_study: Study) -> None:
    with pytest.raises(ValueError, match="repeat"):
        dataclasses.replace(small_study, settings=small_study.settings[:1] * 2)
    with pytest.raises(ValueError, match="K x 900"):
        dataclasses.replace(small_study, objectives=np.zeros((3, 10)))
    with pytest.raises(ValueError, match="K x 900, got none"):  # a reshape error before
        dataclasses.replace(small_study, objectives=np.zeros((0, 900)))
    with pytest.raises(ValueError, match="distinct ids"):
        dataclasses.replace(small_study, objective_ids=(0, 0, 1))
    with pytest.raises(ValueError, match="seeds"):
        dataclasses.replace(small_study, seeds=())
    with pytest.raises(ValueError, match="finite"):
        dataclasses.replace(small_study, objectives=np.full((3, 900), np.nan))


def test_tasks_are_ordered_by_setting_objective_seed(small_study: Study) -> None:
    tasks = small_study.tasks()
    assert len(tasks) == len(small_study) == 3 * 3 * 2
    coords = [(t.setting.name, t.objective_id, t.seed) for t in tasks]
    assert coords[:4] == [("n3_b0", 0, 0), ("n3_b0", 0, 1), ("n3_b0", 5, 0), ("n3_b0", 5, 1)]
    assert coords[-1] == ("random", 7, 1)
    # each task carries its own objective row
    np.testing.assert_array_equal(tasks[2].objective, small_study.objectives[1])


def test_seed_sequence_depends_on_the_coordinates_only() -> None:
    def state(*coords: Any) -> list[int]:
        out: list[int] = run_seed_sequence(*coords).generate_state(4).tolist()
        return out

    assert state(0, "n2_b0", 3, 0) == state(0, "n2_b0", 3, 0)
    others = [(1, "n2_b0", 3, 0), (0, "n3_b0", 3, 0), (0, "n2_b0", 4, 0), (0, "n2_b0", 3, 1)]
    assert all(state(*o) != state(0, "n2_b0", 3, 0) for o in others)


def test_run_one_is_pure_and_seeds_differ(small_study: Study) -> None:
    task = small_study.tasks()[0]
    a, b = run_one(task), run_one(task)
    np.testing.assert_array_equal(a.actions, b.actions)
    np.testing.assert_array_equal(a.normalized, b.normalized)
    other = run_one(small_study.tasks()[1])  # same setting and objective, seed 1
    assert not np.array_equal(a.actions, other.actions)
    assert a.actions.shape == a.normalized.shape == (20,)


def test_a_run_does_not_depend_on_the_rest_of_the_study(small_study: Study) -> None:
    full = run_study(small_study, jobs=1).table
    part = Study.from_config(
        load_config("synthetic-2d"),
        [small_study.settings[1]],
        small_study.objectives[2:],
        objective_ids=(7,),
        seeds=(1,),
        trials=20,
    )
    sub = run_study(part, jobs=1).table
    rows = (full.setting == "n1_b1_coactive") & (full.objective == 7) & (full.seed == 1)
    np.testing.assert_array_equal(sub.action, full.action[rows])
    np.testing.assert_array_equal(sub.normalized_objective, full.normalized_objective[rows])


def test_study_is_reproducible_in_process_and_on_joblib_workers(small_study: Study) -> None:
    first = run_study(small_study, jobs=1)
    again = run_study(small_study, jobs=1)
    workers = run_study(small_study, backend="joblib", jobs=2)
    assert first.table.equals(again.table)
    assert first.table.equals(workers.table)
    assert len(first.table) == len(small_study) * 20
    assert first.table.settings == ("n3_b0", "n1_b1_coactive", "random")


def test_random_baseline_draws_uniform_actions_and_scores_them(small_study: Study) -> None:
    only_random = dataclasses.replace(small_study, settings=(Setting.random(),), trials=400)
    table = run_study(only_random, jobs=1).table
    rows = table.setting == "random"
    actions = table.action[rows]
    assert actions.min() >= 0 and actions.max() < 900
    assert len(np.unique(actions)) > 900 * 0.6  # 2400 uniform draws cover most of the grid
    obj = small_study.objectives[0]
    first = rows & (table.objective == 0) & (table.seed == 0)
    expected = (obj[table.action[first]] - obj.min()) / (obj.max() - obj.min())
    np.testing.assert_allclose(table.normalized_objective[first], expected)


def test_cospar_beats_random_even_on_a_short_study(small_study: Study) -> None:
    curves = run_study(dataclasses.replace(small_study, trials=40), jobs=1).curves
    late = slice(20, 40)
    assert curves.curve("n1_b1_coactive")[1][late].mean() > curves.curve("random")[1][late].mean()


def test_resolve_jobs() -> None:
    assert resolve_jobs(3) == 3
    assert resolve_jobs(-1) >= 1 and resolve_jobs(None) == resolve_jobs(-1)
    with pytest.raises(ValueError, match="jobs"):
        resolve_jobs(0)


def test_bad_backend_is_refused(small_study: Study) -> None:
    with pytest.raises(ValueError, match="backend"):
        run_study(small_study, backend="dask")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="Ray"):
        run_study(small_study, backend="joblib", address="auto")


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"n": 1.5, "buffer": 1}, "n must be an integer, got 1.5"),  # CoSpar's, in a worker
        ({"n": True, "buffer": True}, "n must be an integer, got True"),  # ran as n = b = 1
        ({"n": 2, "buffer": "1"}, "buffer must be an integer, got '1'"),  # a TypeError
        ({"n": 2, "coactive": "no"}, "coactive must be true or false"),  # ran coactive
        ({"n": 2, "coactive_weight": float("inf")}, "coactive_weight must be a finite number"),
        ({"n": 2, "rating_quantiles": ("a",)}, "rating_quantiles must be numbers"),
    ],
)
def test_settings_of_the_wrong_type_are_refused_by_key(
    kwargs: dict[str, object], message: str
) -> None:
    with pytest.raises(ValueError, match=f"setting 's': {message}"):
        Setting("s", **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "key", "value"),
    [
        ({"n": 2, "buffer": 10**9}, "buffer", 10**9),  # kept every trial, compared with all
        ({"n": 2, "buffer": MAX_QUERY + 1}, "buffer", MAX_QUERY + 1),
        ({"n": MAX_QUERY + 1, "buffer": 0}, "n", MAX_QUERY + 1),
        ({"strategy": "random", "buffer": 10**12}, "buffer", 10**12),
    ],
)
def test_settings_take_a_config_s_bounds_on_n_and_buffer(
    kwargs: dict[str, object], key: str, value: int
) -> None:
    """n and buffer of a setting were unbounded above (a config's are at most MAX_QUERY)."""
    message = f"setting 's': {key} must be at most {MAX_QUERY} (as a config's [cospar] {key}), "
    with pytest.raises(ValueError, match=re.escape(f"{message}got {value}")):
        Setting("s", **kwargs)  # type: ignore[arg-type]


def test_settings_at_a_config_s_bounds_are_taken() -> None:
    setting = Setting("s", n=MAX_QUERY, buffer=MAX_QUERY)
    assert (setting.n, setting.buffer) == (MAX_QUERY, MAX_QUERY)


def _replaced(study: Study, **changes: Any) -> Study:
    """``dataclasses.replace`` with values of any type: a study checks them itself."""
    return dataclasses.replace(study, **changes)


def test_studies_refuse_non_integer_counts_and_an_n_past_the_grid(small_study: Study) -> None:
    """Seeds 0.5 and 1.5 were cut to 0 and 1 silently; trials 2.5 failed in a worker; an n past
    the grid failed in a worker naming no setting."""
    with pytest.raises(ValueError, match=r"seeds must be an integer, got 0\.5"):
        _replaced(small_study, seeds=(0.5, 1.5))
    with pytest.raises(ValueError, match=r"trials must be an integer, got 2\.5"):
        _replaced(small_study, trials=2.5)
    with pytest.raises(ValueError, match="objective_ids must be an integer"):
        _replaced(small_study, objective_ids=(0.0, 5, 7))
    tiny = Space([Feature("x", (0.0, 0.5, 1.0))])  # 3 actions: n up to MAX_QUERY passes them
    with pytest.raises(ValueError, match="setting 'wide': n = 4 is more actions than the grid"):
        dataclasses.replace(
            small_study,
            space=tiny,
            kernel=SquaredExponential(0.2, 0.005),
            objectives=np.zeros((3, 3)),
            settings=(Setting("wide", 4, 0),),
        )
    same = _replaced(small_study, seeds=np.arange(2), objective_ids=np.array([0, 5, 7]))
    assert same.seeds == (0, 1) and same.objective_ids == (0, 5, 7)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"noise": float("nan")}, "noise must be a number > 0 with a finite square, got nan"),
        ({"noise": 0.0}, "noise must be a number > 0"),
        ({"user_noise": -1.0}, "user_noise must be a finite number >= 0, got -1.0"),
        ({"user_noise": float("inf")}, "user_noise must be a finite number >= 0, got inf"),
        ({"user_noise": "0.1"}, "user_noise must be a finite number >= 0, got '0.1'"),
        ({"minimize": "no"}, "minimize must be true or false, got 'no'"),
        ({"seeds": 5}, "seeds must be a sequence of integers, got 5"),
    ],
)
def test_studies_refuse_noises_minimize_and_seeds_of_the_wrong_value_by_key(
    small_study: Study, changes: dict[str, object], message: str
) -> None:
    """A bad noise or user_noise was accepted and failed as every run's error ('noise must
    be ...', naming no field), minimize="no" minimized, seeds=5 was a TypeError ('int' object
    is not iterable)."""
    with pytest.raises(ValueError, match=f"study {small_study.name!r}: {message}"):
        _replaced(small_study, **changes)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"name": 5}, "setting name must be text, got 5"),  # a TypeError from 'in'
        ({"name": "s", "config": 5}, "setting 's': config must be TOML text, got 5"),
    ],
)
def test_a_setting_name_or_config_not_text_is_refused_by_key(
    kwargs: dict[str, object], message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        Setting(n=2, **kwargs)  # type: ignore[arg-type]


def test_no_more_workers_than_runs() -> None:
    """jobs = 8 for two runs started eight worker processes (a thousand for --jobs 1000)."""
    from gaitpref.data import paper_objectives

    study = Study.from_config(
        load_config("synthetic-2d"),
        [Setting.random()],
        np.asarray(paper_objectives()[[0]]).reshape(1, -1),
        seeds=(0, 1),
        trials=3,
    )
    wide = run_study(study, jobs=8)
    assert wide.jobs == 2
    assert wide.table.equals(run_study(study, jobs=1).table)


def test_a_study_holds_at_most_max_runs(small_study: Study) -> None:
    """bench compass-gait --runs 100000000 filled the memory (a MemoryError traceback under a
    limit) before its first run."""
    from typer.testing import CliRunner

    from gaitpref.cli.main import app
    from gaitpref.limits import MAX_RUNS

    with pytest.raises(ValueError, match=f"is more than {MAX_RUNS}; split it"):
        _replaced(small_study, seeds=range(MAX_RUNS))
    result = CliRunner().invoke(app, ["bench", "compass-gait", "--runs", "100000000"])
    assert result.exit_code == 2 and f"runs must be 1 to {MAX_RUNS}" in result.output
    assert _replaced(small_study, seeds=iter((0, 1))).seeds == (0, 1)


def test_the_rate_shown_when_a_study_ends_is_the_whole_studys() -> None:
    """Rich's estimate reads the last updates only: 6 runs after a 6 s start-up (Ray's), or
    runs arriving in batches, showed about 1000 runs/s; the runs a resume kept are not run."""
    from rich.progress import Progress

    from gaitpref.simulate.sweep import _RateColumn

    now = [0.0]
    bar = Progress(_RateColumn(), get_time=lambda: now[0], disable=True)
    tid = bar.add_task("study", total=10, completed=4, kept=4)
    now[0] = 6.0
    for _ in range(6):
        now[0] += 0.001
        bar.advance(tid)
    assert _RateColumn().render(bar.tasks[0]).plain == "  1.0 runs/s"  # 6 runs in 6.006 s


def test_a_setting_of_its_defaults_alone_says_why_it_is_refused() -> None:
    """Setting(name) is n = 1, buffer = 0, which compares nothing: the error gave the rule
    only, not that the defaults broke it nor what to give."""
    with pytest.raises(ValueError, match=r"got n = 1, b = 0: one gait a query .*give buffer=1"):
        Setting("mine")
    assert Setting("mine", buffer=1).buffer == 1
