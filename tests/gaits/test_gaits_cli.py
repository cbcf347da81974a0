"""The ``gaitpref gaits`` Typer sub-application."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from joblib import cpu_count
from typer.testing import CliRunner

from gaitpref.cli.gaits import app, parse_range
from gaitpref.gaits import GaitLibrary

runner = CliRunner()


def _text(output: str) -> str:
    """Output without Rich's panel borders and line wrapping."""
    return " ".join(output.replace("│", " ").split())


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("cli") / "lib.json"
    result = runner.invoke(
        app, ["build", "--step-length", "0.10:0.14:3", "--speed", "0.2", "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    assert "wrote" in result.stdout and "3 feasible" in result.stdout  # the result, not stderr
    return out


def test_build_writes_a_loadable_library(built: Path) -> None:
    lib = GaitLibrary.load(built)
    assert lib.shape == (3,) and lib.speed == 0.2
    assert [lib.gait_id(i) for i in range(3)] == ["L0.100-V0.200", "L0.120-V0.200", "L0.140-V0.200"]


def test_build_with_durations_and_width_label(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "grid.json"
    args = ["build", "--step-length", "0.12", "--step-duration", "0.9:1.0:2",
            "--step-width", "0.25:0.30:2", "--jobs", str(min(2, cpu_count())),
            "--out", str(out)]  # fmt: skip
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    lib = GaitLibrary.load(out)
    assert lib.names == ("step_length", "step_duration", "step_width") and lib.shape == (1, 2, 2)
    # at 80 columns the lined table cut values ('L0.120-T0.900-W…', '0.0…', 'y…') and showed
    # the index column empty: now a header wraps and no value is cut
    from gaitpref.cli.output import console

    monkeypatch.setattr(console, "_width", 80)
    shown = runner.invoke(app, ["show", str(out)])
    assert shown.exit_code == 0, shown.output
    rows = [line.split() for line in shown.output.splitlines() if "-W0." in line]
    assert [row[:2] for row in rows] == [[str(i), lib.gait_id(i)] for i in range(4)]
    assert [row[-2:] for row in rows] == [[f"{g.delta_squared:.4f}", "yes"] for g in lib.gaits]
    assert all(f"{g.cot:.5f}" in row for g, row in zip(lib.gaits, rows, strict=True))


def test_show_table_and_json(built: Path) -> None:
    table = runner.invoke(app, ["show", str(built)])
    assert table.exit_code == 0, table.output
    assert "L0.120-V0.200" in table.output and "feasible" in table.output
    result = runner.invoke(app, ["show", str(built), "--json"])
    assert result.exit_code == 0, result.output
    doc = json.loads(result.output)
    assert doc["n_gaits"] == doc["n_feasible"] == 3
    first = doc["gaits"][0]
    assert first["parameters"] == {"step_length": 0.1}
    assert first["feasible"] is True and first["cot"] > 0
    assert first["step_duration"] == pytest.approx(0.5, rel=1e-4)


def test_plot_writes_a_png(built: Path, tmp_path: Path) -> None:
    png = tmp_path / "fig.png"
    result = runner.invoke(
        app, ["plot", str(built), "--id", "L0.120-V0.200", "--steps", "2", "--out", str(png)]
    )
    assert result.exit_code == 0, result.output
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    missing = runner.invoke(app, ["plot", str(built), "--id", "L9.000-V0.200"])
    assert missing.exit_code != 0 and "no gait with id" in _text(missing.output)


def test_usage_errors(tmp_path: Path) -> None:
    neither = runner.invoke(app, ["build", "--out", str(tmp_path / "x.json")])
    assert neither.exit_code == 2 and "exactly one of --step-duration and --speed" in _text(
        neither.output
    )
    bad_range = runner.invoke(
        app, ["build", "--step-length", "0.1:0.05:3", "--speed", "0.2", "--out", "x.json"]
    )
    assert bad_range.exit_code == 2 and "min:max:count" in _text(bad_range.output)
    absent = runner.invoke(app, ["show", str(tmp_path / "absent.json")])
    assert absent.exit_code == 2 and "no such gait library file" in _text(absent.output)


def test_parse_range() -> None:
    assert parse_range("0.08:0.18:3", "--x") == pytest.approx((0.08, 0.13, 0.18))
    assert parse_range("0.2", "--x") == (0.2,)


@pytest.mark.parametrize(
    ("args", "problem"),
    [
        (["--speed", "inf"], "--speed: must be a positive number"),  # a traceback after a build
        (["--speed", "0.2", "--step-length", "0.1:2.5:3"], "step length must be in (0, 2.0)"),
        (["--speed", "0.2", "--step-length", "0.12:0.1201:3"], "distinct gait ids"),
        (["--speed", "0.2", "--step-length", "0.1:0.2:100000000000"], "at most 1000000 values"),
        (["--step-length", "0.1:0.2:1000", "--step-duration", "0.5:1:1001"], "1001000 gaits"),
        (  # within a config's grid, but past what a library file is read back at
            ["--step-length", "0.1:0.2:400", "--step-duration", "0.5:1:400"],
            "the grid has 160,000 gaits; a library file holds at most 96,978 of degree 6",
        ),
        (["--speed", "0.2", "--out", "{tmp}/absent/lib.json"], "no folder"),
        (["--speed", "0.2", "--out", "{tmp}"], "is a folder"),
    ],
)
def test_build_refuses_before_optimizing_and_writes_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, args: list[str], problem: str
) -> None:
    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("optimized a gait of a build that is refused")

    monkeypatch.setattr("gaitpref.gaits.build.optimize_gait", never)
    out = ["--out", str(tmp_path / "lib.json")] if "--out" not in args else []
    argv = ["build", *(a.replace("{tmp}", str(tmp_path)) for a in args), *out]
    result = runner.invoke(app, argv)
    assert result.exit_code == 2, result.output
    assert problem in _text(result.output) and "Traceback" not in result.output
    assert "optimizing gaits" not in result.output  # the bar drew '0/1' above the error
    assert not list(tmp_path.iterdir())


def test_build_refuses_more_jobs_than_cpus(tmp_path: Path) -> None:
    """--jobs 10000 started 10000 worker processes (joblib starts every one asked for)."""
    args = ["build", "--step-length", "0.12", "--speed", "0.2", "--jobs", "10000"]
    result = runner.invoke(app, [*args, "--out", str(tmp_path / "lib.json")])
    assert result.exit_code == 2 and "--jobs: must be in 1.." in _text(result.output)
    assert not list(tmp_path.iterdir())


def test_plot_refuses_steps_and_formats_before_simulating(built: Path, tmp_path: Path) -> None:
    steps = runner.invoke(app, ["plot", str(built), "--steps", "0"])  # a ValueError traceback
    assert steps.exit_code == 2 and "--steps: must be in 1..100" in _text(steps.output)
    forever = runner.invoke(app, ["plot", str(built), "--steps", "1000000000"])
    assert forever.exit_code == 2 and "must be in 1..100" in _text(forever.output)
    text = runner.invoke(app, ["plot", str(built), "--out", str(tmp_path / "fig.txt")])
    assert text.exit_code == 2 and "does not write '.txt' files" in _text(text.output)
    folder = runner.invoke(app, ["plot", str(built), "--out", str(tmp_path)])
    assert folder.exit_code == 2 and "is a folder" in _text(folder.output)
    # a folder that does not exist is not made (as for build --out and session show --figure)
    absent = runner.invoke(app, ["plot", str(built), "--out", str(tmp_path / "sub" / "f.png")])
    assert absent.exit_code == 2 and "no folder" in _text(absent.output)
    assert not list(tmp_path.iterdir())


def test_plot_without_a_suffix_reports_the_png_it_writes(built: Path, tmp_path: Path) -> None:
    target = tmp_path / "sub" / "fig"
    target.parent.mkdir()
    args = ["plot", str(built), "--id", "L0.120-V0.200", "--steps", "1", "--out", str(target)]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    written = tmp_path / "sub" / "fig.png"
    assert written.is_file() and f"wrote {written}" in result.output  # it said 'wrote .../fig'


def test_show_refuses_json_nested_past_the_recursion_limit(tmp_path: Path) -> None:
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    result = runner.invoke(app, ["show", str(deep)])
    assert result.exit_code == 2 and "nested too deeply" in _text(result.output)


@pytest.mark.parametrize(
    ("grid", "chains"),
    [
        (["--step-length", "0.12", "--step-duration", "0.9:1.0:2"], 2),  # a chain per duration
        (["--step-length", "0.10:0.12:2", "--speed", "0.2"], 2),  # a piece per length at most
        (["--step-length", "0.10:0.14:3", "--speed", "0.2"], 3),
    ],
)
def test_build_starts_no_more_workers_than_chains(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, grid: list[str], chains: int
) -> None:
    """Each chain of gaits is one piece of work: ``--jobs 8`` started 8 worker processes for
    2 chains (joblib starts every worker asked for), 6 of them idle."""
    import joblib

    from gaitpref.gaits import build

    asked: list[int] = []

    class Recording:
        """joblib's ``Parallel``, run in this process, recording the workers asked for."""

        def __init__(self, n_jobs: int, **kwargs: object) -> None:
            asked.append(n_jobs)

        def __call__(self, tasks: Any) -> Any:
            return (f(*args, **kwargs) for f, args, kwargs in tasks)

    monkeypatch.setattr(joblib, "cpu_count", lambda *a, **k: 8)  # --jobs 8 is allowed here
    monkeypatch.setattr(build, "Parallel", Recording)
    out = tmp_path / "lib.json"
    result = runner.invoke(app, ["build", *grid, "--jobs", "8", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert asked == [chains]
    assert len(GaitLibrary.load(out)) == chains
