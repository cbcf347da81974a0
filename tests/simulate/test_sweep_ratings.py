"""Sweeps and studies with ratings and safety settings as arms: a setting rates at quantiles of
the objective and carries ``[feedback.rating]``/``[safety]`` config text; the run table keeps the
ratings; joblib and Ray give the same tables."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitpref.config import load_config
from gaitpref.data import paper_objectives
from gaitpref.errors import ConfigError, NoSafeGaitError
from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.safety import Safety
from gaitpref.model.ordinal import Ordinal
from gaitpref.simulate.partial import StudyRunError
from gaitpref.simulate.raters import OrdinalRater
from gaitpref.simulate.run import run_simulation
from gaitpref.simulate.study import Setting, Study, run_one, run_seed_sequence
from gaitpref.simulate.sweep import run_study
from gaitpref.simulate.tables import RunTable, read_table, write_table
from gaitpref.simulate.users import SimulatedUser

LABELS = '["very bad", "bad", "okay", "good"]'
RATING = f"[feedback.rating]\nlabels = {LABELS}\n"
AVOID = RATING + '[safety]\navoid = ["very bad"]\nlambda = 1.0\n'
STRICT = RATING + '[safety]\navoid = ["very bad", "bad"]\nlambda = 0.0\n'
QUARTILES = (0.25, 0.5, 0.75)


def _study(*settings: Setting, trials: int = 20) -> Study:
    return Study.from_config(
        load_config("synthetic-2d"),
        settings,
        np.asarray(paper_objectives()[[3, 8]]),
        objective_ids=(3, 8),
        seeds=(0, 1),
        trials=trials,
        name="rated",
    )


def _truth(objective: np.ndarray) -> np.ndarray:
    obj = objective.reshape(-1)
    norm = (obj - obj.min()) / (obj.max() - obj.min())
    labels: np.ndarray = 1 + np.searchsorted(np.quantile(norm, QUARTILES), norm, side="right")
    return labels


def test_a_rating_setting_rates_every_trial_with_the_true_category() -> None:
    study = _study(Setting("rated", 1, 1, rating_quantiles=QUARTILES, config=RATING))
    for task in study.tasks():
        result = run_one(task)
        assert result.ratings is not None and result.ratings.shape == (20,)
        assert result.ratings.tolist() == _truth(task.objective)[result.actions].tolist()


def test_random_selection_rates_too() -> None:
    task = _study(
        Setting(
            "random",
            strategy="random",
            rating_quantiles=(0.5,),
            config='[feedback.rating]\nlabels = ["bad", "good"]\n',
        )
    ).tasks()[0]
    result = run_one(task)
    obj = task.objective
    norm = (obj - obj.min()) / (obj.max() - obj.min())
    assert result.ratings is not None
    assert result.ratings.tolist() == (1 + (norm[result.actions] >= np.median(norm))).tolist()


def test_settings_without_ratings_run_as_before() -> None:
    plain = _study(Setting("n1_b1", 1, 1)).tasks()[0]
    result = run_one(plain)
    assert result.ratings is None
    # the run's generators are the first two children of its seed sequence, as before ratings
    loop_ss, user_ss = run_seed_sequence(plain.study_seed, "n1_b1", 3, 0).spawn(2)
    loop = CoSpar(
        plain.space, plain.kernel, plain.noise, n=1, buffer=1, seed=np.random.default_rng(loop_ss)
    )
    user = SimulatedUser(plain.space, plain.objective, np.random.default_rng(user_ss))
    assert np.array_equal(run_simulation(loop, user, 20).actions, result.actions)


def test_the_safety_table_reaches_the_loop() -> None:
    """A setting's [safety] gives the loop the same region of avoidance as a loop built by hand
    with it, and it changes what runs (the region of avoidance is not ignored)."""
    setting = Setting("avoid", 1, 1, rating_quantiles=QUARTILES, rating_noise=0.02, config=STRICT)
    task = _study(setting, trials=30).tasks()[0]
    loop_ss, user_ss, rater_ss = run_seed_sequence(task.study_seed, "avoid", 3, 0).spawn(3)
    ordinal = Ordinal(["very bad", "bad", "okay", "good"], noise=task.noise)

    def by_hand(safety: Safety) -> np.ndarray:
        loop = CoSpar(
            task.space,
            task.kernel,
            task.noise,
            n=1,
            buffer=1,
            ordinal=ordinal,
            safety=safety,
            seed=np.random.default_rng(loop_ss),
        )
        user = SimulatedUser(task.space, task.objective, np.random.default_rng(user_ss))
        rater = OrdinalRater(
            task.space, task.objective, QUARTILES, np.random.default_rng(rater_ss), 0.02
        )
        return run_simulation(loop, user, 30, rater=rater).actions

    actions = run_one(task).actions
    assert np.array_equal(actions, by_hand(Safety(avoid=2, lam=0.0)))
    assert not np.array_equal(actions, by_hand(Safety()))


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"rating_quantiles": QUARTILES}, ValueError, "need a [feedback.rating] table with 4"),
        ({"rating_quantiles": (0.5,), "config": RATING}, ValueError, "which has 4 labels"),
        ({"rating_quantiles": (0.5, 0.2), "config": RATING}, ValueError, "must increase"),
        # one number, None or text: a TypeError naming no setting, or '0', '.', '5'
        ({"rating_quantiles": 0.5, "config": RATING}, ValueError, "a sequence of numbers"),
        ({"rating_quantiles": None}, ValueError, "a sequence of numbers, got None"),
        ({"rating_quantiles": "0.5", "config": RATING}, ValueError, "got '0.5'"),
        ({"rating_noise": 0.1}, ValueError, "rating_noise needs rating_quantiles"),
        ({"config": "[model]\nnoise = 1\n"}, ConfigError, "only [feedback.rating] and [safety]"),
        ({"config": "[safety\n"}, ConfigError, "config is not valid TOML"),
        ({"config": '[safety]\navoid = ["very bad"]\n'}, ConfigError, "[safety].avoid"),
        ({"config": RATING.replace("labels", "lables")}, ConfigError, "[feedback.rating]"),
        # risk or lambda without avoid: no region, the key ignored (a new session refuses it)
        ({"config": RATING + "[safety]\nrisk = 0.4\n"}, ConfigError, "[safety].risk: is a"),
        ({"config": RATING + "[safety]\nlambda = 1.0\n"}, ConfigError, "lambda = 1.0 would"),
        # a simulated subject flags no trial unsafe: the radius around a flag did nothing
        (
            {"config": AVOID + "unsafe_radius = 0.1\n", "rating_quantiles": QUARTILES},
            ConfigError,
            "[safety].unsafe_radius: is the neighbourhood kept away from a trial flagged unsafe",
        ),
        (
            {"config": "[safety]\nunsafe_radius = 0.0\n"},
            ConfigError,
            "a simulated subject never flags a trial, so it would do nothing",
        ),
        (
            {"config": "[safety]\nunsafe_radius = 0.2\n", "strategy": "random"},
            ConfigError,
            "(unsafe_radius = 0.2); leave it out",
        ),
    ],
)
def test_bad_rating_settings_are_refused_naming_the_setting(
    kwargs: dict[str, object], error: type[Exception], message: str
) -> None:
    with pytest.raises(error, match="setting 'arm'") as info:
        Setting("arm", 1, 1, **kwargs)  # type: ignore[arg-type]
    assert message in str(info.value)


def test_a_run_left_without_a_safe_gait_fails_naming_the_run() -> None:
    study = _study(Setting("strict", 1, 1, rating_quantiles=QUARTILES, config=STRICT), trials=40)
    with pytest.raises(StudyRunError, match=r"setting 'strict', objective 3, seed 0 failed") as e:
        run_study(study, jobs=1)
    assert isinstance(e.value.__cause__, NoSafeGaitError)
    assert "(NoSafeGaitError): no gait may be proposed" in str(e.value)
    assert (e.value.setting, e.value.objective_id, e.value.seed) == ("strict", 3, 0)


def test_random_selection_takes_no_region_of_avoidance() -> None:
    with pytest.raises(ValueError, match="random selection takes no"):
        Setting("r", strategy="random", config=AVOID)


def test_a_setting_s_start_gaits_are_walked_first_and_checked_on_the_study_s_grid() -> None:
    """[safety] start in a setting's config names gaits of the study's grid (by action index or
    feature values): walked first, as a config's.  It was refused by every setting as on the
    line path ('the line path (subspace = 'line') has none'), the setting having no grid."""
    space = load_config("synthetic-2d").space
    at = space.points_of([7])[0]
    pairs = zip(space.features, at, strict=True)
    by_values = ", ".join(f"{f.name} = {float(v)!r}" for f, v in pairs)
    for start in ("[7]", f"[{{{by_values}}}]"):
        setting = Setting(
            "start", 1, 1, rating_quantiles=QUARTILES, config=AVOID + f"start = {start}\n"
        )
        for task in _study(setting, trials=3).tasks():
            assert run_one(task).actions[0] == 7
    with pytest.raises(ConfigError, match=r"setting 'start': \[safety\].start: gait 1 \(10000\)"):
        _study(Setting("start", 1, 1, config=AVOID + "start = [10000]\n"))
    with pytest.raises(ValueError, match="random selection takes no"):
        Setting("r", strategy="random", config=RATING + "[safety]\nstart = [7]\n")


def _rated_study() -> Study:
    return _study(
        Setting("plain", 1, 1),
        Setting("rated", 1, 1, rating_quantiles=QUARTILES, rating_noise=0.05, config=RATING),
        Setting("avoid", 1, 1, rating_quantiles=QUARTILES, config=AVOID),
        trials=12,
    )


def test_the_run_table_has_the_ratings_and_files_keep_them(tmp_path: Path) -> None:
    result = run_study(_rated_study(), jobs=1)
    table = result.table
    assert table.columns[-1] == "rating" and table.rating is not None
    assert np.all(table.ratings("plain") == 0)  # not rated
    assert set(np.unique(table.ratings("rated"))) <= {1, 2, 3, 4}
    assert table.ratings("avoid").shape == (4, 12) and np.all(table.ratings("avoid") >= 1)
    for name in ("runs.csv", "runs.csv.gz", "runs.parquet"):
        back = read_table(write_table(table, tmp_path / name))
        assert back.equals(table) and back.rating is not None


def test_tables_without_ratings_are_unchanged(tmp_path: Path) -> None:
    plain = run_study(_study(Setting("plain", 1, 1), trials=5), jobs=1).table
    assert plain.rating is None and "rating" not in plain.columns
    path = write_table(plain, tmp_path / "runs.csv")
    assert path.read_text().splitlines()[0] == (
        "setting,objective,seed,trial,action,normalized_objective"
    )
    assert read_table(path).rating is None
    with pytest.raises(KeyError, match="no ratings"):
        plain.ratings("plain")
    rated = run_study(_rated_study(), jobs=1).table
    both = RunTable.concat([plain, rated])
    assert both.rating is not None and np.all(both.rating[: len(plain)] == 0)
    assert not both.equals(plain) and not plain.equals(RunTable.concat([plain, plain]))


def test_joblib_and_ray_give_identical_rated_tables(ray_runtime: None) -> None:
    study = _rated_study()
    alone = run_study(study, jobs=1).table
    assert run_study(study, backend="joblib", jobs=2).table.equals(alone)
    assert run_study(study, backend="ray", jobs=2).table.equals(alone)
