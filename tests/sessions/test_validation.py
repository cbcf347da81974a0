"""Blind validation: max/mean/min of the posterior mean, a logged random order, unblinding."""

from __future__ import annotations

from collections import Counter
from dataclasses import fields

import numpy as np
import pytest

from gaitpref import Session, SessionStateError
from gaitpref.sessions.demo import SimulatedSubject
from gaitpref.sessions.validation import (
    BlindGait,
    ValidationPlan,
    blind_plan,
    check_ranking,
    kendall_tau,
    validation_actions,
)
from gaitpref.storage import MemoryStorage, Storage
from tests.sessions.sessionkit import CONFIG, Drive


def test_validation_actions() -> None:
    mean = np.array([0.0, 3.0, 1.0, 2.1, -1.0, 1.4])  # average 0.9167
    assert validation_actions(mean) == (1, 2, 4)
    with pytest.raises(ValueError, match="flat"):
        validation_actions(np.zeros(5))
    with pytest.raises(ValueError, match="at least 3"):
        validation_actions(np.array([1.0, 2.0]))


def test_kendall_tau() -> None:
    assert kendall_tau("ABC", "ABC") == 1.0
    assert kendall_tau("CBA", "ABC") == -1.0
    assert kendall_tau("BAC", "ABC") == pytest.approx(1 / 3)
    assert kendall_tau("BCA", "ABC") == pytest.approx(-1 / 3)
    with pytest.raises(ValueError):
        kendall_tau("ABD", "ABC")


def test_rankings_are_checked() -> None:
    assert check_ranking("bca", "ABC") == ("B", "C", "A")
    assert check_ranking(["C", "a", "B"], "ABC") == ("C", "A", "B")
    for bad in ("AB", "ABB", "ABCD", "", "XYZ"):
        with pytest.raises(ValueError, match="exactly once"):
            check_ranking(bad, "ABC")


def test_orders_are_uniform_and_labels_say_nothing() -> None:
    mean = np.linspace(-1, 1, 15) ** 3
    orders = Counter(
        tuple(blind_plan(1, mean, np.random.default_rng(k))[1].values()) for k in range(600)
    )
    assert len(orders) == 6 and min(orders.values()) > 60
    assert {f.name for f in fields(ValidationPlan)} == {"round", "gaits"}
    assert {f.name for f in fields(BlindGait)} == {"label", "action"}


def test_session_validation_round_trip(
    db: str | Storage, drive: Drive, subject: SimulatedSubject
) -> None:
    s = Session.create(db, CONFIG, "S01", seed=13)
    with pytest.raises(SessionStateError, match="flat"):
        s.start_validation()  # nothing learned yet
    drive(s, 15)
    plan = s.start_validation()
    assert s.start_validation() == plan  # the open round, not a new order
    assert plan.labels == ("A", "B", "C")
    started = s.events()[-1]
    assert started.kind == "validation_started" and started.payload["round"] == 1
    roles = {g["label"]: g["role"] for g in started.payload["gaits"]}
    assert sorted(roles.values()) == ["max", "mean", "min"]
    with pytest.raises(SessionStateError, match="open"):
        s.next_query()
    with pytest.raises(SessionStateError, match="exactly once"):
        s.answer_validation(1, "AAB")
    result = s.answer_validation(plan.round, subject.rank(plan))
    assert result.roles == roles
    assert result.agrees and result.kendall_tau == 1.0  # a noiseless subject, 15 trials
    assert [result.roles[label] for label in result.model_ranking] == ["max", "mean", "min"]
    assert s.validation_plan is None
    s.next_query()  # the session may go on after validating
    reopened = Session.open(db, s.id)
    assert reopened.validations() == [result]


def test_a_disagreeing_ranking(drive: Drive) -> None:
    s = Session.create(MemoryStorage(), CONFIG, "S01", seed=13)
    drive(s, 10)
    plan = s.start_validation()
    best_first = "".join(
        sorted(
            plan.labels,
            key=lambda lab: -s.posterior().mean[plan.gaits[plan.labels.index(lab)].action],
        )
    )
    result = s.answer_validation(plan.round, best_first[::-1])
    assert not result.agrees and result.kendall_tau == -1.0
    assert s.events()[-1].payload["agrees"] is False
    with pytest.raises(SessionStateError, match="not open"):
        s.answer_validation(plan.round, best_first)
    second = s.start_validation()
    assert second.round == 2


def test_an_answer_while_a_round_is_open_is_refused_and_waits_for_the_ranking(
    db: str | Storage, drive: Drive, subject: SimulatedSubject
) -> None:
    """A query pending when a round opened (or made pending again by an undo inside the round)
    was answered, moving the model the round was drawn from before its ranking came in."""
    s = Session.create(db, CONFIG, "S01", seed=13)
    drive(s, 8)
    q = s.next_query()
    plan = s.start_validation()
    before = s.last_seq
    comparisons, suggestions = subject.respond(q)
    with pytest.raises(SessionStateError) as err:
        s.answer(q.id, comparisons, suggestions)
    message = str(err.value)
    assert f"round {plan.round} is open" in message and "ranking" in message
    assert f"query {q.id} stays pending" in message.lower()
    assert s.last_seq == before == len(s.events()) and s.pending == q
    s.answer_validation(plan.round, subject.rank(plan))
    s.answer(q.id, comparisons, suggestions)  # the round answered: the query takes its answer
    assert s.pending is None and len(s.trials()) == 9
    # an undo inside a round makes the last query pending again: refused the same way
    drive(s, 1)
    plan = s.start_validation()
    again = s.undo()
    assert again is not None and s.pending == again
    with pytest.raises(SessionStateError, match=f"round {plan.round} is open"):
        s.answer(again.id, *subject.respond(again))


def test_a_log_that_answered_inside_a_round_still_replays(
    db: str | Storage,
    drive: Drive,
    subject: SimulatedSubject,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Earlier releases took such an answer: their logs open and replay as written."""
    s = Session.create(db, CONFIG, "S01", seed=13)
    drive(s, 8)
    q = s.next_query()
    plan = s.start_validation()
    with monkeypatch.context() as m:  # as an earlier release wrote it
        m.setattr(Session, "_check_no_open_round", lambda self, query: None)
        s.answer(q.id, *subject.respond(q))
    kinds = [e.kind for e in s.events()]
    assert "trial_executed" in kinds[kinds.index("validation_started") :]  # inside the round
    mean = np.asarray(s.posterior().mean).copy()
    reopened = Session.open(db, s.id)
    assert reopened.validation_plan == plan and reopened.last_seq == s.last_seq
    np.testing.assert_array_equal(np.asarray(reopened.posterior().mean), mean)
    assert reopened.trials() == s.trials()
    result = reopened.answer_validation(plan.round, subject.rank(plan))
    assert result.round == plan.round
