"""Counts on the command line have a maximum, named with the option (``gaitpref.limits``).

A simulated run executes every trial it is asked for: ``--trials 1000000000000`` ran until the
memory was full (a random-selection arm asked NumPy for 7.28 TiB at once, after ``--out`` was
made); ``bench compass-gait --iterations 1,1000000000000`` replayed a run that long for its
posterior panels; ``--seed`` past 2**63 - 1 (what a config's and a session's seed hold) ran
silently, and so did ``random-gp:SEED``; ``--jobs`` had no maximum; ``bench population`` ran a
warm model dense in subjects x gaits whatever its size.  Each is now refused with status 2
before any trial (here a trial would fail the test: ``ask`` raises), naming the option.
"""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref.cli import app
from gaitpref.data import paper_objectives
from gaitpref.limits import (
    MAX_JOBS,
    MAX_POPULATION_NODES,
    MAX_SEED,
    MAX_SNAPSHOTS,
    MAX_STUDY_TRIALS,
    MAX_TRIALS,
    PAPER_OBJECTIVES,
)
from tests.simulate.resumekit import CONTINUOUS

#: every ask fails the test (``no_trial``, tests/conftest.py)
pytestmark = pytest.mark.usefixtures("no_trial")

HUGE = str(10**12)


def _text(output: str) -> str:
    return " ".join(output.split())  # Rich wraps long lines


@pytest.fixture
def continuous_config(tmp_path: Path) -> str:
    path = tmp_path / "cont.toml"
    path.write_text(CONTINUOUS, encoding="utf-8")
    return str(path)


def _refused(args: list[str], *expected: str) -> None:
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, (result.output, result.exception)
    text = _text(result.output)
    for part in expected:
        assert part in text, text


def _past(option: str, most: int) -> tuple[str, str]:
    """What Typer prints for ``option`` past its maximum ``most``."""
    return f"Invalid value for '{option}'", str(most)


def test_the_maxima_are_those_documented() -> None:
    assert (MAX_TRIALS, MAX_STUDY_TRIALS, MAX_SEED) == (100_000, 10_000_000, 2**63 - 1)
    assert (MAX_JOBS, MAX_SNAPSHOTS, MAX_POPULATION_NODES) == (256, 16, 10_000)


@pytest.mark.parametrize("objective", ["grid", "random-gp"])
def test_simulate_refuses_trials_past_the_maximum(grid_file: Path, objective: str) -> None:
    spec = str(grid_file) if objective == "grid" else objective
    _refused(["simulate", "synthetic-2d", "--objective", spec, "--trials", HUGE],
             *_past("--trials", MAX_TRIALS))  # fmt: skip
    _refused(["simulate", "synthetic-2d", "--objective", spec, "--trials", str(MAX_TRIALS + 1)],
             *_past("--trials", MAX_TRIALS))  # fmt: skip


@pytest.mark.parametrize("seed", [MAX_SEED + 1, 2**200])
@pytest.mark.parametrize("objective", ["grid", "random-gp"])
def test_simulate_refuses_a_seed_past_int64(grid_file: Path, objective: str, seed: int) -> None:
    """``--seed 2**200`` ran (NumPy takes any integer); a config's seed holds at most 2**63-1."""
    spec = str(grid_file) if objective == "grid" else objective
    _refused(["simulate", "synthetic-2d", "--objective", spec, "--trials", "2", "--seed",
              str(seed)], *_past("--seed", MAX_SEED))  # fmt: skip


@pytest.mark.parametrize("seed", ["9" * 20, "1" + "0" * 5000, "0" * 30 + "9" * 20])
def test_a_random_gp_seed_past_int64_is_refused(seed: str) -> None:
    """``random-gp:99999999999999999999`` ran; 5,000 digits was int()'s 'Exceeds the limit'."""
    _refused(["simulate", "synthetic-2d", "--objective", f"random-gp:{seed}", "--trials", "2"],
             "the seed after ':' must be an integer >= 0, at most", str(MAX_SEED))  # fmt: skip


def test_demo_refuses_trials_past_the_maximum(tmp_path: Path) -> None:
    _refused(["demo", "--out", str(tmp_path / "demo"), "--trials", HUGE],
             *_past("--trials", MAX_TRIALS))  # fmt: skip
    assert not (tmp_path / "demo").exists()


STUDY_OPTIONS = [
    (["--trials", HUGE], _past("--trials", MAX_TRIALS)),
    (["--seed", str(MAX_SEED + 1)], _past("--seed", MAX_SEED)),
    (["--jobs", str(MAX_JOBS + 1)], _past("--jobs", MAX_JOBS)),
]


@pytest.mark.parametrize(("option", "expected"), STUDY_OPTIONS)
@pytest.mark.parametrize("study", ["paper-2d", "compass-gait"])
def test_a_study_refuses_counts_past_their_maxima(
    tmp_path: Path, study: str, option: list[str], expected: tuple[str, str]
) -> None:
    out = tmp_path / "out"
    args = ["bench", study, "--runs", "1", "--trials", "2", "--no-baseline", "--jobs", "1",
            "--out", str(out)]  # fmt: skip
    _refused([*args, *option], *expected)  # the last of a repeated option counts
    assert not out.exists()


