"""Session objects as the JSON API shows them (:mod:`gaitpref.console.schemas`)."""

from __future__ import annotations

import contextlib
from typing import Literal

import numpy as np

from gaitpref.console import views
from gaitpref.console.schemas import (
    ConfidenceOut,
    EarlierSessionOut,
    FeatureOut,
    GaitOut,
    PosteriorOut,
    QueryOut,
    RatingScaleOut,
    SessionItemOut,
    SessionOut,
    TrialOut,
    ValidationGaitOut,
    ValidationOut,
)
from gaitpref.errors import NoSafeGaitError
from gaitpref.loop.stopping import preference_learned
from gaitpref.pointset import PointSet
from gaitpref.sessions.records import ShownGait
from gaitpref.sessions.session import Session, SessionQuery
from gaitpref.sessions.validation import ValidationPlan, ValidationResult
from gaitpref.sessions.warm import recorded_prior
from gaitpref.storage import SessionRecord


def gait_out(session: Session, action: int, trial: int | None = None) -> GaitOut:
    space = session.space
    values = space.values_of(action)
    return GaitOut(
        index=int(action),
        gait_id=session.gait_name(action),
        values={k: float(v) for k, v in values.items()},
        units={f.name: f.unit for f in space.features},
        trial=trial,
        made=session.gait_made(action),
    )


def features_out(session: Session) -> list[FeatureOut]:
    return [
        FeatureOut(
            name=f.name,
            unit=f.unit,
            values=list(f.values),
            words=f.words,
            moves=views.move_words(f),
        )
        for f in session.space.features
    ]


def query_out(session: Session, query: SessionQuery) -> QueryOut:
    actions = [gait_out(session, a, t) for a, t in zip(query.actions, query.trials, strict=True)]
    buffer = [
        gait_out(session, a, t) for a, t in zip(query.buffer, query.buffer_trials, strict=True)
    ]
    groups = views.comparison_groups(
        [
            views.gait_view(session.space, g.index, trial=g.trial, gait_id=g.gait_id)
            for g in actions
        ],
        [views.gait_view(session.space, g.index, trial=g.trial, gait_id=g.gait_id) for g in buffer],
    )
    return QueryOut(
        session_id=session.id,
        query_id=query.id,
        actions=actions,
        buffer=buffer,
        trials_done=len(session.trials()),
        comparisons=[(g.first.index, g.second.index) for g in groups],
    )


def item_out(record: SessionRecord) -> SessionItemOut:
    return SessionItemOut(
        id=record.id,
        subject=record.subject,
        config=record.config_name,
        status=record.status,
        events=record.last_seq,
        created_at=record.created_at.isoformat(),
        updated_at=record.updated_at.isoformat(),
    )


def session_out(session: Session) -> SessionOut:
    record = session.record
    pending = session.pending
    return SessionOut(
        id=session.id,
        subject=session.subject,
        config=record.config_name,
        status=session.status,
        events=session.last_seq,
        created_at=record.created_at.isoformat(),
        seed=session.seed,
        trials=len(session.trials()),
        pending_query_id=None if pending is None else pending.id,
        validation_open=session.validation_plan is not None,
        features=features_out(session),
        rating=rating_scale_out(session),
        unsafe={t: reason for t, (_, reason) in session.unsafe_flags().items()},
        stop_blocked=session.stop_blocked(),
        prior_from=[
            EarlierSessionOut(session=p.session, subject=p.subject, last_seq=p.last_seq)
            for p in recorded_prior(record)
        ],
        prior_rho=record.meta.get("prior_rho"),
    )


def rating_scale_out(session: Session) -> RatingScaleOut | None:
    ordinal = session.config.ordinal
    if ordinal is None:
        return None
    return RatingScaleOut(categories=list(ordinal.categories), avoid=session.config.safety.avoid)


def posterior_out(session: Session) -> PosteriorOut:
    post = session.posterior()
    mean = np.asarray(post.mean, dtype=float)
    sd = np.asarray(post.std, dtype=float)
    space = session.space
    rec = session.recommended()
    confidence = None
    sure = None
    learned = preference_learned(mean)  # as the trial page and session show say it
    if learned:  # something learnt
        with contextlib.suppress(NoSafeGaitError):  # no gait left to recommend: none stated
            sure = session.confidence()
    if sure is not None:
        confidence = ConfidenceOut(
            sentence=sure.sentence(session.gait_name(sure.recommended)),
            probability=sure.probability,
            tolerance=sure.tolerance,
            regret=sure.regret,
            relative_regret=sure.relative_regret,
            samples=sure.samples,
        )
    return PosteriorOut(
        session_id=session.id,
        features=list(space.names),
        shape=None if space.continuous or isinstance(space, PointSet) else list(space.shape),
        mean=mean.tolist(),
        sd=sd.tolist(),
        argmax=gait_out(session, int(np.argmax(mean))) if mean.size else None,
        recommended=None if rec is None else gait_out(session, rec),
        no_recommendation=None if rec is not None or not mean.size else session.no_recommendation(),
        learned=learned,
        trials=[t.action for t in session.trials()],
        confidence=confidence,
    )


def ratings_by_trial(session: Session) -> dict[int, str]:
    """The category each trial was rated in (ratings undone are left out)."""
    return {
        int(e.payload["trial"]): str(e.payload["category"])
        for e in session.feedback()
        if e.kind == "rating_given" and not e.undone
    }


def trials_out(session: Session) -> list[TrialOut]:
    unsafe = session.unsafe_flags()
    rated = ratings_by_trial(session)
    return [
        TrialOut(
            trial=t.number,
            query_id=t.query,
            gait=gait_out(session, t.action, t.number),
            excluded=t.excluded,
            unsafe=unsafe[t.number][1] if t.number in unsafe else None,
            rating=rated.get(t.number),
        )
        for t in session.trials()
    ]


def shown_out(session: Session, shown: ShownGait) -> GaitOut:
    """A blind validation gait as its round showed it (not looked up by its row)."""
    return GaitOut(
        index=shown.action,
        gait_id=shown.gait,
        values=dict(shown.values),
        units={f.name: f.unit for f in session.space.features},
    )


def _opened_by(session: Session, round_: int) -> Literal["rule", "operator"] | None:
    """Who opened round ``round_`` (its last draw): None when its log does not say."""
    found = [r.opened_by for r in session.validation_rounds() if r.round == round_]
    return found[-1] if found else None


def plan_out(session: Session, plan: ValidationPlan) -> ValidationOut:
    return ValidationOut(
        round=plan.round,
        opened_by=_opened_by(session, plan.round),
        gaits=[
            ValidationGaitOut(label=g.label, gait=shown_out(session, g))
            for g in session.validation_gaits(plan.round)
        ],
    )


def result_out(session: Session, result: ValidationResult) -> ValidationOut:
    shown = {g.label: g for g in session.validation_gaits(result.round)}
    return ValidationOut(
        round=result.round,
        gaits=[
            ValidationGaitOut(label=label, gait=shown_out(session, shown[label]))
            for label in sorted(result.actions)
        ],
        ranking=list(result.ranking),
        model_ranking=list(result.model_ranking),
        roles=dict(result.roles),
        agrees=result.agrees,
        kendall_tau=result.kendall_tau,
        opened_by=_opened_by(session, result.round),
    )
