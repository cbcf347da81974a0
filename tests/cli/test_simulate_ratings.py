"""``gaitpref simulate --rating-quantiles``: a simulated subject rates every executed gait."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref.cli import app
from gaitpref.config import load_config
from gaitpref.data import paper_objectives

runner = CliRunner()
LABELS = '["very bad", "bad", "okay", "good"]'


def _config(tmp_path: Path, extra: str) -> Path:
    path = tmp_path / "rated.toml"
    path.write_text(load_config("synthetic-2d").text + "\n" + extra, encoding="utf-8")
    return path


@pytest.fixture
def objective_file(tmp_path: Path) -> Path:
    path = tmp_path / "objective.npy"
    np.save(path, paper_objectives()[7])
    return path


def _run(config: Path, objective: Path, *extra: str) -> tuple[int, str, str]:
    args = ["simulate", str(config), "--objective", str(objective), "--trials", "16"]
    result = runner.invoke(app, [*args, "--seed", "4", *extra])
    return result.exit_code, result.stdout, result.stderr


def test_json_gives_the_executed_actions_and_their_true_ratings(
    tmp_path: Path, objective_file: Path
) -> None:
    cfg = _config(tmp_path, f"[feedback.rating]\nlabels = {LABELS}\n")
    code, out, err = _run(cfg, objective_file, "--rating-quantiles", "0.25,0.5,0.75", "--json")
    assert code == 0, err
    payload = json.loads(out)
    for key in ("config", "seed", "seconds", "trials", "actions", "normalized_objective"):
        assert key in payload  # every field of a run without ratings is kept
    actions, ratings = payload["actions"], payload["ratings"]
    assert len(actions) == len(ratings) == 16
    # a noiseless rater gives the true quartile of the executed gait's objective
    obj = paper_objectives()[7].reshape(-1)
    norm = (obj - obj.min()) / (obj.max() - obj.min())
    truth = 1 + np.searchsorted(np.quantile(norm, [0.25, 0.5, 0.75]), norm[actions], "right")
    assert ratings == truth.tolist()
    rerun = _run(cfg, objective_file, "--rating-quantiles", "0.25,0.5,0.75", "--json")
    again = json.loads(rerun[1])
    assert again["actions"] == actions and again["ratings"] == ratings


def test_rating_noise_changes_some_ratings_and_stays_seeded(
    tmp_path: Path, objective_file: Path
) -> None:
    cfg = _config(tmp_path, '[feedback.rating]\nlabels = ["bad", "good"]\n')
    args = ("--rating-quantiles", "0.5", "--json")
    clean = json.loads(_run(cfg, objective_file, *args)[1])
    noisy = [json.loads(_run(cfg, objective_file, *args, "--rating-noise", "0.5")[1])]
    noisy.append(json.loads(_run(cfg, objective_file, *args, "--rating-noise", "0.5")[1]))
    assert noisy[0] == {**noisy[1], "seconds": noisy[0]["seconds"]}
    obj = paper_objectives()[7].reshape(-1)
    norm = (obj - obj.min()) / (obj.max() - obj.min())
    median = np.quantile(norm, 0.5)
    assert clean["ratings"] == (1 + (norm[clean["actions"]] >= median)).tolist()
    truth = 1 + (norm[noisy[0]["actions"]] >= median)
    assert set(noisy[0]["ratings"]) <= {1, 2}
    assert noisy[0]["ratings"] != truth.tolist()  # noise 0.5 on a 0..1 scale flips some


def test_no_ratings_without_the_option(tmp_path: Path, objective_file: Path) -> None:
    cfg = _config(tmp_path, f"[feedback.rating]\nlabels = {LABELS}\n")
    code, out, _ = _run(cfg, objective_file, "--json")
    assert code == 0 and "ratings" not in json.loads(out)


def test_the_human_output_counts_the_ratings(tmp_path: Path, objective_file: Path) -> None:
    cfg = _config(tmp_path, f"[feedback.rating]\nlabels = {LABELS}\n")
    code, out, err = _run(cfg, objective_file, "--rating-quantiles", "0.25,0.5,0.75")
    assert code == 0, err
    assert "ratings given:" in out and "'very bad'" in out and "'good'" in out


@pytest.mark.parametrize(
    ("extra", "options", "message"),
    [
        ("", ["--rating-quantiles", "0.5"], "has no [feedback.rating] table"),
        (
            f"[feedback.rating]\nlabels = {LABELS}\n",
            ["--rating-quantiles", "0.3,0.6"],
            "2 quantiles make 3 categories, but [feedback.rating]",
        ),
        (
            f"[feedback.rating]\nlabels = {LABELS}\n",
            ["--rating-quantiles", "0.5,0.25,0.75"],
            "must increase strictly inside (0, 1)",
        ),
        (
            f"[feedback.rating]\nlabels = {LABELS}\n",
            ["--rating-quantiles", "a,b,c"],
            "comma-separated numbers",
        ),
        (  # an empty entry was skipped: "0.25,,0.75" gave 2 quantiles (refused as 3 labels'
            # worth with 4, taken with 3)
            '[feedback.rating]\nlabels = ["bad", "okay", "good"]\n',
            ["--rating-quantiles", "0.25,,0.75"],
            "--rating-quantiles must be comma-separated numbers, got '0.25,,0.75'",
        ),
        (f"[feedback.rating]\nlabels = {LABELS}\n", ["--rating-noise", "0.1"], "needs"),
        (
            f"[feedback.rating]\nlabels = {LABELS}\n",
            ["--rating-quantiles", "0.25,0.5,0.75", "--rating-noise", "-1"],
            "--rating-noise must be a number >= 0",
        ),
    ],
)
def test_errors_name_the_problem(
    tmp_path: Path, objective_file: Path, extra: str, options: list[str], message: str
) -> None:
    code, _, err = _run(_config(tmp_path, extra), objective_file, *options, "--json")
    assert code == 2
    assert message in " ".join(err.split())


def test_a_function_of_points_is_rated_over_the_grid_like_its_npy(tmp_path: Path) -> None:
    """``--objective PATH.py:NAME`` with ratings on a grid config: the function is evaluated at
    the grid's points, and the run is the one its ``.npy`` gives."""
    module = tmp_path / "bowl.py"
    module.write_text(
        "import numpy as np\n\n"
        "def f(x):\n"
        "    x = np.asarray(x)\n"
        "    return -((x[:, 0] - 0.3) ** 2) - 0.5 * (x[:, 1] - 0.7) ** 2\n",
        encoding="utf-8",
    )
    cfg = _config(tmp_path, f"[feedback.rating]\nlabels = {LABELS}\n")
    space = load_config(str(cfg)).space
    pts = space.points
    grid = -((pts[:, 0] - 0.3) ** 2) - 0.5 * (pts[:, 1] - 0.7) ** 2
    npy = tmp_path / "bowl.npy"
    np.save(npy, grid.reshape(tuple(len(f) for f in space.features)))
    rate = ("--rating-quantiles", "0.25,0.5,0.75", "--json")
    code, out, err = _run(cfg, Path(f"{module}:f"), *rate)
    assert code == 0, err
    code_npy, out_npy, err_npy = _run(cfg, npy, *rate)
    assert code_npy == 0, err_npy
    by_fn, by_npy = json.loads(out), json.loads(out_npy)
    assert by_fn["actions"] == by_npy["actions"] and by_fn["ratings"] == by_npy["ratings"]
    assert len(set(by_fn["ratings"])) > 1  # the quartiles split the executed gaits


