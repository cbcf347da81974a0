"""`gaitpref simulate --json` on a grid: every field agrees with the others, as an analysis of
the JSON would read them.

- ``posterior_argmax_normalized_objective`` is the normalised objective *at*
  ``posterior_argmax``, and ``best_point``/``best_objective`` are that gait's: with
  ``[model] hyper = "average"`` the score was the mixture mean's argmax while
  ``posterior_argmax`` named the MAP kernel's (another gait on this objective and seed);
- ``points`` and ``objective`` are per query (``n`` executed points each), as over points: on
  a grid they were one list per trial whatever ``n``.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from gaitpref.cli import app

ROOT = Path(__file__).resolve().parents[2]
runner = CliRunner()


def simulate(*args: str) -> dict[str, object]:
    result = runner.invoke(app, ["simulate", *args, "--json"])
    assert result.exit_code == 0, result.output
    out: dict[str, object] = json.loads(result.stdout)
    return out


def test_the_argmax_score_is_of_the_argmax_with_averaged_hypotheses(tmp_path: Path) -> None:
    text = (ROOT / "configs" / "synthetic-2d.toml").read_text(encoding="utf-8")
    text = text.replace('fit = "fixed"', 'fit = "evidence"\nhyper = "average"')
    assert 'hyper = "average"' in text
    config = tmp_path / "avg.toml"
    config.write_text(text, encoding="utf-8")
    obj = np.random.default_rng(0).normal(size=(30, 30))
    np.save(tmp_path / "obj.npy", obj)
    out = simulate(
        str(config), "--objective", str(tmp_path / "obj.npy"), "--trials", "25", "--seed", "2"
    )
    flat = obj.reshape(-1)
    norm = (flat - flat.min()) / (flat.max() - flat.min())
    best = out["posterior_argmax"]
    assert isinstance(best, int)
    assert out["posterior_argmax_normalized_objective"] == norm[best]
    assert out["best_objective"] == flat[best]
    xs = np.linspace(0.0, 1.0, 30)
    best_point = out["best_point"]
    assert isinstance(best_point, list)
    assert np.allclose(best_point, [xs[best // 30], xs[best % 30]])


def test_points_and_objective_are_per_query_on_a_grid(tmp_path: Path) -> None:
    cot = np.random.default_rng(1).normal(size=24)  # compass-gait: 24 step lengths, n = 2
    np.save(tmp_path / "cot.npy", cot)
    out = simulate("compass-gait", "--objective", str(tmp_path / "cot.npy"), "--trials", "5")
    actions = out["actions"]
    assert isinstance(actions, list) and len(actions) == 5
    grid = np.linspace(0.08, 0.18, 24)
    queries = [actions[0:2], actions[2:4], actions[4:5]]  # the last query cut at --trials
    points = out["points"]
    assert isinstance(points, list) and [len(q) for q in points] == [2, 2, 1]
    for got, q in zip(points, queries, strict=True):
        assert np.allclose(got, [[grid[a]] for a in q])
    assert out["objective"] == [[float(cot[a]) for a in q] for q in queries]
