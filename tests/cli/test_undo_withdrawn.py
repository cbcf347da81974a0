"""``gaitpref session undo``: when the undone answer's query was withdrawn (it proposes a gait
flagged unsafe since), the command says what is pending in its place - a new query, or none yet
while the session is paused or a blind validation round is open."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
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


def _refuse_new_queries(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """The database fails every write of a new query (a disk I/O error): the undo before it is
    written, the query drawn in place of the one it withdrew is not.  Returns a list that
    counts the writes refused."""
    from gaitpref.storage import StorageFailureError
    from gaitpref.storage.sql import SQLStorage

    append = SQLStorage.append
    refused: list[int] = []

    def failing(self: SQLStorage, *args: Any, **kwargs: Any) -> Any:
        if any(e.kind == "query_issued" for e in args[2]):
            refused.append(1)
            raise StorageFailureError(f"{self.url}: disk I/O error; nothing was written")
        return append(self, *args, **kwargs)

    monkeypatch.setattr(SQLStorage, "append", failing)
    return refused


def test_undo_whose_new_query_the_database_refuses_says_the_undo_is_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The undo is written, the query in place of its withdrawn one is not: the command says
    the answer is undone and that the new query is proposed at the next ask, then the error,
    and exits with status 1 (status 2 says nothing was written; it said only the error)."""
    from gaitpref.cli import app

    url = f"sqlite:///{tmp_path / 'u.db'}"
    _flag_then_undo(url, pause=False)[0].close()
    refused = _refuse_new_queries(monkeypatch)
    result = runner.invoke(app, ["session", "undo", "1", "--db", url, "-y"])
    out = " ".join(result.output.split())
    assert refused and result.exit_code == 1, out
    assert "undone: the answer to trial 2" in out
    assert (
        f"{WITHDRAWN}, or in the region of avoidance now, and was withdrawn, but the new query "
        "drawn in its place was not written (the error below says why): it is proposed at the "
        f"next ask (gaitpref session run 1 --db {url})" in out
    )
    assert "storage error: the undo is written; the query drawn in place of the one" in out
    monkeypatch.undo()
    with Session.open(url, 1) as s:
        assert [t.number for t in s.trials()] == [1] and s.pending is None
        assert s.next_query().trials == (2,)  # proposed at the next ask


def test_withdraw_undo_whose_new_query_the_database_refuses_says_the_round_is_withdrawn(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``session validate --withdraw --undo``: the withdrawal and the undo are written, the new
    query in place of the undone one's (a gait flagged since) is not: it says the round is
    withdrawn and the answer undone, then the error, with status 1 (it printed only 'storage
    error: the undo is written; ...' with status 2)."""
    from gaitpref.cli import app
    from gaitpref.config import parse_config
    from tests.sessions.test_unsafe import CONFIG, _answer

    url = f"sqlite:///{tmp_path / 'u.db'}"
    with Session.create(url, parse_config(CONFIG + "\n[stop]\nmax_trials = 2\n"), "S01") as s:
        _answer(s, 0)
        _answer(s, 1)
        assert [t.action for t in s.trials()] == [6, 8] and s.validation_plan is not None
        s.flag_unsafe(1, "ankle pain")
    refused = _refuse_new_queries(monkeypatch)
    result = runner.invoke(
        app, ["session", "validate", "1", "--withdraw", "--reason", "x", "--undo", "--db", url,
              "-y"],
    )  # fmt: skip
    out = " ".join(result.output.split())
    assert refused and result.exit_code == 1, out
    assert "validation round 1 withdrawn; its log stays" in out
    assert "undone: the answer to trial 2" in out
    assert "was not written (the error below says why): it is proposed at the next ask" in out
    assert "storage error: the undo is written" in out
    monkeypatch.undo()
    with Session.open(url, 1) as s:
        assert s.validation_plan is None and s.pending is None
        assert [r.withdrawn for r in s.validation_rounds()] == ["x"]
        assert [t.number for t in s.trials()] == [1]


def test_withdraw_undo_refused_by_the_database_writes_nothing_and_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A failure of the withdrawal's own write: nothing written, status 2, no 'withdrawn'."""
    from gaitpref.cli import app
    from gaitpref.config import parse_config
    from gaitpref.storage import StorageFailureError
    from gaitpref.storage.sql import SQLStorage
    from tests.sessions.test_unsafe import CONFIG, _answer

    url = f"sqlite:///{tmp_path / 'u.db'}"
    with Session.create(url, parse_config(CONFIG + "\n[stop]\nmax_trials = 2\n"), "S01") as s:
        _answer(s, 0)
        _answer(s, 1)

    def failing(self: SQLStorage, *args: Any, **kwargs: Any) -> Any:
        raise StorageFailureError(f"{self.url}: disk I/O error; nothing was written")

    monkeypatch.setattr(SQLStorage, "append", failing)
    result = runner.invoke(
        app, ["session", "validate", "1", "--withdraw", "--reason", "x", "--undo", "--db", url,
              "-y"],
    )  # fmt: skip
    out = " ".join(result.output.split())
    assert result.exit_code == 2, out
    assert "withdrawn" not in out and "undone" not in out
    assert "storage error:" in out