def test_ratings_on_the_line_path_are_refused_by_name(tmp_path: Path) -> None:
    args = ["simulate", "compass-continuous-3d", "--objective", "hartmann6", "--trials", "3"]
    result = runner.invoke(app, [*args, "--rating-quantiles", "0.25,0.5,0.75"])
    assert result.exit_code == 2
    assert "--rating-quantiles: config 'compass-continuous-3d' runs on the line path" in " ".join(
        result.stderr.split()
    )


def test_with_minimize_the_worst_rating_is_the_highest_cost(
    tmp_path: Path, objective_file: Path
) -> None:
    """--minimize: the objective is a cost, so category 1 (the worst) holds its highest values."""
    cfg = _config(tmp_path, f"[feedback.rating]\nlabels = {LABELS}\n")
    args = ("--rating-quantiles", "0.25,0.5,0.75", "--minimize", "--json")
    code, out, err = _run(cfg, objective_file, *args)
    assert code == 0, err
    payload = json.loads(out)
    obj = paper_objectives()[7].reshape(-1)
    norm = (obj.max() - obj) / (obj.max() - obj.min())
    truth = 1 + np.searchsorted(np.quantile(norm, [0.25, 0.5, 0.75]), norm, "right")
    assert payload["ratings"] == truth[payload["actions"]].tolist()
    assert set(np.flatnonzero(truth == 1)) == set(np.argsort(obj)[-int((truth == 1).sum()) :])


def test_a_region_of_avoidance_left_without_a_gait_is_an_error_line(
    tmp_path: Path, objective_file: Path
) -> None:
    """No gait left to propose stops the run with the error and the trial it reached (it was a
    traceback of NoSafeGaitError)."""
    strict = '[safety]\navoid = ["very bad", "bad"]\nlambda = 0.0\n'
    cfg = _config(tmp_path, f"[feedback.rating]\nlabels = {LABELS}\n{strict}")
    args = ("--rating-quantiles", "0.25,0.5,0.75", "--trials", "40", "--json")
    code, out, err = _run(cfg, objective_file, *args)
    assert code == 1 and out == ""
    assert "Traceback" not in err
    message = " ".join(err.split())
    assert message.startswith("model error: the simulation stopped after ")
    assert "of 40 trials: no gait may be proposed" in message
