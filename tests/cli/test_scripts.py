"""The CLI as a lab's scripts drive it (nightly exports, a clinic's batch of simulate and bench
runs, a cron job that backs up and checks the database): what a command found goes to stdout,
progress, notes, questions and errors to stderr; ``--json`` prints JSON alone on stdout; the
exit status says how it went (docs/getting-started.md, "In scripts")."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from gaitpref.cli import app
from gaitpref.config import load_config

runner = CliRunner()
POPULATION = "exo-1d-step-length"


def _population_objectives(tmp_path: Path) -> Path:
    x = np.linspace(0, 1, len(load_config(POPULATION).space))
    path = tmp_path / "objectives.npy"
    np.save(path, np.array([-((x - p) ** 2) for p in (0.6, 0.65)]))
    return path


def test_a_bench_summary_goes_to_stdout_and_its_bar_to_stderr(tmp_path: Path) -> None:
    """``bench continuous`` and ``population`` printed their summaries on stderr: ``> out.txt``
    kept nothing, and ``2> /dev/null`` hid the results."""
    args = ["bench", "continuous", POPULATION, "--objective", "random-gp", "--runs", "2"]
    result = runner.invoke(app, [*args, "--trials", "3"])
    assert result.exit_code == 0, result.output
    assert "trials 1-3: " in result.stdout and "final best point's objective" in result.stdout
    assert "6/6" in result.stderr and "trials 1-3" not in result.stderr
    path = _population_objectives(tmp_path)
    args = ["bench", "population", "--objectives", str(path), "--trials", "2"]
    result = runner.invoke(app, [*args, "--config", POPULATION])
    assert result.exit_code == 0, result.output
    assert "trials 1-2: cold " in result.stdout and "warm" in result.stdout
    assert "4/4" in result.stderr and "trials 1-2" not in result.stderr


def test_json_is_alone_on_stdout_and_stderr_is_empty(tmp_path: Path) -> None:
    path = _population_objectives(tmp_path)
    commands = [
        ["bench", "continuous", POPULATION, "--objective", "random-gp", "--runs", "2",
         "--trials", "3", "--json"],
        ["bench", "population", "--objectives", str(path), "--trials", "2", "--config",
         POPULATION, "--json"],
        ["simulate", POPULATION, "--objective", "random-gp", "--trials", "3", "--json"],
    ]  # fmt: skip
    for command in commands:
        result = runner.invoke(app, command)
        assert result.exit_code == 0, (command, result.output)
        assert isinstance(json.loads(result.stdout), dict), command
        assert result.stdout.count("\n") == 1 and result.stderr == "", command


def test_a_study_says_what_it_wrote_on_stdout(tmp_path: Path) -> None:
    args = ["--runs", "1", "--trials", "3", "--settings", "n1_b1", "--no-baseline", "--jobs", "1"]
    result = runner.invoke(app, ["bench", "paper-2d", *args, "--out", str(tmp_path / "o")])
    assert result.exit_code == 0, result.output
    assert "1 run in " in result.stdout and "curves.csv" in result.stdout
    assert " run in " not in result.stderr


def test_an_error_under_json_prints_no_json_and_a_line_on_stderr(tmp_path: Path) -> None:
    for command, status in (
        (["simulate", POPULATION, "--objective", str(tmp_path / "no.npy"), "--json"], 2),
        (["simulate", "no-such-config", "--objective", "random-gp", "--json"], 2),
        (["bench", "continuous", POPULATION, "--objective", "random-gp", "--runs", "0",
          "--json"], 2),
        (["session", "show", "1", "--json", "--no-figure", "--db", str(tmp_path / "no.db")], 2),
        (["db", "check", "--json", "--db", str(tmp_path / "no.db")], 2),
    ):  # fmt: skip
        result = runner.invoke(app, command)
        assert result.exit_code == status, (command, result.output)
        assert result.stdout == "", command
        assert result.stderr.strip(), command


def test_session_list_json_names_every_session_whatever_the_width(tmp_path: Path) -> None:
    """A nightly export loops over the sessions: the table folded a long config name onto two
    lines at 80 columns (the width off a terminal), and had no --json to read instead."""
    from gaitpref import Session

    db = f"sqlite:///{tmp_path / 'lab.db'}"
    text = load_config(POPULATION).text.replace(
        f'name = "{POPULATION}"', 'name = "' + "x" * 90 + '"'
    )
    config = tmp_path / "long.toml"
    config.write_text(text)
    Session.create(db, str(config), "S01", seed=3).close()
    Session.create(db, POPULATION, "S02", seed=4).close()
    result = runner.invoke(app, ["session", "list", "--json", "--db", db])
    assert result.exit_code == 0, result.output
    assert result.stderr == ""
    rows = json.loads(result.stdout)
    assert [list(row) for row in rows] == [
        ["id", "subject", "config", "seed", "status", "imported_from", "events", "created",
         "updated"]
    ] * 2  # fmt: skip
    assert [(r["id"], r["subject"], r["config"], r["seed"]) for r in rows] == [
        (1, "S01", "x" * 90, 3),
        (2, "S02", POPULATION, 4),
    ]
    assert rows[0]["imported_from"] is None and rows[0]["created"].endswith("+00:00")
    only = runner.invoke(app, ["session", "list", "--json", "--subject", "S02", "--db", db])
    assert [r["id"] for r in json.loads(only.stdout)] == [2]
    empty = tmp_path / "empty.db"
    assert runner.invoke(app, ["db", "upgrade", "--db", str(empty)]).exit_code == 0
    none = runner.invoke(app, ["session", "list", "--json", "--db", str(empty)])
    assert none.exit_code == 0 and json.loads(none.stdout) == []


def _documented_statuses() -> dict[int, str]:
    page = Path(__file__).resolve().parents[2] / "docs" / "getting-started.md"
    section = page.read_text(encoding="utf-8").split("### In scripts: exit statuses and output")[1]
    rows = (line.split("|") for line in section.split("\n## ")[0].splitlines())
    return {int(r[1]): r[2] for r in rows if len(r) > 3 and r[1].strip().isdigit()}


def test_the_documented_statuses_are_the_ones_the_error_helper_uses() -> None:
    """Every status and error label of ``cli/output.py`` is in the docs' table, in its row."""
    from gaitpref.cli.output import FAMILIES

    documented = _documented_statuses()
    assert sorted(documented) == [0, 1, 2, 130]
    for _, label, status in FAMILIES:
        assert f"`{label}" in documented[status], (label, status)


