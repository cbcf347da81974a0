"""The JSON API under ``/api/``: the same actions as the pages, for scripts and device controllers.

A controller polls ``GET /api/sessions/{id}/query`` (the same pending query until it is answered,
so a reconnecting controller never skips or repeats a gait), loads the gaits (feature values in
physical units), acknowledges with ``POST .../query/{query_id}/ack``, and the answer arrives with
``POST .../answers``.  Errors: 404 unknown session, 409 stale or already-answered query (nothing
written), 422 malformed body with ``loc`` naming the field (see :mod:`gaitpref.console.errors`).
Answers take ratings (and any other registered feedback kind) as ``feedback`` items; a trial
flagged unsafe (``POST .../trials/{trial}/unsafe``) keeps its gait out of every later query, and
when no gait is left to propose the query is refused with 409 and its reason.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Body, Path, Query, Request, Response, status
from fastapi.concurrency import run_in_threadpool

from gaitpref.config import load_config, shipped_configs
from gaitpref.console import present, views
from gaitpref.console.answers import feedback_records
from gaitpref.console.schemas import (
    MAX_ID,
    AckOut,
    AnsweredOut,
    AnswerIn,
    ConfigOut,
    CreatedOut,
    CreateSessionIn,
    ErrorOut,
    EventOut,
    ExcludeIn,
    NoteIn,
    NoteOut,
    PosteriorOut,
    QueryOut,
    RankingIn,
    SessionItemOut,
    SessionOut,
    StatusIn,
    TrialOut,
    UndoIn,
    UndoneOut,
    UnsafeIn,
    ValidationOut,
    WithdrawnRoundOut,
    WithdrawRoundIn,
)
from gaitpref.console.service import SessionService
from gaitpref.sessions.session import Session

SessionId = Annotated[int, Path(ge=1, le=MAX_ID, description="the session's id")]
_ERRORS: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorOut, "description": "no such session"},
    409: {"model": ErrorOut, "description": "refused now: stale query, paused/finished session"},
}

router = APIRouter(prefix="/api", tags=["api"], responses=_ERRORS)


def service_of(request: Request) -> SessionService:
    service: SessionService = request.app.state.service
    return service


@router.get("/configs", response_model=list[ConfigOut])
def configs() -> list[ConfigOut]:
    """The shipped experiment configs (their names can be given as ``config``)."""
    out = []
    for name in shipped_configs():
        cfg = load_config(name)
        out.append(
            ConfigOut(
                name=name,
                grid=None if cfg.space.continuous else list(cfg.space.shape),
                space=cfg.space.words,
                n=cfg.n,
                buffer=cfg.buffer,
                description=cfg.description,
            )
        )
    return out


@router.get("/sessions", response_model=list[SessionItemOut])
def list_sessions(request: Request) -> list[SessionItemOut]:
    """Every session of the database, by id."""
    return [present.item_out(r) for r in service_of(request).list_sessions()]


@router.post("/sessions", response_model=CreatedOut, status_code=status.HTTP_201_CREATED)
def create_session(request: Request, body: CreateSessionIn) -> CreatedOut:
    """A new session from a shipped config's name or a TOML config's text, warm-started from
    ``prior_from`` (earlier session ids or subject codes) when given."""
    session = service_of(request).create(
        body.config, body.subject, body.seed, prior_from=body.prior_from
    )
    return CreatedOut(id=session.id)


@router.get("/sessions/{session_id}", response_model=SessionOut)
def get_session(request: Request, session_id: SessionId) -> SessionOut:
    return service_of(request).read(session_id, present.session_out)


@router.get("/sessions/{session_id}/query", response_model=QueryOut)
def get_query(request: Request, session_id: SessionId) -> QueryOut:
    """The pending query: the gait(s) to run now and the buffered trial(s) to compare with.

    Issued (and logged) on the first read; every later read returns the same query until it is
    answered.  409 while the session is paused or finished, a blind validation is open, or no
    gait may be proposed (every gait is in the region of avoidance or near an unsafe flag: the
    reason says so; nothing is written).  With gaits made on demand, after an ask that stopped
    (``query_stopped``; nothing logged since) a read does not ask again: 409 with that stop's
    reason, no gait made, however often a controller polls; ``POST`` asks again.
    """
    return service_of(request).read(
        session_id, lambda s: present.query_out(s, s.next_query(retry=False))
    )


@router.post("/sessions/{session_id}/query", response_model=QueryOut)
def ask_query(request: Request, session_id: SessionId) -> QueryOut:
    """The pending query, or an explicit new ask: as ``GET``, but after an ask that stopped it
    asks again, going on from the gaits avoided so far (409 when this ask stops too)."""
    return service_of(request).read(session_id, lambda s: present.query_out(s, s.next_query()))


@router.post("/sessions/{session_id}/query/{query_id}/ack", response_model=AckOut)
def acknowledge(
    request: Request,
    session_id: SessionId,
    query_id: Annotated[int, Path(ge=1, le=MAX_ID)],
) -> AckOut:
    """A device controller loaded the query's gaits (logged once as a note); 409 if not pending."""
    new = service_of(request).acknowledge(session_id, query_id)
    return AckOut(query_id=query_id, acknowledged=new)


