"""``gaitpref session validate ID --withdraw --reason TEXT [--undo]``: an open, unanswered blind
validation round withdrawn from the command line (with the answer after which the ``[stop]``
rule opened it, given ``--undo``), refused naming the problem otherwise."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gaitpref import Session
from gaitpref.config import load_config, parse_config
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from tests.cli.invokekit import invoke

CONFIG = "exo-1d-step-length"


@pytest.fixture
def db(tmp_path: Path) -> str:
    """Session 1, whose ``[stop]`` rule (max_trials = 4) opened round 1 after its last answer."""
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    config = parse_config(
        load_config(CONFIG).text + "\n[stop]\nmax_trials = 4\n", default_name=CONFIG
    )
    subject = SimulatedSubject(config.space, bump_utility(config.space), seed=1)
    with Session.create(url, config, "S01") as s:
        while s.validation_plan is None:
            q = s.next_query()
            s.answer(q.id, *subject.respond(q))
    return url


def test_withdraw_with_undo_from_the_cli(db: str) -> None:
    with Session.open(db, 1) as s:
        last = s.trials()[-1]
        seq = s.last_seq
    code, out = invoke("session", "validate", "1", "--withdraw", "--reason", "typo", "--db", db,
                        answer="n\n")  # fmt: skip
    assert code == 1 and "nothing done" in out
    code, out = invoke(
        "session", "validate", "1", "--withdraw", "--reason", "mis-keyed", "--undo", "--db", db,
        answer="y\n",
    )  # fmt: skip
    assert code == 0, out
    assert f"and undo the answer to trial {last.number}, after which the [stop] rule" in out
    assert "validation round 1 withdrawn" in out
    assert f"undone: the answer to trial {last.number}" in out
    with Session.open(db, 1) as s:
        kinds = [(e.kind, e.payload) for e in s.events()[seq:]]
        assert kinds[0] == ("validation_withdrawn", {"round": 1, "reason": "mis-keyed"})
        assert kinds[1][0] == "undo"
        assert s.validation_plan is None and s.pending is not None
        assert s.pending.id == last.query  # its trial is asked again


def test_withdraw_without_a_round_or_reason_is_refused(db: str) -> None:
    code, out = invoke("session", "validate", "1", "--withdraw", "--db", db, "-y")
    assert code == 2 and "give --reason" in out
    code, out = invoke("session", "validate", "1", "--undo", "--db", db, "-y")
    assert code == 2 and "go with --withdraw" in out
    code, out = invoke(
        "session", "validate", "1", "--withdraw", "--reason", "x", "--ranking", "ABC", "--db", db
    )
    assert code == 2 and "takes no --ranking" in out
    code, out = invoke("session", "validate", "1", "--ranking", "ABC", "--db", db, "-y")
    assert code == 0, out
    code, out = invoke("session", "validate", "1", "--withdraw", "--reason", "x", "--db", db, "-y")
    assert code == 2 and "no open blind validation round: nothing to withdraw" in out


def test_undo_inside_a_round_says_how_to_withdraw_it(db: str) -> None:
    code, out = invoke("session", "undo", "1", "--db", db, "-y")
    assert code == 0, out
    assert "round 1 stays open" in out and "--withdraw --reason TEXT" in out
    # the answer that opened it is gone: --undo is refused, naming why; without it, taken
    code, out = invoke(
        "session", "validate", "1", "--withdraw", "--reason", "x", "--undo", "--db", db, "-y"
    )
    assert code == 2 and "no longer the last answer in force" in out
    code, out = invoke("session", "validate", "1", "--withdraw", "--reason", "x", "--db", db, "-y")
    assert code == 0 and "validation round 1 withdrawn" in out


def test_show_json_lists_who_opened_each_round_and_the_withdrawn_ones(db: str) -> None:
    """``validations`` (answered rounds) carry ``opened_by``; ``validation_rounds`` lists every
    round logged, the withdrawn one marked with its reason, the open one as open."""
    code, out = invoke("session", "validate", "1", "--withdraw", "--reason", "mis-keyed",
                       "--db", db, "-y")  # fmt: skip
    assert code == 0, out
    with Session.open(db, 1) as s:
        s.start_validation()  # round 2, the operator's
    code, out = invoke("session", "validate", "1", "--ranking", "ABC", "--db", db, "-y")
    assert code == 0, out
    with Session.open(db, 1) as s:
        s.start_validation()  # round 3, open
    code, out = invoke("session", "show", "1", "--json", "--no-figure", "--db", db)
    assert code == 0, out
    info = json.loads(out)
    assert [(v["round"], v["opened_by"]) for v in info["validations"]] == [(2, "operator")]
    assert info["validation_rounds"] == [
        {"round": 1, "opened_by": "rule", "status": "withdrawn", "withdrawn_reason": "mis-keyed"},
        {"round": 2, "opened_by": "operator", "status": "answered", "withdrawn_reason": None},
        {"round": 3, "opened_by": "operator", "status": "open", "withdrawn_reason": None},
    ]