def test_an_interrupt_exits_130(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """As documented: a script can tell Ctrl-C from a check that failed (``db check``: 1)."""
    import gaitpref.sessions.check as check

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(check, "check_database", interrupted)
    db = tmp_path / "lab.db"
    assert runner.invoke(app, ["db", "upgrade", "--db", str(db)]).exit_code == 0
    result = runner.invoke(app, ["db", "check", "--db", str(db)])
    assert result.exit_code == 130 and result.stdout == ""
    # the root group says so itself: earlier typer releases exited 1 ("Aborted!")
    import typer

    from gaitpref.cli.main import RootGroup

    group = typer.main.get_command(app)
    assert isinstance(group, RootGroup)
    ctx = group.make_context("gaitpref", ["db", "check", "--db", str(db)])
    with ctx, pytest.raises(typer.Exit) as stopped:
        group.invoke(ctx)
    assert stopped.value.exit_code == 130


def test_session_new_json_gives_the_id_to_a_script(tmp_path: Path) -> None:
    """A clinic's script creates a session and runs commands on it: the id was in a sentence
    (``session 1: subject S01, ...``) to parse."""
    db = str(tmp_path / "lab.db")
    args = ["session", "new", "--config", POPULATION, "--json", "--db", db]
    first = runner.invoke(app, [*args, "--subject", "S01", "--seed", "5"])
    assert first.exit_code == 0, first.output
    assert first.stderr == ""
    info = json.loads(first.stdout)
    assert info == {
        "id": 1,
        "subject": "S01",
        "config": POPULATION,
        "seed": 5,
        "db": f"sqlite:///{db}",
        "prior_from": [],
        "prior_rho": None,
    }
    second = runner.invoke(app, [*args, "--subject", "S02", "--prior-from", "S01"])
    assert second.exit_code == 0, second.output
    warm = json.loads(second.stdout)
    assert warm["id"] == 2 and [p["session"] for p in warm["prior_from"]] == [1]
    shown = json.loads(
        runner.invoke(app, ["session", "show", "2", "--json", "--no-figure", "--db", db]).stdout
    )
    assert shown["prior_from"] == warm["prior_from"] and shown["prior_rho"] == warm["prior_rho"]
    refused = runner.invoke(app, [*args, "--subject", "Jane Doe"])
    assert refused.exit_code == 2 and refused.stdout == "" and refused.stderr


def test_off_a_terminal_nothing_is_coloured_and_long_paths_are_not_wrapped(
    tmp_path: Path,
) -> None:
    """Run as a script runs it (pipes, ``COLUMNS`` unset, a colour ``TERM``): no ANSI codes on
    stdout or stderr, a path longer than 80 columns on one line, tables included."""
    from tests.cli.scriptkit import run_script

    folder = tmp_path / ("a" * 70) / ("b" * 70)
    folder.mkdir(parents=True)
    db = str(folder / "lab.db")
    runs = [
        run_script("session", "new", "--config", POPULATION, "--subject", "S01", "--db", db),
        run_script("session", "list", "--db", db),
        run_script("db", "check", "--db", db),
        run_script("session", "show", "9", "--no-figure", "--db", db),  # an error line
        run_script("configs"),
    ]
    for run in runs:
        assert "\x1b[" not in run.stdout + run.stderr, run.args
    new, listed, checked, missing, _ = runs
    assert new.returncode == 0 and f"--db {db}\n" in new.stdout  # one line, not folded
    assert listed.returncode == 0 and "S01" in listed.stdout
    assert checked.returncode == 0 and "the one session replays" in checked.stdout
    assert missing.returncode == 2 and missing.stdout == ""
    assert missing.stderr == f"storage error: no session 9 in sqlite:///{db}\n"


def test_configs_json_lists_every_shipped_config() -> None:
    from gaitpref.config import shipped_configs

    result = runner.invoke(app, ["configs", "--json"])
    assert result.exit_code == 0 and result.stderr == ""
    rows = json.loads(result.stdout)
    assert [r["name"] for r in rows] == list(shipped_configs())
    assert all(list(r) == ["name", "space", "n", "b", "description"] for r in rows)
    compass = next(r for r in rows if r["name"] == "compass-gait")
    assert (compass["n"], compass["b"]) == (2, 0) and compass["space"] == "24"
    table = runner.invoke(app, ["configs"])
    assert table.exit_code == 0 and "compass-gait" in table.stdout  # names whole at 80: below


def test_an_objective_that_prints_does_not_break_the_json(tmp_path: Path) -> None:
    """A lab's objective (``PATH.py:NAME``) that prints when imported or called put its lines
    on stdout before the JSON: ``json.loads`` of the output failed.  They go to stderr now."""
    source = tmp_path / "chatty.py"
    source.write_text(
        "import numpy as np\n"
        "print('loading chatty')\n"
        "def f(x):\n"
        "    print('evaluating', len(x))\n"
        "    return -np.sum((np.asarray(x) - 0.12) ** 2, axis=1)\n"
    )
    spec = f"{source}:f"
    for command in (
        ["simulate", POPULATION, "--objective", spec, "--trials", "3", "--json"],
        ["bench", "continuous", POPULATION, "--objective", spec, "--runs", "2", "--trials", "3",
         "--json"],
    ):  # fmt: skip
        result = runner.invoke(app, command)
        assert result.exit_code == 0, (command, result.output)
        assert isinstance(json.loads(result.stdout), dict), command
        assert "loading chatty" in result.stderr and "evaluating" in result.stderr, command
    grid = ["simulate", "exo-2d-rated", "--objective", spec, "--trials", "3", "--json"]
    rated = runner.invoke(app, [*grid, "--rating-quantiles", "0.25,0.5,0.75"])
    assert rated.exit_code == 0, rated.output  # a function over the grid's points, rated
    assert isinstance(json.loads(rated.stdout), dict) and "evaluating 90" in rated.stderr
    plain = runner.invoke(app, ["simulate", POPULATION, "--objective", spec, "--trials", "3"])
    assert plain.exit_code == 0 and "evaluating" in plain.stdout  # without --json, as before


def test_the_configs_table_names_every_config_whole_off_a_terminal() -> None:
    """At 80 columns off a terminal (a pipe), the configs table cut a long name to
    ``exo-2d-length-durati…``: a name that cannot be typed as shown.  Each is whole on its row."""
    from gaitpref.config import shipped_configs
    from tests.cli.scriptkit import run_script

    result = run_script("configs")
    assert result.returncode == 0 and result.stderr == ""
    assert "…" not in result.stdout
    assert max(len(line) for line in result.stdout.splitlines()) <= 80
    rows = [line.split("│")[1].strip() for line in result.stdout.splitlines() if "│" in line]
    assert set(shipped_configs()) <= set(rows)