@router.post("/sessions/{session_id}/answers", response_model=AnsweredOut)
def answer(request: Request, session_id: SessionId, body: AnswerIn) -> AnsweredOut:
    """Answer the pending query: ``comparisons`` ``[i, j, first|second|none]`` and
    ``suggestions`` ``[action, feature, move]``, as for ``CoSpar.tell``, and ``feedback`` items
    of any registered kind, e.g. ``{"kind": "rating", "action": 7, "label": "okay"}``."""
    service = service_of(request)  # the answer and what is pending after it, under one lock
    records = feedback_records([(f.kind, f.fields()) for f in body.feedback])
    answered, pending = service.answer(
        session_id,
        body.query_id,
        [list(c) for c in body.comparisons],
        [list(s) for s in body.suggestions],
        None if body.note is None else views.free_text(body.note, "note", "the note"),
        records,
    )
    return AnsweredOut(
        query_id=answered.query,
        trials=list(answered.trials),
        next_query_id=pending,
        stop_warning=answered.stop_warning,
        clipped=list(answered.clipped),
        stopped=answered.stopped,
    )


@router.post("/sessions/{session_id}/undo", response_model=UndoneOut)
def undo(
    request: Request, session_id: SessionId, body: Annotated[UndoIn | None, Body()] = None
) -> UndoneOut:
    """Take back the last answer; its query is pending again (or, where it proposed a gait
    flagged unsafe since or in the region of avoidance now, a new query in its place:
    ``withdrawn``; should none be proposed, as the gait generator failed, no gait may be
    proposed or the database failed to write the new query, the undo stands, the answer is 200
    and ``next_query_error`` says why).  With ``query_id``, refused (409) unless that query is
    the pending one (so two clients cannot undo twice)."""
    done = service_of(request).undo(session_id, None if body is None else body.query_id)
    pending = done.pending
    return UndoneOut(
        pending_query_id=None if pending is None else pending.id,
        trials=list(done.trials if pending is None else pending.trials),
        discarded_query_id=done.discarded_query,
        undone_query_id=done.undone_query,
        withdrawn=done.withdrawn,
        next_query_error=done.detail or None,
    )


@router.get("/sessions/{session_id}/posterior", response_model=PosteriorOut)
def posterior(request: Request, session_id: SessionId) -> PosteriorOut:
    """Posterior mean and standard deviation of every action, in grid order."""
    return service_of(request).read(session_id, present.posterior_out)


@router.get("/sessions/{session_id}/trials", response_model=list[TrialOut])
def trials(request: Request, session_id: SessionId) -> list[TrialOut]:
    """The trials in force, in order (the chronology)."""
    return service_of(request).read(session_id, present.trials_out)


@router.get("/sessions/{session_id}/events", response_model=list[EventOut])
def events(request: Request, session_id: SessionId) -> list[EventOut]:
    """The session's whole append-only log."""
    return [
        EventOut(seq=e.seq, kind=e.kind, at=e.at.isoformat(), payload=e.payload)
        for e in service_of(request).get(session_id).events()
    ]


@router.post("/sessions/{session_id}/notes", response_model=NoteOut)
def add_note(request: Request, session_id: SessionId, body: NoteIn) -> NoteOut:
    text = views.free_text(body.text, "text", "the note")
    return NoteOut(seq=service_of(request).note(session_id, text))


@router.post("/sessions/{session_id}/trials/{trial}/exclude", response_model=list[TrialOut])
def exclude(
    request: Request,
    session_id: SessionId,
    trial: Annotated[int, Path(ge=1, le=MAX_ID)],
    body: ExcludeIn,
) -> list[TrialOut]:
    """Exclude an answered trial (device fault, stumble...): its answers leave the model.  A
    pending query that proposes a gait in the region of avoidance of the model without them is
    withdrawn (read ``GET .../query`` again for the next one); an open validation round that
    shows one is drawn again."""
    service = service_of(request)
    detail = views.free_text(body.detail, "detail", "the detail")
    service.exclude(session_id, trial, body.reason, detail)
    return service.read(session_id, present.trials_out)


