"""Undo and exclusion: both are events; the model goes exactly where it should."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import Session, SessionStateError
from gaitpref.storage import MemoryStorage, Storage
from tests.sessions.sessionkit import CONFIG, Drive, state_of


def _comparisons(q: object, outcome: str) -> list[tuple[int, int, str]]:
    return [(q.actions[0], b, outcome) for b in q.buffer if b != q.actions[0]]  # type: ignore[attr-defined]


def _different_first_answer(db: str | Storage, drive: Drive, undo_twice: bool) -> None:
    seed = 21
    a = Session.create(db, CONFIG, "S01", seed=seed)
    b = Session.create(MemoryStorage(), CONFIG, "S01", seed=seed)
    drive(a, 4)
    drive(b, 4)
    if undo_twice:  # one more answer, taken back too
        q = a.next_query()
        a.answer(q.id, _comparisons(q, "second"), [(q.actions[0], "step_length", "-big")])
        a.next_query()
    q = a.next_query()
    a.answer(q.id, _comparisons(q, "first"), [(q.actions[0], "step_length", "+big")])
    a.next_query()  # the following query is issued, then discarded by the undo
    if undo_twice:
        a.undo()
    pending = a.undo()
    assert pending is not None
    assert pending == q if not undo_twice else pending.trials == (5,)
    qa, qb = a.next_query(), b.next_query()
    assert (qa.actions, qa.buffer, qa.trials) == (qb.actions, qb.buffer, qb.trials)
    a.answer(qa.id, _comparisons(qa, "second"), [])
    b.answer(qb.id, _comparisons(qb, "second"), [])
    mean_a, var_a, next_a, rng_a = state_of(a)
    mean_b, var_b, next_b, rng_b = state_of(b)
    np.testing.assert_array_equal(mean_a, mean_b)
    np.testing.assert_array_equal(var_a, var_b)
    assert (next_a.actions, next_a.buffer) == (next_b.actions, next_b.buffer)  # type: ignore[attr-defined]
    assert rng_a == rng_b
    assert [e.kind for e in a.events()].count("undo") == (2 if undo_twice else 1)
    reopened = Session.open(db, a.id)
    np.testing.assert_array_equal(reopened.posterior().mean, mean_a)


@pytest.mark.parametrize("undo_twice", [False, True])
def test_answer_undo_answer_differently_equals_answering_differently(
    db: str | Storage, drive: Drive, undo_twice: bool
) -> None:
    _different_first_answer(db, drive, undo_twice)


def test_undo_brings_back_the_posterior_and_query(db: str | Storage, drive: Drive) -> None:
    s = Session.create(db, CONFIG, "S01", seed=4)
    drive(s, 3)
    mean, _, query, rng = state_of(s)
    s.answer(query.id, _comparisons(query, "first"), [])  # type: ignore[attr-defined]
    assert s.undo() == query
    mean2, _, query2, rng2 = state_of(s)
    np.testing.assert_array_equal(mean2, mean)
    assert query2 == query and rng2 == rng
    undone = [t for t in s.trials(include_undone=True) if t.undone]
    assert [t.number for t in undone] == [4]


def test_undo_with_nothing_to_undo_writes_nothing(db: str | Storage) -> None:
    s = Session.create(db, CONFIG, "S01")
    s.next_query()
    before = len(s.events())
    with pytest.raises(SessionStateError, match="nothing to undo"):
        s.undo()
    assert len(s.events()) == before


def _refit_without(s: Session, trial: int) -> np.ndarray:
    """The posterior fitted from scratch on every preference not touching ``trial``."""
    loop = s._state.loop
    keep = []
    for told in s._state.told:
        q = told.query
        bad_members = {a for t, a in zip(q.member_trials, q.members, strict=True) if t == trial}
        bad_exec = {a for t, a in zip(q.trials, q.actions, strict=True) if t == trial}
        for p in told.answer.preferences:
            if p.source == "comparison" and ({p.winner, p.loser} & bad_members):
                continue
            if p.source == "coactive" and p.loser in bad_exec:
                continue
            keep.append(p)
    post = loop.gp.posterior(
        [p.winner for p in keep], [p.loser for p in keep], [p.noise for p in keep]
    )
    return np.asarray(post.mean)


def test_excluding_a_trial_equals_never_having_its_comparisons(
    db: str | Storage, drive: Drive
) -> None:
    s = Session.create(db, CONFIG, "S01", seed=8)
    drive(s, 8)
    n_events = len(s.events())
    trial = s.exclude(5, "stumble", "caught a toe")
    assert trial.excluded == "stumble" and trial.exclusion_detail == "caught a toe"
    np.testing.assert_allclose(s.posterior().mean, _refit_without(s, 5), rtol=0, atol=1e-9)
    flagged = [(c.first_trial, c.second_trial) for c in s.comparisons() if c.excluded]
    assert flagged == [(5, 4), (6, 5)]  # trial 5 against its buffer, and trial 6 against it
    assert [x.trial for x in s.suggestions() if x.excluded] in ([5], [])
    assert len(s.comparisons()) == 7 and len(s.events()) == n_events + 1  # the record stays
    reopened = Session.open(db, s.id)
    np.testing.assert_array_equal(reopened.posterior().mean, s.posterior().mean)


def test_a_later_answer_against_an_excluded_trial_leaves_the_model(
    db: str | Storage, drive: Drive
) -> None:
    s = Session.create(db, CONFIG, "S01", seed=8)
    drive(s, 4)
    q = s.next_query()  # compares trial 5 with trial 4
    s.exclude(4, "distracted")
    s.answer(q.id, _comparisons(q, "first"), [])
    assert [c.excluded for c in s.comparisons()][-1] is True
    np.testing.assert_allclose(s.posterior().mean, _refit_without(s, 4), rtol=0, atol=1e-9)


def test_bad_exclusions_are_refused_and_write_nothing(db: str | Storage, drive: Drive) -> None:
    s = Session.create(db, CONFIG, "S01")
    drive(s, 3)
    s.exclude(2, "other", "subject coughing")
    before = len(s.events())
    with pytest.raises(SessionStateError, match="no trial 7"):
        s.exclude(7, "stumble")
    with pytest.raises(SessionStateError, match="already excluded"):
        s.exclude(2, "stumble")
    with pytest.raises(ValueError, match="reason must be one of"):
        s.exclude(1, "bored")
    s.exclude(3, "device_fault")
    with pytest.raises(SessionStateError, match="cannot be undone"):
        s.undo()
    assert len(s.events()) == before + 1
