"""Commands that take something back or close a session ask first (``--yes`` skips the question)."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from gaitpref import Session, load_config
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from tests.sessions.sessionkit import CONFIG

runner = CliRunner()


@pytest.fixture
def db(tmp_path: Path) -> str:
    """A session with four answered trials (a simulated subject, seeded)."""
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    space = load_config(CONFIG).space
    subject = SimulatedSubject(space, bump_utility(space), seed=1)
    with Session.create(url, CONFIG, "S01", seed=2) as session:
        for _ in range(4):
            q = session.next_query()
            session.answer(q.id, *subject.respond(q))
    return url


def _invoke(*args: str, answer: str | None = None) -> tuple[int, str]:
    from gaitpref.cli import app

    result = runner.invoke(app, list(args), input=answer)
    return result.exit_code, result.output


def _answers(db: str) -> int:
    with Session.open(db, 1) as s:
        return sum(not c.undone for c in s.comparisons())


def test_undo_asks_and_no_keeps_the_answer(db: str) -> None:
    before = _answers(db)
    code, out = _invoke("session", "undo", "1", "--db", db, answer="n\n")
    assert code == 1 and "Undo the last answer of session 1?" in out and "nothing done" in out
    assert _answers(db) == before
    code, out = _invoke("session", "undo", "1", "--db", db, answer="y\n")
    assert code == 0 and "undone: the answer to trial 4" in out
    assert _answers(db) == before - 1


def test_undo_without_a_terminal_does_nothing_unless_yes(db: str) -> None:
    before = _answers(db)
    code, _ = _invoke("session", "undo", "1", "--db", db)  # no input: the question fails
    assert code != 0 and _answers(db) == before
    code, _ = _invoke("session", "undo", "1", "--db", db, "--yes")
    assert code == 0 and _answers(db) == before - 1


def test_finish_asks(db: str) -> None:
    code, out = _invoke("session", "finish", "1", "--db", db, answer="n\n")
    assert code == 1 and "It will take no more answers" in out
    assert Session.open(db, 1).status != "finished"
    code, _ = _invoke("session", "finish", "1", "--db", db, "-y")
    assert code == 0 and Session.open(db, 1).status == "finished"


def test_a_ranking_given_on_the_command_line_is_confirmed(db: str) -> None:
    code, out = _invoke("session", "validate", "1", "--ranking", "ABC", "--db", db, answer="n\n")
    assert code == 1 and "Record the ranking ABC for session 1?" in out
    assert Session.open(db, 1).validations() == []
    code, out = _invoke("session", "validate", "1", "--ranking", "ABC", "--db", db, answer="y\n")
    assert code == 0 and "Unblinded" in out
    assert len(Session.open(db, 1).validations()) == 1


def test_quitting_the_ranking_prompt_says_the_round_stays_open(db: str) -> None:
    """It ended silently with status 0, the round left open."""
    code, out = _invoke("session", "validate", "1", "--db", db, answer="q\n")
    assert code == 0 and "The subject's ranking, best first" in out
    assert "u withdraw the round, q quit" in " ".join(out.split())  # the prompt's keys
    assert "No ranking recorded; the round stays open" in out
    assert f"Record it with: gaitpref session validate 1 --db {db}" in " ".join(out.split())
    with Session.open(db, 1) as s:
        assert s.validations() == [] and s.validation_plan is not None


def test_the_question_goes_to_stderr_and_a_closed_stdin_is_a_no(db: str) -> None:
    """A script capturing stdout (``out=$(gaitpref session finish 1)``) hid the question, and
    the command seemed to hang; with stdin at its end it printed click's bare ``Aborted!``."""
    from gaitpref.cli import app

    result = runner.invoke(app, ["session", "finish", "1", "--db", db])  # stdin: empty
    assert result.exit_code == 1
    assert result.stdout == ""
    assert "Finish session 1? It will take no more answers. [y/N]: " in result.stderr
    assert "no answer (stdin ended): nothing done; give --yes" in result.stderr
    assert "Aborted" not in result.output
    assert Session.open(db, 1).status != "finished"
    result = runner.invoke(app, ["session", "undo", "1", "--db", db], input="maybe\nn\n")
    assert result.exit_code == 1 and result.stdout == ""
    assert "answer y or n" in result.stderr and result.stderr.count("[y/N]") == 2
    assert result.stderr.endswith("nothing done\n")


def test_a_script_without_stdin_is_refused_at_once_and_stdout_holds_only_the_result(
    db: str,
) -> None:
    """Run as a script runs it (``subprocess``, stdin ``/dev/null``): no hang, status 1, nothing
    done; with ``--yes`` status 0 and stdout holds the result line alone."""
    from tests.cli.scriptkit import run_script

    run = run_script("session", "finish", "1", "--db", db)
    assert run.returncode == 1 and run.stdout == ""
    assert "give --yes" in run.stderr
    assert Session.open(db, 1).status != "finished"
    run = run_script("session", "finish", "1", "--db", db, "--yes")
    assert run.returncode == 0, run.stderr
    assert run.stdout == "session 1 finished\n" and run.stderr == ""


def test_undo_with_nothing_to_undo_says_so_before_asking(tmp_path: Path) -> None:
    """It asked "Undo the last answer of session 1?" and only after a yes said nothing was
    there to undo."""
    url = f"sqlite:///{tmp_path / 'empty.db'}"
    Session.create(url, CONFIG, "S01").close()
    code, out = _invoke("session", "undo", "1", "--db", url, answer="y\n")
    assert code == 2 and "nothing to undo" in out and "Undo the last answer" not in out
