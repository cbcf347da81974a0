"""``gaitpref session undo``: when the undone answer's query was withdrawn (it proposes a gait
flagged unsafe since), the command says what is pending in its place - a new query, or none yet
while the session is paused or a blind validation round is open."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner

from gaitpref import Session
from tests.sessions.test_unsafe import _flag_then_undo

runner = CliRunner()
WITHDRAWN = "its query proposed a gait flagged unsafe since"


def _undo(url: str) -> str:
    from gaitpref.cli import app

    result = runner.invoke(app, ["session", "undo", "1", "--db", url, "-y"])
    assert result.exit_code == 0, result.output
    return " ".join(result.output.split())  # Rich wraps long lines


def test_undo_of_a_withdrawn_query_names_the_query_proposed_in_its_place(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'u.db'}"
    _flag_then_undo(url, pause=False)[0].close()
    out = _undo(url)
    with Session.open(url, 1) as s:
        assert s.pending is not None
        assert f"{WITHDRAWN}" in out
        assert f"a new query is proposed in its place (query {s.pending.id})" in out


def test_undo_of_a_withdrawn_query_while_paused_proposes_none_until_resumed(
    tmp_path: Path,
) -> None:
    url = f"sqlite:///{tmp_path / 'u.db'}"
    _flag_then_undo(url, pause=True)[0].close()
    out = _undo(url)
    assert WITHDRAWN in out
    assert "in its place yet: the next is proposed once the session is resumed" in out
    assert f"gaitpref session run 1 --db {url}" in out
    assert "a new query is proposed" not in out and "validation round" not in out
    with Session.open(url, 1) as s:
        assert s.pending is None and s.status == "paused"


def test_undo_of_a_withdrawn_query_inside_a_round_proposes_none_until_it_closes(
    tmp_path: Path,
) -> None:
    url = f"sqlite:///{tmp_path / 'u.db'}"
    s, _ = _flag_then_undo(url, pause=False)
    with s:
        number = s.start_validation().round
    out = _undo(url)
    assert WITHDRAWN in out
    assert (
        f"in its place yet: the next is proposed once blind validation round {number} is "
        "ranked or withdrawn" in out
    )
    assert "a new query is proposed" not in out and "resumed" not in out
    with Session.open(url, 1) as s:
        assert s.pending is None and s.validation_plan is not None


def test_withdrawing_a_round_with_an_undo_while_paused_says_the_query_is_withdrawn(
    tmp_path: Path,
) -> None:
    """The ``[stop]`` rule opens round 1 after trial 2 (gait 8); trial 1 (gait 6, near it) is
    flagged and the session paused: withdrawing the round with ``--undo`` takes back trial 2's
    answer, whose query is withdrawn, and none is proposed while paused (it said nothing)."""
    from gaitpref.cli import app
    from gaitpref.config import parse_config
    from tests.sessions.test_unsafe import CONFIG, _answer

    url = f"sqlite:///{tmp_path / 'u.db'}"
    with Session.create(url, parse_config(CONFIG + "\n[stop]\nmax_trials = 2\n"), "S01") as s:
        _answer(s, 0)
        _answer(s, 1)
        assert [t.action for t in s.trials()] == [6, 8] and s.validation_plan is not None
        s.flag_unsafe(1, "ankle pain")
        s.pause()
    result = runner.invoke(
        app, ["session", "validate", "1", "--withdraw", "--reason", "x", "--undo", "--db", url,
              "-y"],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    out = " ".join(result.output.split())
    assert "undone: the answer to trial 2" in out and WITHDRAWN in out
    assert "in its place yet: the next is proposed once the session is resumed" in out
    with Session.open(url, 1) as s:
        assert s.pending is None and s.validation_plan is None and s.status == "paused"
