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