@router.post("/sessions/{session_id}/trials/{trial}/unsafe", response_model=list[TrialOut])
def flag_unsafe(
    request: Request,
    session_id: SessionId,
    trial: Annotated[int, Path(ge=1, le=MAX_ID)],
    body: UnsafeIn,
) -> list[TrialOut]:
    """Flag an answered trial unsafe (``reason`` required): its gait, and those within the
    config's ``[safety] unsafe_radius``, are never proposed again.  A pending query that proposes
    one of them is withdrawn: read ``GET .../query`` again for the next one."""
    service = service_of(request)
    service.flag_unsafe(session_id, trial, views.free_text(body.reason, "reason", "the reason"))
    return service.read(session_id, present.trials_out)


@router.post("/sessions/{session_id}/trials/{trial}/unsafe/withdraw", response_model=list[TrialOut])
def withdraw_unsafe(
    request: Request, session_id: SessionId, trial: Annotated[int, Path(ge=1, le=MAX_ID)]
) -> list[TrialOut]:
    """Withdraw the unsafe flag of a trial (the flag's undo); 409 if it is not flagged."""
    service = service_of(request)
    service.withdraw_unsafe(session_id, trial)
    return service.read(session_id, present.trials_out)


@router.post("/sessions/{session_id}/status", response_model=SessionOut)
def set_status(request: Request, session_id: SessionId, body: StatusIn) -> SessionOut:
    """Pause, resume (``active``) or finish the session."""
    service = service_of(request)
    service.set_status(session_id, body.status)
    return service.read(session_id, present.session_out)


@router.post("/sessions/{session_id}/validation", response_model=ValidationOut)
def start_validation(request: Request, session_id: SessionId) -> ValidationOut:
    """Open a blind validation round (max/mean/min of the posterior mean in a stored random
    order), or return the open one."""
    service = service_of(request)
    plan = service.start_validation(session_id)
    return service.read(session_id, lambda s: present.plan_out(s, plan))


@router.get("/sessions/{session_id}/validation", response_model=list[ValidationOut])
def validations(request: Request, session_id: SessionId) -> list[ValidationOut]:
    """The answered rounds (unblinded), then the open one, if any."""

    def rounds(session: Session) -> list[ValidationOut]:
        out = [present.result_out(session, r) for r in session.validations()]
        if session.validation_plan is not None:
            out.append(present.plan_out(session, session.validation_plan))
        return out

    return service_of(request).read(session_id, rounds)


@router.post("/sessions/{session_id}/validation/{round_}/ranking", response_model=ValidationOut)
def rank(
    request: Request,
    session_id: SessionId,
    round_: Annotated[int, Path(ge=1, le=MAX_ID)],
    body: RankingIn,
) -> ValidationOut:
    """The subject's blind ranking (labels, best first); returns the round unblinded.  With
    ``shown`` (the gait ids of the round as the client showed them), refused (409) when a flag
    drew the round again since with other gaits."""
    service = service_of(request)
    result = service.rank(session_id, round_, body.ranking, body.shown)
    return service.read(session_id, lambda s: present.result_out(s, result))


@router.post(
    "/sessions/{session_id}/validation/{round_}/withdraw", response_model=WithdrawnRoundOut
)
def withdraw_round(
    request: Request,
    session_id: SessionId,
    round_: Annotated[int, Path(ge=1, le=MAX_ID)],
    body: WithdrawRoundIn,
) -> WithdrawnRoundOut:
    """Withdraw the open, unanswered round (``reason`` logged); with ``undo``, also take back
    the answer after which the ``[stop]`` rule opened it (a mis-keyed answer).  409 for a round
    answered, withdrawn, not started or not the open one, and for ``undo`` of a round the rule
    did not open or whose answer is no longer the last in force.  When the query to be
    proposed in place of the undone one (withdrawn) could not be (the database failed to write
    it, ...), the withdrawal and the undo stand: 200, ``next_query_error`` says why."""
    done = service_of(request).withdraw_validation(session_id, round_, body.reason, body.undo)
    pending = done.pending
    return WithdrawnRoundOut(
        round=done.round,
        undone_query_id=done.undone_query,
        trials=list(done.trials),
        pending_query_id=None if pending is None else pending.id,
        next_query_error=done.detail or None,
    )


@router.get(
    "/sessions/{session_id}/export",
    response_class=Response,
    responses={200: {"content": {"application/zip": {}}, "description": "the export folder"}},
)
async def export(
    request: Request,
    session_id: SessionId,
    format: Annotated[Literal["csv", "json"], Query()] = "csv",
) -> Response:
    """The session exported (``gaitpref session export``) as a zip of its folder."""
    data = await run_in_threadpool(service_of(request).export_zip, session_id, format)
    return Response(
        data,
        media_type="application/zip",
        headers={
            "content-disposition": f'attachment; filename="session-{session_id}-{format}.zip"'
        },
    )