def test_compass_gait_refuses_iterations_past_the_maximum(tmp_path: Path) -> None:
    """``--iterations 1,10**12`` replayed a run of 10**12 iterations for its panels; 17 counts
    drew 17 panels."""
    args = ["bench", "compass-gait", "--runs", "1", "--trials", "2", "--out", str(tmp_path)]
    most = f"at most {MAX_SNAPSHOTS} counts, each at most {MAX_TRIALS}"
    _refused([*args, "--iterations", f"1,{HUGE}"], f"--iterations: {most}")
    many = ",".join(str(i) for i in range(MAX_SNAPSHOTS + 1))
    _refused([*args, "--iterations", many], f"--iterations: {most}")


def test_compass_gait_refuses_runs_x_trials_past_the_maximum_before_a_build(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Checked before ``--objective hzd`` builds its gait library (minutes) into ``--out``."""
    import gaitpref.simulate.compass

    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("a gait library was built before the counts were checked")

    monkeypatch.setattr(gaitpref.simulate.compass, "compass_objective", never)
    out = tmp_path / "out"
    runs = MAX_STUDY_TRIALS // 100 // 2 + 1
    args = ["bench", "compass-gait", "--objective", "hzd", "--runs", str(runs), "--trials",
            "100", "--out", str(out)]  # fmt: skip
    _refused(args, f"2 settings x --runs {runs} x --trials 100", f"more than {MAX_STUDY_TRIALS}")
    assert not out.exists()


def test_bench_paper_2d_refuses_runs_past_the_objectives(tmp_path: Path) -> None:
    """Run k uses objective k: more runs than the paper's objectives is refused naming the
    option (the message said ``runs must be 1..100``, not which option)."""
    assert paper_objectives().shape[0] == PAPER_OBJECTIVES
    out = tmp_path / "out"
    args = ["bench", "paper-2d", "--trials", "2", "--jobs", "1", "--out", str(out)]
    _refused([*args, "--runs", str(PAPER_OBJECTIVES + 1)], *_past("--runs", PAPER_OBJECTIVES))
    _refused([*args, "--runs", "0"], "Invalid value for '--runs'")
    assert not out.exists()


def test_bench_continuous_refuses_trials_past_the_maximum(continuous_config: str) -> None:
    args = ["bench", "continuous", continuous_config, "--objective", "random-gp", "--runs", "2"]
    _refused([*args, "--trials", HUGE], *_past("--trials", MAX_TRIALS))
    runs = MAX_STUDY_TRIALS // MAX_TRIALS + 1
    _refused([*args, "--runs", str(runs), "--trials", str(MAX_TRIALS)],
             f"--runs {runs} x --trials {MAX_TRIALS}", f"more than {MAX_STUDY_TRIALS}")  # fmt: skip


@pytest.fixture
def population_file(tmp_path: Path) -> Path:
    path = tmp_path / "population.npy"
    np.save(path, np.asarray(paper_objectives()[:3]).reshape(3, -1))
    return path


@pytest.mark.parametrize(
    ("option", "expected"),
    [
        (["--trials", HUGE], _past("--trials", MAX_TRIALS)),
        (["--seed", str(MAX_SEED + 1)], _past("--seed", MAX_SEED)),
        (["--jobs", str(MAX_JOBS + 1)], _past("--jobs", MAX_JOBS)),
    ],
)
def test_bench_population_refuses_counts_past_their_maxima(
    population_file: Path, option: list[str], expected: tuple[str, str]
) -> None:
    args = ["bench", "population", "--objectives", str(population_file), "--trials", "2"]
    _refused([*args, *option], *expected)


def test_bench_population_refuses_a_warm_model_past_its_nodes(tmp_path: Path) -> None:
    """Subjects x the gaits each run visits: a warm run's fit is dense in them."""
    subjects = MAX_POPULATION_NODES // 50 + 1
    path = tmp_path / "many.npy"
    objectives = np.asarray(paper_objectives()).reshape(100, -1)
    np.save(path, np.resize(objectives, (subjects, objectives.shape[1])))
    args = ["bench", "population", "--objectives", str(path), "--trials", "50"]
    _refused(args, f"{subjects} subjects x up to 50 gaits each (50 trials)",
             f"more than {MAX_POPULATION_NODES}")  # fmt: skip


@pytest.mark.parametrize("jobs", ["-2", "-7", str(-(10**12))])
@pytest.mark.parametrize("command", ["paper-2d", "compass-gait", "population"])
def test_jobs_below_minus_one_are_refused(
    tmp_path: Path, population_file: Path, command: str, jobs: str
) -> None:
    """``--jobs`` is a count, or -1 for every core.  Below -1 was taken as joblib counts
    (``-2``: every core but one), silently, and past the cores as 1 (``-7`` on 2 cores)."""
    out = tmp_path / "out"
    if command == "population":
        args = ["bench", "population", "--objectives", str(population_file), "--trials", "2"]
    else:
        args = ["bench", command, "--runs", "1", "--trials", "2", "--no-baseline",
                "--out", str(out)]  # fmt: skip
    _refused([*args, "--jobs", jobs], "Invalid value for '--jobs'", jobs, "-1")
    assert not out.exists()


def test_bench_continuous_refuses_before_its_progress_bar(
    continuous_config: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    main = importlib.import_module("gaitpref.cli.main")  # the package's ``main`` is a function
    bars: list[bool] = []
    real = main.progress_bar

    def counted(**settings: bool) -> object:
        bars.append(True)
        return real(**settings)

    monkeypatch.setattr(main, "progress_bar", counted)
    missing = tmp_path / "nowhere.py"
    args = ["bench", "continuous", continuous_config, "--runs", "2"]
    _refused([*args, "--objective", f"{missing}:f"], "nowhere.py")
    _refused([*args, "--objective", "random-gp", "--noise", "-1"], "noise")
    assert bars == []
