"""``gaitpref session validate ID --ranking R --gaits A,B,C``: a ranking typed in a later command
than the one that showed the round is checked against the gaits it showed.

A flag on a gait the open round shows draws the round again (same number, other gaits); the
answer command showed the round as it was then and booked the ranking against it, so a ranking
of the gaits walked before was recorded for gaits the subject never walked."""

from __future__ import annotations

from pathlib import Path

import pytest

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.loop.safety import near
from tests.cli.invokekit import invoke
from tests.sessions.test_unsafe import CONFIG as UNSAFE
from tests.sessions.test_unsafe import _answer


@pytest.fixture
def db(tmp_path: Path) -> str:
    """Session 1 after six answered trials (no round open yet)."""
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with Session.create(url, parse_config(UNSAFE), "S01") as s:
        for k in range(6):
            _answer(s, k)
    return url


def _shown(db: str) -> list[str]:
    with Session.open(db, 1) as s:
        return [g.gait for g in s.validation_gaits()]


def _command(db: str, gaits: list[str]) -> str:
    return f"gaitpref session validate 1 --db {db} --gaits {','.join(gaits)} --ranking RANKING"


def _show(db: str) -> str:
    """Show the round (opened now) and quit at the ranking prompt, as an operator who goes to
    walk the gaits first."""
    code, out = invoke("session", "validate", "1", "--db", db, answer="q\n")
    assert code == 0 and "Blind validation, round 1" in out
    return out


def _flag_a_shown_gait(db: str) -> None:
    """Another writer (the console) flags a trial near a gait the open round shows: the round
    is drawn again with the same number."""
    with Session.open(db, 1) as other:
        shown = [g.action for g in other.validation_gaits()]
        space = other.config.space
        trial = next(t for t in other.trials() if near(space, {t.action}, 0.15)[shown].any())
        assert other.flag_unsafe(trial.number, "knee gave way") is True
        assert other.validation_plan is not None and other.validation_plan.round == 1


def test_the_round_shown_prints_the_command_that_records_its_ranking(db: str) -> None:
    out = _show(db)
    command = _command(db, _shown(db))
    assert f"To record the ranking later: {command}" in out
    assert "No ranking recorded; the round stays open" in out
    # a round is answered or withdrawn (the rounds branch): it said "until it is answered"
    assert "until it is answered or withdrawn: gaitpref session validate 1 --withdraw" in out
    assert f"Record it with: {command}" in out


def test_the_ranking_of_the_gaits_shown_is_recorded(db: str) -> None:
    _show(db)
    gaits = ",".join(_shown(db))
    code, out = invoke(
        "session", "validate", "1", "--ranking", "BCA", "--gaits", gaits, "--db", db, "-y"
    )
    assert code == 0 and "Unblinded" in out, out
    with Session.open(db, 1) as s:
        [result] = s.validations()
        assert "".join(result.ranking) == "BCA"


def test_a_ranking_of_a_round_drawn_again_since_it_was_shown_is_refused(db: str) -> None:
    _show(db)
    walked = _shown(db)
    _flag_a_shown_gait(db)
    now = _shown(db)
    assert now != walked
    with Session.open(db, 1) as s:
        before = len(s.events())
    code, out = invoke(
        "session", "validate", "1", "--ranking", "BCA", "--gaits", ",".join(walked), "--db", db,
        "-y",
    )  # fmt: skip
    assert code == 2, out
    assert "the ranking BCA was not recorded: it ranks the gaits " + ", ".join(walked) in out
    assert f"validation round 1 shows {', '.join(now)} now (drawn again" in out
    assert "nothing was written" in out
    # the round is shown as it is now, with the command for its gaits
    assert f"To record the ranking later: {_command(db, now)}" in out
    with Session.open(db, 1) as s:
        assert len(s.events()) == before and s.validations() == []
    # the command shown records the ranking of the gaits as they are now
    code, out = invoke(
        "session", "validate", "1", "--ranking", "CAB", "--gaits", ",".join(now), "--db", db, "-y"
    )
    assert code == 0 and "Unblinded" in out, out


def test_without_gaits_the_redrawn_round_is_ranked_unnoticed(db: str) -> None:
    """The command line as before (no --gaits) still works: it ranks the round as it is when
    the command runs, which is why --gaits is there."""
    _show(db)
    _flag_a_shown_gait(db)
    code, out = invoke("session", "validate", "1", "--ranking", "BCA", "--db", db, "-y")
    assert code == 0 and "Unblinded" in out
    with Session.open(db, 1) as s:
        assert len(s.validations()) == 1


def test_gaits_with_no_round_open_opens_none_and_writes_nothing(db: str) -> None:
    _show(db)
    walked = _shown(db)
    with Session.open(db, 1) as other:  # another writer answered the round meanwhile
        other.answer_validation(1, "CBA")
        before = len(other.events())
    code, out = invoke(
        "session", "validate", "1", "--ranking", "BCA", "--gaits", ",".join(walked), "--db", db,
        "-y",
    )  # fmt: skip
    assert code == 2 and f"the ranking BCA of {', '.join(walked)} was not recorded" in out
    assert "no blind validation round is open" in out
    with Session.open(db, 1) as s:
        assert len(s.events()) == before and s.validation_plan is None


def test_gaits_need_a_ranking_and_names(db: str) -> None:
    code, out = invoke("session", "validate", "1", "--gaits", "G1,G2,G3", "--db", db)
    assert code == 2 and "--gaits checks the ranking given with --ranking" in out
    code, out = invoke(
        "session", "validate", "1", "--ranking", "ABC", "--gaits", "G1,,G3", "--db", db
    )
    assert code == 2 and "separated by commas" in out
    with Session.open(db, 1) as s:
        assert s.validation_plan is None  # nothing opened


def test_the_confirmation_names_the_gaits(db: str) -> None:
    _show(db)
    gaits = _shown(db)
    code, out = invoke(
        "session", "validate", "1", "--ranking", "ABC", "--gaits", ",".join(gaits), "--db", db,
        answer="n\n",
    )  # fmt: skip
    assert code == 1 and f"Record the ranking ABC of {', '.join(gaits)} for session 1?" in out
