"""``CoSpar`` with ``fit = "evidence"`` and ratings: a rating-like feedback kind written here (an
ordinal scale with thresholds left to the evidence) is told with comparisons; the loop refits
with the ratings, learns increasing thresholds, uses them in its posterior, and a second loop
told the same answers replays it exactly.  A kind whose likelihood has no ``third`` is refused
by name, and a loop without ratings refits as before (no thresholds in its records)."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from gaitpref import FeedbackError, Space, SquaredExponential
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
from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.learning import Learning
from gaitpref.model.likelihood import ActionLikelihood
from gaitpref.model.ordinal import Ordinal, OrdinalLikelihood, rating_likelihood
from gaitpref.payloads import EventPayload

VARIANCE, NOISE = 0.005, 0.02
SCALE = Ordinal(("bad", "okay", "good"), noise=NOISE)  # thresholds left to the evidence


@dataclass(frozen=True)
class Stars:
    action: int
    label: int


class StarsGiven(EventPayload):
    kind: ClassVar[str] = "stars_given"
    version: ClassVar[int] = 1
    query: int
    trial: int
    action: int
    label: int


class StarsKind(FeedbackKind[Stars]):
    name: ClassVar[str] = "stars"
    record_type: ClassVar[type[Stars]] = Stars
    payload_type: ClassVar[type[EventPayload]] = StarsGiven
    export: ClassVar[ExportTable] = ExportTable("stars", ("query", "trial", "action", "label"))

    def __init__(self, with_third: bool = True) -> None:
        self.with_third = with_third

    def parse(self, raw: object, query: QueryView, context: ModelContext, where: str) -> Stars:
        if isinstance(raw, Stars):
            raw = (raw.action, raw.label)
        action, label = expect_fields(raw, ("action", "label"), where)
        a = grid_index(context.space, action, where)
        if a not in query.actions:
            raise FeedbackError(f"{where}: action {a} was not executed in this query")
        return Stars(a, SCALE.label_index(label))

    def observations(self, record: Stars, context: ModelContext, query_id: int) -> Observations:
        return Observations(
            singles=(ActionObservation(record.action, self.name, record.label, query_id),)
        )

    def action_likelihood(
        self, observations: Sequence[ActionObservation], context: ModelContext
    ) -> ActionLikelihood:
        lik = rating_likelihood(SCALE, VARIANCE, [int(str(o.value)) for o in observations])
        return lik if self.with_third else _TermsOnly(lik)

    def payload(self, record: Stars, query: TrialQuery, context: ModelContext) -> EventPayload:
        trial = query.trial_of(record.action)
        return StarsGiven(query=query.id, trial=trial, action=record.action, label=record.label)

    def from_payload(self, payload: EventPayload) -> Stars:
        assert isinstance(payload, StarsGiven)
        return Stars(payload.action, payload.label)


@dataclass(frozen=True)
class _TermsOnly:
    inner: OrdinalLikelihood

    def terms(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.inner.terms(values)


@pytest.fixture
def stars() -> Iterator[StarsKind]:
    kind = StarsKind()
    register(kind)
    yield kind
    unregister("stars")


def _utility(space: Space) -> np.ndarray:
    x = space.points
    return 0.08 * np.exp(-((x[:, 0] - 0.14) ** 2) / 0.001 - ((x[:, 1] - 1.0) ** 2) / 0.02)


def _loop(space: Space, kernel: SquaredExponential) -> CoSpar:
    learning = Learning(fit="evidence", refit_every=3)
    return CoSpar(space, kernel, NOISE, n=1, buffer=1, seed=11, learning=learning)


def _play(loop: CoSpar, rated: bool, n: int = 9) -> list[list[object]]:
    f = _utility(loop.space)
    cuts = np.quantile(f, [1 / 3, 2 / 3])
    told: list[list[object]] = []
    for _ in range(n):
        q = loop.ask()
        a = q.actions[0]
        answers: list[object] = []
        if q.buffer:
            b = q.buffer[0]
            answers.append((a, b, "first" if f[a] > f[b] else "second"))
        if rated:
            answers.append(Stars(a, 1 + int(np.searchsorted(cuts, f[a]))))
        loop.tell(q, answers)
        told.append(answers)
    return told


def test_refits_learn_ordered_thresholds_and_replay_identically(
    stars: StarsKind, small_space: Space, small_kernel: SquaredExponential
) -> None:
    loop = _loop(small_space, small_kernel)
    told = _play(loop, rated=True)
    assert len(loop.refits) == 3
    for refit in loop.refits:
        assert refit.failed_evaluations == 0, refit.message
        assert refit.observations > 0
    assert loop.refits[0].before.thresholds is None
    fitted = [r.after.thresholds for r in loop.refits if r.accepted]
    assert fitted and all(t is not None and np.all(np.diff(t) > 0) for t in fitted)
    assert loop.hyper.thresholds == loop.refits[-1].after.thresholds
    record = loop.refits[-1].to_json()["after"]
    assert isinstance(record, dict) and record["thresholds"] == list(loop.hyper.thresholds or ())
    # the posterior uses the fitted thresholds, not the kind's own
    t = np.asarray(loop.hyper.thresholds)
    own = np.asarray(SCALE.thresholds_for(VARIANCE))
    assert not np.allclose(t, own)

    again = _loop(small_space, small_kernel)
    for answers in told:
        again.tell(again.ask(), answers)
    assert again.hyper == loop.hyper
    assert [r.to_json() for r in again.refits] == [r.to_json() for r in loop.refits]
    np.testing.assert_array_equal(again.posterior.mean, loop.posterior.mean)

    # undo the refitting 9th answer: back to the 6th's hyperparameters and posterior
    loop.undo()
    assert loop.hyper == loop.refits[-1].after
    assert loop.hyper.thresholds == loop.refits[1].after.thresholds


def test_ratings_change_the_refit_and_without_them_records_are_as_before(
    stars: StarsKind, small_space: Space, small_kernel: SquaredExponential
) -> None:
    plain = _loop(small_space, small_kernel)
    _play(plain, rated=False)
    rated = _loop(small_space, small_kernel)
    _play(rated, rated=True)
    assert plain.hyper.thresholds is None
    for refit in plain.refits:
        assert "thresholds" not in refit.to_json()["after"]  # type: ignore[operator]
    assert rated.refits[0].observations > plain.refits[0].observations
    assert rated.hyper.lengthscale != plain.hyper.lengthscale


def test_a_single_action_likelihood_without_third_is_refused_by_name(
    stars: StarsKind, small_space: Space, small_kernel: SquaredExponential
) -> None:
    stars.with_third = False  # the registered instance now gives a likelihood without third
    loop = _loop(small_space, small_kernel)
    q = loop.ask()
    with pytest.raises(FeedbackError, match=r"feedback kind 'stars'.*_TermsOnly has no third"):
        loop.tell(q, [Stars(q.actions[0], 2)])
    assert loop.answers == [] and loop.pending == q
    fixed = CoSpar(small_space, small_kernel, NOISE, n=1, buffer=1, seed=11)  # fit = "fixed"
    q = fixed.ask()
    fixed.tell(q, [Stars(q.actions[0], 2)])  # the fixed kernel needs no third
    assert len(fixed.answers) == 1
