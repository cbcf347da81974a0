"""A feedback kind defined outside gaitpref (here) is answered, stored, replayed, undone,
excluded and exported through ``Session`` without editing any gaitpref module.

The toy kind, "effort": after a trial the subject scores its effort from 0 (none) to 10; the
score is a Gaussian observation of that gait's utility, ``y = (5 - score) / 100``, noise 0.02:
a single-action likelihood term (``model/laplace.py``).
"""

from __future__ import annotations

import csv
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest

from gaitpref import FeedbackError, ReplayError, Session
from gaitpref.feedback import (
    ActionObservation,
    ExportTable,
    FeedbackKind,
    ModelContext,
    Observations,
    QueryView,
    TrialQuery,
    expect_fields,
    grid_index,
    register,
    unregister,
)
from gaitpref.payloads import EventPayload
from gaitpref.sessions import export_session, import_session

NOISE = 0.02


@dataclass(frozen=True)
class Effort:
    action: int
    score: int


class EffortGiven(EventPayload):
    kind: ClassVar[str] = "effort_scored"
    version: ClassVar[int] = 1
    query: int
    trial: int
    action: int
    score: int


def _score(observation: ActionObservation) -> int:
    """An effort observation's score (the value this kind's observations carry)."""
    assert isinstance(observation.value, int)
    return observation.value


@dataclass(frozen=True)
class GaussianEffort:
    y: np.ndarray

    def terms(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        r = self.y - values
        return -0.5 * (r / NOISE) ** 2, r / NOISE**2, np.full(values.shape, 1 / NOISE**2)


class EffortKind(FeedbackKind[Effort]):
    name: ClassVar[str] = "effort"
    record_type: ClassVar[type[Effort]] = Effort
    payload_type: ClassVar[type[EventPayload]] = EffortGiven
    export: ClassVar[ExportTable] = ExportTable("efforts", ("query", "trial", "action", "score"))

    def parse(self, raw: object, query: QueryView, context: ModelContext, where: str) -> Effort:
        if isinstance(raw, Effort):
            raw = (raw.action, raw.score)
        action, score = expect_fields(raw, ("action", "score"), where)
        a = grid_index(context.space, action, where)
        if a not in query.actions:
            raise FeedbackError(f"{where}: action {a} was not executed in this query")
        if isinstance(score, bool) or not isinstance(score, int) or not 0 <= score <= 10:
            raise FeedbackError(f"{where}: score must be an integer 0..10, got {score!r}")
        return Effort(a, score)

    def check_all(self, records: Sequence[Effort], query: QueryView) -> None:
        if len({r.action for r in records}) != len(records):
            raise FeedbackError("effort: one score per executed action")

    def observations(self, record: Effort, context: ModelContext, query_id: int) -> Observations:
        return Observations(
            singles=(ActionObservation(record.action, self.name, record.score, query_id),)
        )

    def action_likelihood(
        self, observations: Sequence[ActionObservation], context: ModelContext
    ) -> GaussianEffort:
        return GaussianEffort(np.array([(5 - _score(o)) / 100 for o in observations]))

    def payload(self, record: Effort, query: TrialQuery, context: ModelContext) -> EventPayload:
        return EffortGiven(
            query=query.id,
            trial=query.trial_of(record.action),
            action=record.action,
            score=record.score,
        )

    def from_payload(self, payload: EventPayload) -> Effort:
        assert isinstance(payload, EffortGiven)
        return Effort(payload.action, payload.score)


@pytest.fixture
def effort() -> Iterator[None]:
    register(EffortKind())
    yield
    unregister("effort")


def _run(url: str, efforts: bool, n: int = 6) -> Session:
    session = Session.create(url, "exo-1d-step-length", "S01", seed=3)
    for k in range(n):
        q = session.next_query()
        a = q.actions[0]
        answers: list[object] = [(a, q.buffer[0], "first")] if q.buffer else []
        if efforts:
            answers.append(Effort(a, (3 * k) % 11))
        session.answer(q.id, answers, [(a, "step_length", "+small")])
    return session


def test_answered_stored_and_replayed(effort: None, tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'a.db'}"
    with _run(url, efforts=True) as s:
        mean = np.asarray(s.posterior().mean).copy()
        kinds = [e.kind for e in s.events()]
        entries = s.feedback()
        sid = s.id
    assert kinds.count("effort_scored") == 6
    assert [e.payload["score"] for e in entries] == [(3 * k) % 11 for k in range(6)]
    with Session.open(url, sid) as again:
        assert np.array_equal(np.asarray(again.posterior().mean), mean)
        assert again.feedback() == entries
    with _run(f"sqlite:///{tmp_path / 'b.db'}", efforts=False) as plain:
        assert not np.allclose(np.asarray(plain.posterior().mean), mean)


def test_single_terms_enter_the_model(effort: None) -> None:
    from gaitpref.storage import MemoryStorage

    s = Session.create(MemoryStorage(), "exo-1d-step-length", "S01", seed=3)
    q = s.next_query()
    a = q.actions[0]
    done = s.answer(q.id, [Effort(a, 0)])
    assert done.singles == 1 and done.preferences == 0
    post = s.posterior()
    # score 0: y = +0.05 observed with noise 0.02 pulls the utility of a up from 0
    assert float(np.asarray(post.mean)[a]) > 0.03


def test_refused_answer_writes_nothing(effort: None, tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'a.db'}"
    with Session.create(url, "exo-1d-step-length", "S01", seed=3) as s:
        q = s.next_query()
        before = s.last_seq
        with pytest.raises(FeedbackError, match="effort 0: score must be an integer"):
            s.answer(q.id, [Effort(q.actions[0], 11)])
        assert s.last_seq == before


def test_undo_and_exclude_flag_it(effort: None, tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'a.db'}"
    with _run(url, efforts=True, n=4) as s:
        s.undo()
        assert s.feedback()[-1].undone
        q = s.next_query()
        s.answer(q.id, [Effort(q.actions[0], 9)])
        s.exclude(2, "stumble")
        flagged = [e.excluded for e in s.feedback() if not e.undone]
        assert flagged == [False, True, False, False]
        mean = np.asarray(s.posterior().mean).copy()
        sid = s.id
    with Session.open(url, sid) as again:
        assert np.array_equal(np.asarray(again.posterior().mean), mean)
        assert [e.excluded for e in again.feedback() if not e.undone] == flagged


def test_exported_and_imported(effort: None, tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'a.db'}"
    with _run(url, efforts=True, n=3) as s:
        export_session(s, tmp_path / "out")
        mean = np.asarray(s.posterior().mean).copy()
    with (tmp_path / "out" / "efforts.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [r["score"] for r in rows] == ["0", "3", "6"]
    assert set(rows[0]) == {"seq", "query", "trial", "action", "score", "undone", "excluded", "at"}
    copy = import_session(f"sqlite:///{tmp_path / 'b.db'}", tmp_path / "out")
    with copy:
        assert np.array_equal(np.asarray(copy.posterior().mean), mean)


def test_a_kind_that_is_not_registered_stops_replay_by_name(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'a.db'}"
    register(EffortKind())
    try:
        with _run(url, efforts=True, n=2) as s:
            sid = s.id
    finally:
        unregister("effort")
    with pytest.raises(ReplayError, match="effort_scored"):
        Session.open(url, sid)
