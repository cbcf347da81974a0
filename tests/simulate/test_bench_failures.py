"""``gaitpref bench continuous`` and ``bench population`` keep their finished runs when one
fails, as a study does (``simulate/partial.py``): the error names the run (objective or
subject, and seed) and its cause, the finished runs are in the ``--partial`` file it names
(JSON lines, one a run), and the status is 1.  Before, a failure lost every finished run."""

from __future__ import annotations

import json
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref.cli import app
from gaitpref.config import load_config
from gaitpref.simulate.partial import RunError, RunFailure
from gaitpref.simulate.population import population_bench
from gaitpref.simulate.sweep import run_tasks
from tests.simulate.breaking import fails_at_three
from tests.simulate.resumekit import (
    POPULATION,
    break_seed,
    break_subject,
    continuous_bench,
    population_objectives,
)


def _text(output: str) -> str:
    return " ".join(output.split())  # Rich wraps long lines


def _lines(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text(encoding="utf-8").splitlines()]


@pytest.mark.parametrize("jobs", [1, 2])
def test_run_tasks_returns_the_finished_runs_and_the_first_failure(jobs: int) -> None:
    seen: list[int] = []
    results, failure = run_tasks(
        fails_at_three, [0, 1, 2, 3, 4, 5], jobs, done=lambda i, r: seen.append(i)
    )
    assert isinstance(failure, RunFailure) and failure.indices == (3,)
    assert isinstance(failure.error, ValueError) and str(failure.error) == "three broke"
    finished = [i for i, r in enumerate(results) if r is not None]
    assert results[3] is None and sorted(seen) == finished
    assert all(r == i * i for i, r in enumerate(results) if r is not None)
    if jobs == 1:  # in order: the three before it, none after
        assert results == [0, 1, 4, None, None, None]
    assert run_tasks(fails_at_three, [0, 1, 2], jobs) == ([0, 1, 4], None)


# -- bench continuous ---------------------------------------------------------------------


@pytest.fixture()
def continuous_args(tmp_path: Path) -> list[str]:
    return continuous_bench(tmp_path)


