"""One error helper for the whole CLI, help texts, confirmations and the console extra."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
import typer
from typer.testing import CliRunner

from gaitpref import errors, load_config
from gaitpref.cli import app
from gaitpref.cli.output import exit_for
from gaitpref.storage import SessionNotFoundError

runner = CliRunner()


@pytest.mark.parametrize(
    ("exc", "line", "code"),
    [
        (errors.ConfigError("[model]: unknown key 'noize'"), "config error: [model]: unknown", 2),
        (SessionNotFoundError("no session 7"), "storage error: no session 7", 2),
        (errors.FeedbackError("bad move"), "answer refused: bad move", 2),
        (errors.QueryError("stale query 3"), "answer refused: stale query 3", 2),
        (errors.SessionStateError("session 1 is finished"), "session error: session 1", 2),
        (errors.GaitLibraryError("gait g9: no such id"), "gait error: gait g9", 2),
        (errors.ConvergenceError("Newton: 50 steps"), "model error: Newton: 50 steps", 1),
        (errors.GaitprefError("other"), "error: other", 2),
        (ValueError("plain"), "error: plain", 2),
    ],
)
def test_each_family_has_one_message_and_status(exc: Exception, line: str, code: int) -> None:
    said, status = exit_for(exc)
    assert said.startswith(line) and status == code


def test_an_error_it_does_not_know_is_not_swallowed() -> None:
    with pytest.raises(TypeError, match="KeyError is not an error the CLI reports"):
        exit_for(KeyError("x"))


def test_a_config_error_prints_its_own_words(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    text = Path("src/gaitpref/config/shipped/exo-1d-step-length.toml").read_text()
    bad.write_text(text.replace("[model]", "[model]\nnoize = 0.1", 1))
    with pytest.raises(errors.ConfigError) as raised:
        load_config(str(bad))
    result = runner.invoke(app, ["simulate", str(bad), "--objective", "x.npy"])
    assert result.exit_code == 2
    assert f"config error: {raised.value}" in " ".join(result.output.split())
    assert "noize" in result.output and "error: :" not in result.output


def _commands(group: object, prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    out = [prefix]
    for name, cmd in getattr(group, "commands", {}).items():
        if hasattr(cmd, "commands"):
            out += _commands(cmd, (*prefix, name))
        else:
            out.append((*prefix, name))
    return out


def test_help_shows_no_bool_placeholder_anywhere() -> None:
    paths = _commands(typer.main.get_command(app))
    assert ("session", "undo") in paths and ("console",) in paths and len(paths) > 20
    for path in paths:
        result = runner.invoke(app, [*path, "--help"])
        assert result.exit_code == 0, (path, result.output)
        assert "<bool>" not in result.output, path
        assert "--help" in result.output


def test_console_help_lists_its_options_not_a_command() -> None:
    result = runner.invoke(app, ["console", "--help"])
    assert result.exit_code == 0
    assert "COMMAND [ARGS]" not in result.output
    assert "--port" in result.output and "--token" in result.output


def test_console_without_the_extra_says_how_to_install_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(sys.modules, "uvicorn", None)  # `import uvicorn` now fails
    result = runner.invoke(app, ["console", "--port", "8123"])
    assert result.exit_code == 2
    text = " ".join(result.output.split())
    assert "module 'uvicorn' is not installed" in text
    assert "pip install 'gaitpref[console]'" in text


def test_console_reraises_a_missing_module_that_is_not_a_web_one(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setitem(sys.modules, "gaitpref.console.app", None)
    result = runner.invoke(app, ["console"])
    assert isinstance(result.exception, ModuleNotFoundError)


def test_simulate_says_what_its_time_is(tmp_path: Path) -> None:
    import numpy as np

    path = tmp_path / "obj.npy"
    np.save(path, np.linspace(0.0, 1.0, 24))
    result = runner.invoke(
        app, ["simulate", "configs/compass-gait.toml", "--objective", str(path), "--trials", "4"]
    )
    assert result.exit_code == 0, result.output
    assert "simulated 4 trials in" in result.output and "s (wall clock)" in result.output
    assert not any(line.strip().endswith(" s") and len(line.split()) == 2
                   for line in result.output.splitlines())  # fmt: skip


@pytest.mark.parametrize("name", ["lab [/bold] [red]x", "exo [v2]", "a [b]c[/b] d"])
def test_names_and_notes_print_as_they_are_not_as_rich_markup(tmp_path: Path, name: str) -> None:
    """A config name (or a note, a reason) with brackets was read as Rich markup: "[v2]"
    vanished from listings and "[/bold]" raised MarkupError after the session was created."""
    text = load_config("exo-1d-step-length").text
    config = tmp_path / "c.toml"
    config.write_text(f"name = {name!r}\n" + "\n".join(
        line for line in text.splitlines() if not line.startswith("name =")
    ))  # fmt: skip
    db = str(tmp_path / "s.db")
    new = runner.invoke(
        app, ["session", "new", "--config", str(config), "--subject", "S01", "--db", db]
    )
    assert new.exit_code == 0, new.output
    assert f"config {name}," in new.output
    assert runner.invoke(app, ["session", "note", "1", f"check {name}", "--db", db]).exit_code == 0
    listed = runner.invoke(app, ["session", "list", "--db", db])
    assert listed.exit_code == 0, listed.output
    assert all(word in listed.output for word in name.split())  # a narrow table wraps it
    shown = runner.invoke(app, ["session", "show", "1", "--db", db, "--no-figure"])
    assert shown.exit_code == 0 and f"S01, {name}, seed" in shown.output
