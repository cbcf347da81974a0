"""Running the CLI in-process with an answer on stdin, its output with Rich's wrapping undone."""

from __future__ import annotations

from typer.testing import CliRunner

runner = CliRunner()


def invoke(*args: str, answer: str | None = None) -> tuple[int, str]:
    """``gaitpref ARGS`` with ``answer`` on stdin: the exit code and the output on one line
    (Rich wraps long lines at the runner's width, so words are joined by single spaces)."""
    from gaitpref.cli import app

    result = runner.invoke(app, list(args), input=answer)
    return result.exit_code, " ".join(result.output.split())
