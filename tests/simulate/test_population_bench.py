"""``gaitpref bench population``: warm against cold per held-out subject, and calibration."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref.cli import app
from gaitpref.config import load_config
from gaitpref.simulate.population import (
    calibration,
    cluster_bootstrap,
    gp_population,
    population_bench,
    synthetic_population,
)

CONFIG = "exo-1d-step-length"


def test_the_json_holds_cold_and_warm_per_subject_and_a_calibration(tmp_path: Path) -> None:
    A = len(load_config(CONFIG).space)
    x = np.linspace(0, 1, A)
    peaks = [0.6, 0.65, 0.7]
    path = tmp_path / "objectives.npy"
    np.save(path, np.array([-((x - p) ** 2) for p in peaks]))
    args = ["bench", "population", "--objectives", str(path), "--trials", "6"]
    result = CliRunner().invoke(app, [*args, "--config", CONFIG, "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    assert [s["subject"] for s in out["subjects"]] == [0, 1, 2]
    for s in out["subjects"]:
        assert len(s["cold"]) == len(s["warm"]) == 6
        assert all(0.0 <= v <= 1.0 for v in s["cold"] + s["warm"])
        assert 0.0 < s["rho"] < 1.0
    assert sum(b["count"] for b in out["calibration"]) == 2 * 3 * 6  # one per answer, both runs
    again = CliRunner().invoke(app, [*args, "--config", CONFIG, "--json"])
    assert json.loads(again.stdout) == out  # same seeds, same runs


def test_calibration_bins_and_synthetic_populations() -> None:
    bins = calibration([0.05, 0.08, 0.95, 0.91, 0.99], [False, True, True, True, False])
    assert [(b["lo"], b["count"]) for b in bins] == [(0.0, 2), (0.9, 3)]
    assert bins[1]["observed"] == 2 / 3 and abs(bins[1]["stated"] - 0.95) < 1e-12
    objectives = np.random.default_rng(0).normal(size=(5, 40))
    same = synthetic_population(objectives, 1.0, 3)
    assert np.allclose(same, same[0])  # rho = 1: one utility
    alone = synthetic_population(objectives, 0.0, 3)
    z = (objectives - objectives.mean(1, keepdims=True)) / objectives.std(1, keepdims=True)
    assert np.allclose(alone, z[1:4])  # rho = 0: each their own


def test_cluster_bootstrap_resamples_whole_subjects() -> None:
    rng = np.random.default_rng(0)
    # two subjects, each always right or always wrong at stated 0.5: the bin's observed
    # frequency is 0.5, but resampling subjects moves it between 0, 0.5 and 1
    runs = [([0.5] * 20, [True] * 20), ([0.55] * 20, [False] * 20)]
    (b,) = cluster_bootstrap(runs, rng, resamples=4000)
    assert (b["lo"], b["count"], b["clusters"]) == (0.5, 40, 2)
    assert abs(b["observed"] - 0.5) < 1e-12 and abs(b["stated"] - 0.525) < 1e-12
    binomial = np.sqrt(0.25 / 40)
    assert b["se"] > 3 * binomial  # the clusters' spread: sd of {0, 0.5, 0.5, 1} ~ 0.35
    assert abs(b["se"] - np.sqrt(0.125)) < 0.03
    # independent subjects with one answer each: the bootstrap se is close to the binomial
    hits = rng.random(400) < 0.3
    (c,) = cluster_bootstrap([([0.31], [bool(h)]) for h in hits], rng)
    assert abs(c["se"] - np.sqrt(c["observed"] * (1 - c["observed"]) / 400)) < 0.005
    with pytest.raises(ValueError, match="at least one run"):
        cluster_bootstrap([], rng)


def test_gp_population_draws_the_models_prior_and_its_smooth_part() -> None:
    config = load_config("synthetic-2d")
    draws, smooth = gp_population(config, 0.5, 200, np.random.default_rng(1))
    assert draws.shape == smooth.shape == (200, len(config.space))
    kernel = config.make_loop(seed=0).gp.kernel
    jitter = draws - smooth  # the independent per-gait term: variance jitter, no correlation
    assert abs(jitter.var() / kernel.jitter - 1) < 0.05
    assert abs(np.corrcoef(jitter[:, 0], jitter[:, 1])[0, 1]) < 0.2
    assert abs(draws.var() / (kernel.variance + kernel.jitter) - 1) < 0.2
    # rho = 0.5: half of each subject's variance is their own (the spread about the subjects'
    # mean), half the shared part they all hold; rho = 0: nothing shared
    total = kernel.variance + kernel.jitter
    assert abs((draws - draws.mean(axis=0)).var() / total - 0.5) < 0.05
    alone, _ = gp_population(config, 0.0, 200, np.random.default_rng(1))
    assert abs((alone - alone.mean(axis=0)).var() / total - 1.0) < 0.1
    assert alone.mean(axis=0).var() / total < 0.02
    with pytest.raises(ValueError, match="rho"):
        gp_population(config, 1.5, 2, np.random.default_rng(1))


def test_the_bench_judges_the_recommendation_on_the_truths_given(tmp_path: Path) -> None:
    config = load_config(CONFIG)
    x = np.linspace(0, 1, len(config.space))
    objectives = np.array([-((x - p) ** 2) for p in (0.6, 0.65)])
    out = population_bench(config, objectives, 4)
    subjects = out["subjects"]
    assert isinstance(subjects, list)
    for s in subjects:  # the answers behind the calibration, per subject and arm
        assert len(s["stated"]["cold"]) == len(s["right"]["warm"]) == 4
    # judged on the opposite utility: the same runs, every recommendation near the best is now
    # near the worst
    flipped = population_bench(config, objectives, 4, truths=-objectives)["subjects"]
    assert isinstance(flipped, list)
    for a, b in zip(subjects, flipped, strict=True):
        assert a["cold"] == b["cold"] and a["stated"] == b["stated"]
        assert all(
            not (r and q) for r, q in zip(a["right"]["cold"], b["right"]["cold"], strict=True)
        )
    with pytest.raises(ValueError, match="truths"):
        population_bench(config, objectives, 2, truths=objectives[:1])


def test_no_more_workers_than_subjects(monkeypatch: pytest.MonkeyPatch) -> None:
    """jobs = 8 for three subjects started eight loky processes (a thousand for --jobs 1000)."""
    import joblib

    asked: list[int] = []
    real = joblib.Parallel

    def parallel(n_jobs: int, **kwargs: object) -> joblib.Parallel:
        asked.append(n_jobs)
        return real(n_jobs=n_jobs, **kwargs)

    monkeypatch.setattr(joblib, "Parallel", parallel)
    A = len(load_config(CONFIG).space)
    x = np.linspace(0, 1, A)
    grids = np.array([-((x - p) ** 2) for p in (0.6, 0.65, 0.7)])
    population_bench(load_config(CONFIG), grids, 2, jobs=8)
    assert asked == [3, 3]  # cold, then warm


def test_objectives_that_are_not_one_grid_per_subject_are_named_by_shape_or_subject() -> None:
    """A flat file of S x A values, or one subject's grid alone, was iterated value by value:
    'objective has shape (); the grid needs (15,)'; a NaN named no subject."""
    cfg = load_config(CONFIG)
    A = len(cfg.space)
    for flat in (np.zeros(3 * A), np.zeros(A)):
        with pytest.raises(
            ValueError, match=rf"one utility grid per subject.*shape \({flat.size},\)"
        ):
            population_bench(cfg, flat, 1)
    bad = np.zeros((3, A))
    bad[2, 4] = np.nan
    with pytest.raises(ValueError, match=r"objectives: subject 2 .*must be finite"):
        population_bench(cfg, bad, 1)
    with pytest.raises(ValueError, match=r"truths: subject 0 .*shape \(16,\)"):
        population_bench(cfg, np.zeros((3, A)), 1, truths=np.zeros((3, A + 1)))


def test_an_infinite_user_noise_is_refused_as_not_finite() -> None:
    """It was refused as 'noise must be >= 0, got inf' (which it is)."""
    cfg = load_config(CONFIG)
    with pytest.raises(ValueError, match="noise must be a finite number >= 0, got inf"):
        population_bench(cfg, np.zeros((2, len(cfg.space))), 1, user_noise=float("inf"))


def test_the_bench_reports_its_progress_run_by_run(tmp_path: Path) -> None:
    """It said nothing till the end (minutes for 20 subjects): the API counts the finished
    runs, and the command draws a bar of them (not with --json, whose stdout is the JSON)."""
    config = load_config(CONFIG)
    x = np.linspace(0, 1, len(config.space))
    objectives = np.array([-((x - p) ** 2) for p in (0.6, 0.65)])
    seen: list[int] = []
    population_bench(config, objectives, 2, progress=seen.append)
    assert seen == [0, 1, 2, 3, 4]  # once before the runs, then each of 2 cold, 2 warm
    path = tmp_path / "objectives.npy"
    np.save(path, objectives)
    args = ["bench", "population", "--objectives", str(path), "--trials", "2"]
    result = CliRunner().invoke(app, [*args, "--config", CONFIG])
    assert result.exit_code == 0, result.output
    assert "2 subjects, cold and warm" in result.output and "4/4" in result.output
