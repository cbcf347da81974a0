"""``gaitpref simulate`` refuses options its run would ignore, naming them.

``--minimize`` with an objective over points (``PATH.py:NAME``, ``hartmann6``, ``random-gp``)
ran the same maximizing subject as without it (the point path never took the option);
``--noise`` with a ``.npy`` objective (or with ``--rating-quantiles``, which evaluates the
objective over the grid) ran a noiseless subject whatever the value, ``nan`` included.  Both
now exit with status 2 naming the option, before any trial.  So does ``demo`` given a file
as its ``--out`` folder (a traceback after the whole run).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from gaitpref.cli import app

runner = CliRunner()

POINTS = "def f(x):\n    return -((x - 0.3) ** 2).sum(axis=1)\n"


@pytest.fixture
def points_spec(tmp_path: Path) -> str:
    path = tmp_path / "points.py"
    path.write_text(POINTS, encoding="utf-8")
    return f"{path}:f"


@pytest.mark.parametrize("objective", ["points", "random-gp"])
def test_minimize_with_an_objective_over_points_is_refused(
    points_spec: str, objective: str
) -> None:
    spec = points_spec if objective == "points" else objective
    args = ["simulate", "synthetic-2d", "--objective", spec, "--trials", "3", "--minimize"]
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    assert "--minimize" in result.output and "maximized" in result.output
    assert "Traceback" not in result.output
    args.remove("--minimize")
    assert runner.invoke(app, args).exit_code == 0  # and without it the run goes


@pytest.mark.parametrize("noise", ["0.1", "nan", "-1"])
def test_noise_with_a_grid_objective_is_refused(grid_file: Path, noise: str) -> None:
    args = ["simulate", "synthetic-2d", "--objective", str(grid_file), "--trials", "3"]
    result = runner.invoke(app, [*args, "--noise", noise])
    assert result.exit_code == 2, result.output
    assert "--noise" in result.output and "Traceback" not in result.output
    assert runner.invoke(app, [*args, "--noise", "0"]).exit_code == 0


@pytest.mark.parametrize("noise", ["nan", "inf", "-1"])
def test_a_bad_noise_over_points_is_refused_naming_the_option(points_spec: str, noise: str) -> None:
    """It said 'noise must be a finite number >= 0', not naming --noise."""
    args = ["simulate", "synthetic-2d", "--objective", points_spec, "--trials", "2"]
    result = runner.invoke(app, [*args, "--noise", noise])
    assert result.exit_code == 2, result.output
    assert "--noise must be a finite number >= 0" in result.output
    assert "Traceback" not in result.output


def test_noise_with_rating_quantiles_is_refused(tmp_path: Path, points_spec: str) -> None:
    """--rating-quantiles runs the grid's subject even for a function over points."""
    from gaitpref.config import load_config

    text = load_config("synthetic-2d").text + '\n[feedback.rating]\nlabels = ["bad", "good"]\n'
    config = tmp_path / "rated.toml"
    config.write_text(text, encoding="utf-8")
    args = ["simulate", str(config), "--objective", points_spec, "--trials", "3"]
    args += ["--rating-quantiles", "0.5"]
    result = runner.invoke(app, [*args, "--noise", "0.1"])
    assert result.exit_code == 2, result.output
    assert "--noise" in result.output
    assert runner.invoke(app, args).exit_code == 0
    # --minimize is taken there: the grid's subject minimizes
    assert runner.invoke(app, [*args, "--minimize"]).exit_code == 0


@pytest.mark.parametrize("below", [False, True])
def test_demo_refuses_a_file_as_its_out_folder_before_running(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, below: bool
) -> None:
    """``demo --out FILE`` ran the whole simulation, then died with a FileExistsError (or,
    for ``FILE/sub``, NotADirectoryError) traceback."""
    import importlib

    main = importlib.import_module("gaitpref.cli.main")  # the package's `main` is a function

    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("the demo ran before --out was checked")

    monkeypatch.setattr(main, "simulate_once", never)
    file = tmp_path / "taken"
    file.write_text("a file", encoding="utf-8")
    out = file / "sub" if below else file
    result = runner.invoke(app, ["demo", "--out", str(out), "--trials", "2"])
    assert result.exit_code == 2, result.output
    assert f"--out {str(out)!r}" in " ".join(result.output.split())
    assert file.read_text(encoding="utf-8") == "a file"


def test_demo_labels_the_trials_it_ran(tmp_path: Path) -> None:
    """The summary said 'trials 1-25: ..., 126-150: ...' whatever --trials was (with 30 trials,
    the means of trials 1-25 and 6-30)."""
    result = runner.invoke(app, ["demo", "--out", str(tmp_path), "--trials", "30"])
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert "mean normalized objective over trials 1-25: " in text and ", 6-30: " in text
    assert "126-150" not in text


@pytest.mark.parametrize("given", [["--rating-noise", "0.3"], ["--rating-quantiles", ""]])
def test_rating_options_without_a_rater_are_refused_over_points(
    points_spec: str, given: list[str]
) -> None:
    """With a function over points, --rating-noise without --rating-quantiles (and an empty
    --rating-quantiles) was ignored, the run made without a rater; with a .npy objective both
    were refused."""
    args = ["simulate", "synthetic-2d", "--objective", points_spec, "--trials", "2", *given]
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    assert "--rating-" in result.output and "Traceback" not in result.output


@pytest.mark.parametrize(
    ("command", "extra", "key"),
    [
        (["simulate"], "\n[stop]\nconfidence = 0.9\nsamples = 100000\n", "[stop].samples"),
        (
            ["bench", "continuous"],
            "\n[cospar.strategy_settings]\nsamples = 4096\ngates = 3\n",
            "[cospar.strategy_settings].samples",
        ),
    ],
)
def test_a_config_refused_for_a_new_run_is_named_with_its_key(
    tmp_path: Path, command: list[str], extra: str, key: str
) -> None:
    """Parse errors named the file (config 'my.toml': ...), a new run's checks only the key."""
    from gaitpref.config import load_config

    text = load_config("synthetic-6d").text
    if "strategy_settings" in extra:  # 4096 joint samples of 57,750 gaits: past the budget
        text = text.replace('strategy = "self-sparring"', 'strategy = "plausible-eubo"', 1)
    path = tmp_path / "mine.toml"
    path.write_text(text + extra, encoding="utf-8")
    result = runner.invoke(app, [*command, str(path), "--objective", "hartmann6"])
    said = " ".join(result.output.split())
    assert result.exit_code == 2 and f"mine.toml': {key}" in said, result.output
