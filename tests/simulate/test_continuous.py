"""Objectives over points and simulation on continuous spaces (issue 13, item 5)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref import CoSpar, Feature, Space, SquaredExponential
from gaitpref.cli.main import app
from gaitpref.loop.line import LineCoSpar
from gaitpref.simulate.continuous import (
    HARTMANN6_ARGMAX,
    HARTMANN6_MAX,
    RandomGP,
    builtin,
    estimate_optimum,
    hartmann6,
    load_function,
    objective_from,
)
from gaitpref.simulate.points import PointCoactive, PointUser, run_points

CONFIG = """\
[space.a]
min = 0.0
max = 2.0
[space.b]
min = -1.0
max = 1.0
[space.c]
min = 0.0
max = 1.0
num = 4
[model]
lengthscale = 0.4
signal_variance = 1.0
noise = 0.05
jitter = 1e-6
fit = "fixed"
"""


def test_hartmann6_has_its_known_maximum() -> None:
    at = np.array([HARTMANN6_ARGMAX])
    assert hartmann6(at)[0] == pytest.approx(HARTMANN6_MAX, abs=1e-4)
    rng = np.random.default_rng(0)
    assert hartmann6(rng.uniform(size=(5000, 6))).max() < HARTMANN6_MAX


def test_a_random_gp_has_the_kernel_it_was_drawn_with() -> None:
    # across draws, cov(f(x), f(y)) = exp(-|x - y|^2 / (2 l^2)) (Rahimi & Recht)
    x = np.array([[0.2, 0.3], [0.4, 0.3], [0.9, 0.9]])
    values = np.array([RandomGP.draw(2, seed, 0.2)(x) for seed in range(3000)])
    d2 = np.sum((x[:, None] - x[None]) ** 2, axis=2)
    np.testing.assert_allclose(np.cov(values.T), np.exp(-d2 / (2 * 0.2**2)), atol=0.08)
    np.testing.assert_array_equal(RandomGP.draw(2, 5)(x), RandomGP.draw(2, 5)(x))


def test_an_objective_loads_from_a_python_file(tmp_path: Path) -> None:
    path = tmp_path / "obj.py"
    path.write_text("import numpy as np\ndef bowl(x):\n    return -np.sum(x ** 2, axis=1)\n")
    fn = load_function(f"{path}:bowl")
    np.testing.assert_allclose(fn(np.array([[1.0, 2.0], [0.0, 0.0]])), [-5.0, 0.0])
    with pytest.raises(ValueError, match="defines no function 'nope'"):
        load_function(f"{path}:nope")
    with pytest.raises(ValueError, match=r"PATH\.py:NAME"):
        load_function(str(path))
    bad = tmp_path / "bad.py"
    bad.write_text("def one(x):\n    return 1.0\n")
    space = Space([Feature.interval("a", 0.0, 1.0)])
    with pytest.raises(ValueError, match="must return 2 finite utilities"):
        objective_from(f"{bad}:one", space)


@pytest.mark.parametrize(
    ("spec", "extra"),
    [
        ("hartman6", ""),  # a mistyped built-in said only 'expected PATH.py:NAME'
        ("obj.py", ""),
        ("grid.npy", "`gaitpref simulate` takes it"),  # bench continuous takes no grid
    ],
)
def test_an_objective_that_is_no_function_nor_builtin_names_what_is_taken(
    spec: str, extra: str
) -> None:
    message = (
        f"objective {spec!r}: expected PATH.py:NAME (a function in a Python file) or a "
        "built-in: hartmann6, random-gp[:SEED]"
    )
    with pytest.raises(ValueError, match=re.escape(message)) as caught:
        load_function(spec)
    assert extra in str(caught.value)
    result = CliRunner().invoke(
        app, ["bench", "continuous", "synthetic-2d", "--objective", spec, "--runs", "1"]
    )
    assert result.exit_code == 2 and "random-gp[:SEED]" in result.output, result.output


def test_builtins_read_the_box_in_the_features_units() -> None:
    space = Space([Feature.interval(f"x{k}", 10.0, 20.0) for k in range(8)])
    fn = builtin("hartmann6", space)
    point = 10.0 + 10.0 * np.array([[*HARTMANN6_ARGMAX, 0.9, 0.1]])
    assert fn(point)[0] == pytest.approx(HARTMANN6_MAX, abs=1e-4)
    _, value = estimate_optimum(fn, space, samples=4000, starts=4)
    assert value == pytest.approx(HARTMANN6_MAX, abs=0.05)
    with pytest.raises(ValueError, match="at least 6 features"):
        builtin("hartmann6", Space([Feature.interval("x", 0.0, 1.0)]))


@pytest.mark.parametrize("path", ["grid", "line"])
def test_runs_on_either_path_learn_and_report_points(path: str) -> None:
    grid = Space([Feature.linspace(f"x{k}", 0.0, 1.0, 6) for k in range(3)])
    domain = (
        grid if path == "grid" else Space([Feature.interval(f"x{k}", 0.0, 1.0) for k in range(3)])
    )

    def fn(x: np.ndarray) -> np.ndarray:
        out: np.ndarray = -np.sum((x - np.array([0.6, 0.2, 0.8])) ** 2, axis=1)
        return out

    kernel = SquaredExponential(0.2, 1.0, 1e-6)
    loop = (CoSpar if path == "grid" else LineCoSpar)(domain, kernel, 0.05, n=1, buffer=1, seed=0)
    user = PointUser(fn, np.random.default_rng(1))
    res = run_points(loop, fn, user, 60, PointCoactive(fn, domain), checkpoints=(20, 60))
    assert len(res.points) == 60 and all(len(q) == 1 and len(q[0]) == 3 for q in res.points)
    np.testing.assert_allclose(res.curve, fn(np.array([q[0] for q in res.points])))
    assert res.best_objective == pytest.approx(float(fn(np.array([res.best_point]))[0]))
    assert res.best_at[60] == res.best_objective
    rand = fn(np.random.default_rng(2).uniform(size=(2000, 3)))
    assert res.best_objective > np.quantile(rand, 0.75)  # it learned


def _cli(*args: str) -> str:
    result = CliRunner().invoke(app, list(args))
    assert result.exit_code == 0, result.output
    return result.output


def test_simulate_with_a_function_reports_points_and_the_best(tmp_path: Path) -> None:
    cfg = tmp_path / "cont.toml"
    cfg.write_text(CONFIG)
    obj = tmp_path / "obj.py"
    obj.write_text(
        "import numpy as np\n"
        "def peak(x):\n"
        "    return -np.sum((x - np.array([1.5, 0.0, 0.5])) ** 2, axis=1)\n"
    )
    out = json.loads(_cli("simulate", str(cfg), "--objective", f"{obj}:peak", "--trials", "12",
                          "--coactive", "--json"))  # fmt: skip
    assert out["trials"] == 12 and len(out["points"]) == 12 and len(out["objective"]) == 12
    for points, values in zip(out["points"], out["objective"], strict=True):
        (point,) = points
        assert 0.0 <= point[0] <= 2.0 and -1.0 <= point[1] <= 1.0
        assert point[2] in (0.0, 1 / 3, 2 / 3, 1.0) or np.isclose(point[2] * 3, round(point[2] * 3))
        assert values[0] == pytest.approx(-np.sum((np.array(point) - [1.5, 0.0, 0.5]) ** 2))
    best = np.array(out["best_point"])
    assert out["best_objective"] == pytest.approx(-np.sum((best - [1.5, 0.0, 0.5]) ** 2))
    again = json.loads(_cli("simulate", str(cfg), "--objective", f"{obj}:peak", "--trials", "12",
                            "--coactive", "--json"))  # fmt: skip
    assert again["points"] == out["points"]  # reproducible from the seed
    refused = CliRunner().invoke(app, ["simulate", str(cfg), "--objective", "hartmann6"])
    assert refused.exit_code != 0 and "at least 6 features" in refused.output
    text = _cli("simulate", str(cfg), "--objective", "random-gp:4", "--trials", "5")
    assert "posterior best point: a=" in text


def test_a_grid_objective_on_the_line_path_is_refused(tmp_path: Path) -> None:
    cfg = tmp_path / "cont.toml"
    cfg.write_text(CONFIG)
    npy = tmp_path / "o.npy"
    np.save(npy, np.zeros(4))
    result = CliRunner().invoke(app, ["simulate", str(cfg), "--objective", str(npy)])
    assert result.exit_code != 0 and "line path" in result.output


def test_bench_continuous_sweeps_seeds_with_a_function(tmp_path: Path) -> None:
    cfg = tmp_path / "cont.toml"
    cfg.write_text(CONFIG)
    obj = tmp_path / "obj.py"
    obj.write_text("import numpy as np\ndef f(x):\n    return -np.abs(x[:, 0] - 1.0)\n")
    out = json.loads(_cli("bench", "continuous", str(cfg), "--objective", f"{obj}:f",
                          "--runs", "2", "--trials", "6", "--json"))  # fmt: skip
    assert out["path"] == "line" and [r["seed"] for r in out["runs"]] == [0, 1]
    curves = np.array([[v[0] for v in r["objective"]] for r in out["runs"]])
    np.testing.assert_allclose(out["mean_curve"], curves.mean(axis=0))
    best = [r["best_objective"] for r in out["runs"]]
    assert out["best_objective_mean"] == pytest.approx(np.mean(best))
    assert out["best_objective_se"] == pytest.approx(np.std(best, ddof=1) / np.sqrt(2))


def test_a_users_objective_that_fails_is_an_error_naming_it_and_the_run(tmp_path: Path) -> None:
    """A file that does not import, a function that raises, returns NaN or the wrong count:
    a traceback, or a NaN utility taken silently ('objective nan'), before; booleans failed
    later with numpy's 'boolean subtract is not supported', naming nothing, and complex
    numbers had their imaginary parts dropped."""
    cfg = tmp_path / "cont.toml"
    cfg.write_text(CONFIG)
    obj = tmp_path / "obj.py"
    obj.write_text(
        "import numpy as np\n"
        "def raises(x):\n"
        "    if x.shape[0] != 2:\n"
        "        raise RuntimeError('sensor model blew up')\n"
        "    return -x[:, 0]\n"
        "def nan(x):\n"
        "    return np.where(x[:, 0] > -1, np.nan, 0.0) if x.shape[0] != 2 else -x[:, 0]\n"
        "def count(x):\n"
        "    return np.zeros(x.shape[0] + 1) if x.shape[0] != 2 else -x[:, 0]\n"
        "def flags(x):\n"
        "    return x[:, 0] > 0.5 if x.shape[0] != 2 else -x[:, 0]\n"
        "def cplx(x):\n"
        "    return x[:, 0] + 1j if x.shape[0] != 2 else -x[:, 0]\n"
    )
    (tmp_path / "broken.py").write_text("def f(x) return 1\n")
    cases = {
        f"{obj}:raises": "failed on 1 point(s): RuntimeError: sensor model blew up",
        f"{obj}:nan": "must return 1 finite utilities, got values that are not finite",
        f"{obj}:count": "must return 1 finite utilities, got shape (2,)",
        f"{obj}:flags": "must return 1 real utilities, got bool values",
        f"{obj}:cplx": "must return 1 real utilities, got complex128 values",
        f"{tmp_path / 'broken.py'}:f": "cannot be imported: SyntaxError",
        "random-gp:x": "the seed after ':' must be an integer >= 0",
    }
    refused = (f"{tmp_path / 'broken.py'}:f", "random-gp:x")  # before any run
    for spec, message in cases.items():
        for args in (["simulate"], ["bench", "continuous"]):
            result = CliRunner().invoke(
                app, [*args, str(cfg), "--objective", spec, "--trials", "3"]
            )
            # bench continuous: a run that failed stops the bench with status 1, as a study's
            stopped = args[0] == "bench" and spec not in refused
            assert result.exit_code == (1 if stopped else 2), result.output
            assert isinstance(result.exception, SystemExit), result.exception  # no traceback
            assert message in " ".join(result.output.split()), (args, spec, result.output)
    result = CliRunner().invoke(app, ["bench", "continuous", str(cfg), "--objective",
                                      f"{obj}:raises", "--runs", "2", "--trials", "3"])  # fmt: skip
    text = " ".join(result.output.split())
    assert f"objective '{obj}:raises', seed 0 failed (ValueError): objective" in text
    assert "the bench stopped: 0 of 2 runs finished (none to keep)" in text


def test_runs_over_points_report_their_progress(tmp_path: Path) -> None:
    """simulate and bench continuous said nothing until a run (all runs) ended: now a bar,
    fed by simulate_points' progress (trials done after every query)."""
    from gaitpref.cli.points import simulate_points
    from gaitpref.config import parse_config

    cfg = parse_config(CONFIG)
    done: list[int] = []
    simulate_points(cfg, builtin("random-gp", cfg.space, 1), trials=5, seed=0,
                    progress=done.append)  # fmt: skip
    assert done == sorted(done) and done[-1] == 5


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("hartmann6:5", "hartmann6 takes no seed"),  # ran hartmann6, the seed ignored
        ("hartmann6:", "hartmann6 takes no seed"),
        ("random-gp:", "the seed after ':' must be an integer >= 0"),  # ran the config's seed
    ],
)
def test_a_builtin_seed_that_is_not_taken_is_refused(spec: str, message: str) -> None:
    from gaitpref.config import load_config
    from gaitpref.simulate.continuous import objective_from

    space = load_config("synthetic-6d").space
    with pytest.raises(ValueError, match=f"objective {spec!r}: {message}"):
        objective_from(spec, space)
    result = CliRunner().invoke(app, ["simulate", "synthetic-6d", "--objective", spec])
    assert result.exit_code == 2 and message in " ".join(result.output.split()), result.output