def test_bench_continuous_names_the_failed_run_and_keeps_the_finished_ones(
    continuous_args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    clean = CliRunner().invoke(app, [*continuous_args, "--json"])
    assert clean.exit_code == 0, clean.output
    runs = json.loads(clean.stdout)["runs"]
    break_seed(monkeypatch, 2)
    partial = tmp_path / "kept.jsonl"
    result = CliRunner().invoke(app, [*continuous_args, "--json", "--partial", str(partial)])
    assert result.exit_code == 1, result.output
    assert isinstance(result.exception, SystemExit)  # an error, not a traceback
    assert result.stdout == ""  # no JSON of a bench that did not finish
    text = _text(result.stderr)
    obj = continuous_args[4]
    assert f"objective {obj!r}, seed 2 failed (ValueError): the treadmill stopped" in text
    assert f"2 of 4 runs finished; their results are in {partial}" in text
    first, *kept = _lines(partial)
    assert first["gaitpref bench"]["bench"] == "continuous"  # the bench that wrote it
    assert kept == runs[:2]  # the runs before it, as the JSON gives them
    documented = ["seed", "trials", "points", "objective", "best_point", "best_objective"]
    assert list(runs[0]) == documented  # docs/sweeps.md's line (it left out trials)


def test_bench_continuous_keeps_them_in_a_temporary_file_by_default(
    continuous_args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = tmp_path / "tmp"
    folder.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(folder))
    ok = CliRunner().invoke(app, continuous_args)
    assert ok.exit_code == 0, ok.output
    assert list(folder.iterdir()) == []  # a bench that finished keeps no partial file
    break_seed(monkeypatch, 1)
    result = CliRunner().invoke(app, continuous_args)
    assert result.exit_code == 1, result.output
    (kept,) = folder.iterdir()
    assert kept.name.startswith("gaitpref-bench-continuous-") and kept.suffix == ".jsonl"
    assert f"1 of 4 runs finished; their results are in {kept}" in _text(result.stderr)
    assert [r["seed"] for r in _lines(kept)[1:]] == [0]


def test_a_bench_that_finishes_or_fails_first_leaves_no_partial_file(
    continuous_args: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    partial = tmp_path / "kept.jsonl"
    ok = CliRunner().invoke(app, [*continuous_args, "--partial", str(partial)])
    assert ok.exit_code == 0, ok.output
    assert not partial.exists()
    break_seed(monkeypatch, 0)
    result = CliRunner().invoke(app, [*continuous_args, "--partial", str(partial)])
    assert result.exit_code == 1, result.output
    assert "0 of 4 runs finished (none to keep)" in _text(result.stderr)
    assert not partial.exists()


def test_input_refused_before_any_run_is_status_2_and_keeps_no_file(
    continuous_args: list[str], population_file: Path, tmp_path: Path
) -> None:
    """A noise no subject can have is refused as input, not as every run's failure, naming
    the option (both said 'noise must be ...', for --user-noise too)."""
    partial = tmp_path / "kept.jsonl"
    result = CliRunner().invoke(
        app, [*continuous_args, "--noise", "inf", "--partial", str(partial)]
    )
    assert result.exit_code == 2, result.output
    assert "--noise must be a finite number >= 0, got inf" in _text(result.stderr)
    args = ["bench", "population", "--objectives", str(population_file), "--trials", "2",
            "--config", POPULATION, "--user-noise", "inf", "--partial", str(partial)]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    assert "--user-noise must be a finite number >= 0, got inf" in _text(result.stderr)
    assert not partial.exists()


@pytest.mark.parametrize("tolerance", ["nan", "-0.1", "1", "inf"])
def test_a_tolerance_outside_0_1_is_refused_before_any_run(
    population_file: Path, tmp_path: Path, tolerance: str
) -> None:
    """It was checked by every run: the first run's failure, status 1 ("0 of 6 runs")."""
    partial = tmp_path / "kept.jsonl"
    args = ["bench", "population", "--objectives", str(population_file), "--trials", "2"]
    args += ["--config", POPULATION, "--tolerance", tolerance, "--partial", str(partial)]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    assert "tolerance must be a fraction in [0, 1)" in _text(result.stderr)
    assert "runs finished" not in _text(result.stderr)
    assert not partial.exists()


# -- bench population ---------------------------------------------------------------------


@pytest.fixture()
def population_file(tmp_path: Path) -> Path:
    return population_objectives(tmp_path)


def test_bench_population_names_the_failed_run_and_keeps_the_finished_ones(
    population_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    args = ["bench", "population", "--objectives", str(population_file), "--trials", "4",
            "--config", POPULATION, "--json"]  # fmt: skip
    clean = CliRunner().invoke(app, args)
    assert clean.exit_code == 0, clean.output
    subjects = json.loads(clean.stdout)["subjects"]
    break_subject(monkeypatch, 1, "warm")
    partial = tmp_path / "kept.jsonl"
    result = CliRunner().invoke(app, [*args, "--partial", str(partial)])
    assert result.exit_code == 1, result.output
    assert isinstance(result.exception, SystemExit) and result.stdout == ""
    text = _text(result.stderr)
    assert "subject 1 (warm), seed 0 failed (ValueError): the subject left" in text
    assert f"4 of 6 runs finished; their results are in {partial}" in text
    first, *kept = _lines(partial)
    assert first["gaitpref bench"]["bench"] == "population"  # the bench that wrote it
    assert [(r["subject"], r["run"]) for r in kept] == [(0, "cold"), (1, "cold"), (2, "cold"),
                                                         (0, "warm")]  # fmt: skip
    for r in kept:  # the runs of the bench that finished
        s = subjects[r["subject"]]
        assert r["scores"] == s[r["run"]] and r["stated"] == s["stated"][r["run"]]
        assert r["right"] == s["right"][r["run"]] and r["seed"] == 0
    assert kept[3]["rho"] == subjects[0]["rho"]
    assert all(("preferences" in r) == (r["run"] == "cold") for r in kept)


def test_population_bench_keeps_the_finished_runs_on_its_error(
    population_file: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """From Python: the error names the run and carries the finished runs' records; a cold run
    that fails stops the bench before any warm run."""
    break_subject(monkeypatch, 2, "cold")
    with pytest.raises(RunError) as info:
        population_bench(load_config(POPULATION), np.load(population_file), 3)
    err = info.value
    assert err.run == "subject 2 (cold), seed 0" and err.partial is None
    assert isinstance(err.__cause__, ValueError)
    assert [(r["subject"], r["run"]) for r in err.finished] == [(0, "cold"), (1, "cold")]
    assert "2 of 6 runs finished; their results are on this error (RunError.finished)" in str(err)


OVER_BUDGET = """\
name = "over-budget"
[space.a]
min = 0.0
max = 1.0
num = 500
[space.b]
min = 0.0
max = 1.0
num = 500
[model]
lengthscale = 0.2
signal_variance = 1.0
noise = 0.05
[cospar]
strategy = "plausible-eubo"
[cospar.strategy_settings]
samples = 4096
"""


@pytest.mark.parametrize("bench", ["continuous", "population"])
def test_a_bench_refuses_a_config_over_the_sampling_budget_before_any_run(
    tmp_path: Path, bench: str
) -> None:
    """As a new session and ``gaitpref simulate`` do (``config/draws.py``): named, status 2,
    no run made (before, each run failed at its first ask)."""
    config = tmp_path / "over.toml"
    config.write_text(OVER_BUDGET)
    partial = tmp_path / "runs.jsonl"
    if bench == "continuous":
        args = ["bench", "continuous", str(config), "--objective", "random-gp", "--runs", "2"]
    else:
        objectives = tmp_path / "f.npy"
        np.save(objectives, np.zeros((2, 3)))
        args = ["bench", "population", "--config", str(config), "--objectives", str(objectives)]
    result = CliRunner().invoke(app, [*args, "--trials", "2", "--partial", str(partial)])
    assert result.exit_code == 2, result.output
    assert "[cospar.strategy_settings].samples: is 4096" in _text(result.output)
    assert "set samples to at most 536" in _text(result.output)
    assert not partial.exists()


def test_bench_continuous_refuses_more_runs_than_a_study_holds(
    continuous_args: list[str], tmp_path: Path
) -> None:
    """``--runs 1000000000000`` made the list of its runs first: a MemoryError traceback.  At
    most MAX_RUNS (a study's limit), refused before any run, and the help says so (it said
    ``x>=1``)."""
    from gaitpref.limits import MAX_RUNS

    partial = tmp_path / "kept.jsonl"
    args = [*continuous_args, "--partial", str(partial)]
    args[args.index("--runs") + 1] = str(MAX_RUNS + 1)
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 2, result.output
    assert f"--runs': Input should be less than or equal to {MAX_RUNS}" in _text(result.stderr)
    helped = CliRunner().invoke(app, ["bench", "continuous", "--help"])
    assert f"1<=x<={MAX_RUNS}" in _text(helped.output)
    assert not partial.exists()


@pytest.mark.parametrize("kind", ["file", "symlink", "folder", "no-folder"])
@pytest.mark.parametrize("bench", ["continuous", "population"])
def test_a_partial_path_that_exists_or_has_no_folder_is_refused(
    continuous_args: list[str], population_file: Path, tmp_path: Path, kind: str, bench: str
) -> None:
    """``--partial`` is opened for writing and removed once every run has finished: an existing
    file was truncated and then deleted (``--partial /dev/null`` removed /dev/null), a symlink
    removed after its target was truncated.  Now refused before any run, naming the option."""
    kept = tmp_path / "results.jsonl"
    kept.write_text('{"earlier": "results"}\n', encoding="utf-8")
    given = {
        "file": kept,
        "symlink": tmp_path / "link.jsonl",
        "folder": tmp_path,
        "no-folder": tmp_path / "missing" / "kept.jsonl",
    }[kind]
    if kind == "symlink":
        given.symlink_to(kept)
    args = (
        continuous_args
        if bench == "continuous"
        else ["bench", "population", "--objectives", str(population_file), "--trials", "2",
              "--config", POPULATION]
    )  # fmt: skip
    result = CliRunner().invoke(app, [*args, "--partial", str(given)])
    assert result.exit_code == 2, result.output
    assert f"--partial {str(given)!r}" in _text(result.stderr)
    assert kept.read_text(encoding="utf-8") == '{"earlier": "results"}\n'
    assert kind != "symlink" or given.is_symlink()
