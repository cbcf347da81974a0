"""``gaitpref bench population``: warm against cold per held-out subject, and calibration."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from gaitpref.cli import app
from gaitpref.config import load_config
from gaitpref.simulate.population import calibration, synthetic_population

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
