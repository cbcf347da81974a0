"""The console's HTML pages: sessions, the trial page, blind validation.

Every form posts with the page's CSRF token; answers and undos carry the query id they were
decided on and go through a confirm step (in the page with JavaScript, as a server-rendered page
without), and a successful post redirects (303) so that reloading never posts twice.
"""

from __future__ import annotations

import functools
import json
import re
from collections import Counter
from typing import Annotated, Any

from fastapi import APIRouter, Path, Query, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import HTMLResponse, RedirectResponse, Response
from starlette.datastructures import UploadFile
from starlette.exceptions import HTTPException

from gaitpref.config import ExperimentConfig, load_config, shipped_configs
from gaitpref.console import figures, views
from gaitpref.console.answers import logged_answer, read_rating_fields
from gaitpref.console.errors import AnsweredDifferentlyError, CsrfError, InputError, quoted
from gaitpref.console.limits import (
    MAX_CONFIG_TEXT,
    MAX_FORM_FIELD,
    MAX_FORM_FIELDS,
    MAX_FORM_FILES,
    MAX_LIBRARY_BYTES,
    MAX_UPLOAD,
    form_error,
)
from gaitpref.console.once import ONCE_FIELD, OncePosts
from gaitpref.console.schemas import MAX_ID, SUBJECT_PATTERN
from gaitpref.console.security import CSRF_COOKIE, CSRF_FIELD, Csrf
from gaitpref.console.service import (
    ExportFormat,
    SessionService,
    ask_again,
    check_ranking_labels,
    check_undo_query,
    pending_of,
    session_query_error,
)
from gaitpref.console.templating import confirm_page, render
from gaitpref.console.trial_page import trial_context
from gaitpref.errors import SessionStateError
from gaitpref.feedback import Rating
from gaitpref.loop.cospar import QueryError
from gaitpref.sessions import read_prior_from
from gaitpref.sessions.records import REASONS
from gaitpref.sessions.session import Session

router = APIRouter(include_in_schema=False)
SessionId = Annotated[int, Path(ge=1, le=MAX_ID)]
#: the most trials the flash of a redirect names (``?answered=3,4``): an answer's or an undo's
#: trials, at most a query's gaits (``[cospar] n`` is at most 64); and its most characters, as
#: many trial numbers of 18 digits with their commas (the text was cut at 200 characters, so
#: that the redirect after an answer of n = 40 gaits from trial 1000 on was a 422)
MAX_FLASH_TRIALS = 64
MAX_FLASH_TEXT = MAX_FLASH_TRIALS * 19
#: ``?trials=all``: the trial page lists every trial, not only the recent ones
ALL_TRIALS = "all"


def service_of(request: Request) -> SessionService:
    service: SessionService = request.app.state.service
    return service


#: the fields of the console's forms that take a file (the create form's uploads)
FILE_FIELDS = frozenset({"config_file", "library_file"})


def once_posts(request: Request) -> OncePosts:
    posts: OncePosts = request.app.state.once
    return posts


def see_other(url: str) -> RedirectResponse:
    return RedirectResponse(url, status_code=303)


async def read_form(request: Request) -> tuple[dict[str, str], dict[str, UploadFile]]:
    """The posted form (each field once), after checking its CSRF token; a form past the form
    limits (``limits.py``), or one that cannot be parsed, is the console's error (an HTML page
    saying which), not Starlette's bare JSON 400."""
    try:
        form = await request.form(
            max_files=MAX_FORM_FILES, max_fields=MAX_FORM_FIELDS, max_part_size=MAX_FORM_FIELD
        )
    except HTTPException as exc:  # Starlette's parser refused it
        if exc.status_code != 400:
            raise
        raise form_error(str(exc.detail)) from None
    fields: dict[str, str] = {}
    files: dict[str, UploadFile] = {}
    for key, value in form.multi_items():
        if key in fields or key in files:
            raise InputError(key, f"the field {quoted(key)} was given twice")
        if isinstance(value, UploadFile):
            files[key] = value
        else:
            fields[key] = value
    csrf: Csrf = request.app.state.csrf
    if not csrf.check(request.cookies.get(CSRF_COOKIE), fields.get(CSRF_FIELD)):
        raise CsrfError(
            "this form has no valid CSRF token (it was not made by this console, or the console "
            "restarted since the page was loaded): reload the page and try again"
        )
    stray = sorted(files.keys() - FILE_FIELDS)  # were read as missing: "the note is empty"
    if stray:
        raise InputError(
            stray[0],
            "was sent as a file; this field is text (only config_file and library_file take files)",
        )
    return fields, files


# -- sessions ----------------------------------------------------------------------------------
@router.get("/", response_class=HTMLResponse)
async def sessions_page(request: Request) -> Response:
    service = service_of(request)
    records = await run_in_threadpool(service.list_sessions)
    subjects = await run_in_threadpool(service.list_subjects)
    per_subject = Counter(r.subject for r in records)  # one pass, not one per subject
    counts = {s.code: per_subject[s.code] for s in subjects}
    configs = _shipped()
    return render(
        request,
        "sessions.html",
        sessions=list(reversed(records)),
        subjects=subjects,
        counts=counts,
        configs=configs,
        db_url=service.url,
    )


@functools.cache
def _shipped() -> list[tuple[str, ExperimentConfig, str]]:
    """The shipped configs, each with its space in words."""
    configs = [(name, load_config(name)) for name in shipped_configs()]
    return [(name, cfg, cfg.space.words) for name, cfg in configs]


async def _upload_text(upload: UploadFile | None, field: str) -> str | None:
    if upload is None or not upload.filename:
        return None
    data = await upload.read(MAX_UPLOAD + 1)
    if len(data) > MAX_UPLOAD:
        raise InputError(field, f"the file is larger than {MAX_UPLOAD // 1000} kB")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(field, "the file is not UTF-8 text") from None


@router.post("/sessions")
async def create_session(request: Request) -> Response:
    fields, files = await read_form(request)
    subject = fields.get("subject", "").strip()
    if not re.fullmatch(SUBJECT_PATTERN, subject):
        raise InputError(
            "subject",
            f"{quoted(subject)} is not a subject code: 1 to 64 letters, digits, '-', '_' or '.' "
            "(a pseudonymous code such as S01, never a name)",
        )
    seed_text = fields.get("seed", "").strip()
    seed = views.read_int(fields, "seed", minimum=0) if seed_text else None
    uploaded = await _upload_text(files.get("config_file"), "config_file")
    upload_name = files["config_file"].filename if uploaded is not None else None
    source = uploaded if uploaded is not None else fields.get("config", "")
    if not source:
        raise InputError("config", "choose a shipped config or upload a TOML config")
    if len(source) > MAX_CONFIG_TEXT:
        raise InputError(
            "config",
            f"the config text has {len(source):,} characters; at most {MAX_CONFIG_TEXT:,} are "
            "taken (as many as an uploaded config file holds)",
        )
    library = None
    lib_file = files.get("library_file")
    if lib_file is not None and lib_file.filename:
        data = await lib_file.read(MAX_LIBRARY_BYTES + 1)
        if len(data) > MAX_LIBRARY_BYTES:
            raise InputError("library_file", f"larger than {MAX_LIBRARY_BYTES // 1_000_000} MB")
        library = (data, lib_file.filename)
    name = upload_name.rsplit(".", 1)[0] if upload_name else None
    try:
        prior = read_prior_from([fields.get("prior_from", "")])
    except ValueError as exc:
        raise InputError("prior_from", str(exc)) from None

    async def post() -> str:
        session = await run_in_threadpool(
            lambda: service_of(request).create(
                source, subject, seed, config_name=name, library=library, prior_from=prior
            )
        )
        return f"/sessions/{session.id}"

    return see_other(await once_posts(request).run(fields.get(ONCE_FIELD), post))


@router.post("/sessions/{session_id}/status")
async def set_status(request: Request, session_id: SessionId) -> Response:
    fields, _ = await read_form(request)
    status = fields.get("status", "")
    if status not in ("active", "paused", "finished"):
        raise InputError("status", f"must be active, paused or finished; got {quoted(status)}")
    if status == "finished" and fields.get("confirmed") != "1":  # no undo: confirmed first
        session = await run_in_threadpool(service_of(request).get, session_id)
        if session.status != "finished":
            return confirm_page(
                request,
                session_id,
                "finish",
                [
                    f"Finish session {session_id}: it will take no more answers, undos or "
                    "unsafe flags (its data stay, for export)"
                ],
                fields,
                f"/sessions/{session_id}/status",
            )
    await run_in_threadpool(service_of(request).set_status, session_id, status)
    back = fields.get("back", "")
    return see_other(
        back if back in ("/", f"/sessions/{session_id}") else f"/sessions/{session_id}"
    )


# -- the trial page ----------------------------------------------------------------------------
@router.get("/sessions/{session_id}", response_class=HTMLResponse)
async def trial_page(
    request: Request,
    session_id: SessionId,
    answered: Annotated[str | None, Query(max_length=MAX_FLASH_TEXT)] = None,
    undone: Annotated[str | None, Query(max_length=MAX_FLASH_TEXT)] = None,
    flagged: Annotated[int | None, Query(ge=1, le=MAX_ID)] = None,
    withdrawn: Annotated[int | None, Query(ge=1, le=MAX_ID)] = None,
    replaced: Annotated[int | None, Query(ge=0, le=1)] = None,
    excluded: Annotated[int | None, Query(ge=1, le=MAX_ID)] = None,
    stop_unchecked: Annotated[int | None, Query(ge=1, le=1)] = None,
    again: Annotated[int | None, Query(ge=1, le=1)] = None,
    trials: Annotated[str | None, Query(pattern=f"^{ALL_TRIALS}$")] = None,
) -> Response:
    """The trial page; it lists the last ``RECENT_TRIALS`` trials, or every one with
    ``?trials=all``."""
    for name, text in (("answered", answered), ("undone", undone)):
        if text is not None and text.count(",") >= MAX_FLASH_TRIALS:
            raise InputError(
                name,
                f"names {text.count(',') + 1:,} trials; a query runs at most "
                f"{MAX_FLASH_TRIALS} gaits ([cospar] n), so a redirect names at most as many",
            )
    every = trials == ALL_TRIALS
    context = await run_in_threadpool(
        service_of(request).read,
        session_id,
        lambda s: trial_context(s, pending_of(s), all_trials=every),
    )
    flash = _flash(context, answered, undone, replaced, flagged, withdrawn, excluded, again)
    if stop_unchecked and flash.startswith("Saved:"):
        flash += (
            " The [stop] rule could not be checked after it (the console's log says why: a "
            "warning of the gaitpref.console logger); it is checked again after the next answer."
        )
    return render(request, "trial.html", flash=flash, reasons=REASONS, **context)


def trial_list(fields: dict[str, str]) -> str:
    """The query string that takes a trial's form (flag, withdraw, exclude) back to the list it
    was posted from: ``trials=all`` from the page listing every trial (its forms carry the field
    ``trials``), empty from the page of the recent ones."""
    value = fields.get("trials", "")
    if value not in ("", ALL_TRIALS):
        what = f"must be {ALL_TRIALS!r} (the list of every trial) or absent"
        raise InputError("trials", f"{what}; got {quoted(value)}")
    return f"trials={ALL_TRIALS}" if value else ""


def trial_page_url(session_id: int, *queries: str) -> str:
    """The trial page with the query strings ``queries`` (empty ones left out)."""
    parts = "&".join(q for q in queries if q)
    return f"/sessions/{session_id}" + (f"?{parts}" if parts else "")


def _numbers(text: str | None) -> set[int]:
    """The trial numbers of a flash parameter (``"3,4"``); none if it is not such a list."""
    if not text or not re.fullmatch(r"\d{1,18}(,\d{1,18})*", text):
        return set()
    return {int(t) for t in text.split(",")}


def _flash(
    context: dict[str, Any],
    answered: str | None,
    undone: str | None,
    replaced: int | None,
    flagged: int | None,
    withdrawn: int | None,
    excluded: int | None = None,
    again: int | None = None,
) -> str:
    """What the redirect after a post says, if it is still so: a page reloaded after another
    tab undid the answer, withdrew the flag (...) says nothing rather than what is no longer
    true ("Saved: trial 4." above trial 4 asked again)."""
    done = {row.trial for row in context["chronology"]}
    unsafe = context["unsafe"]
    saved, taken = _numbers(answered), _numbers(undone)
    if saved and saved <= done and again:
        names = ", ".join(map(str, sorted(saved)))
        return f"That answer was already saved (trial {names}); nothing was stored twice."
    if saved and saved <= done:
        return f"Saved: trial {', '.join(map(str, sorted(saved)))}."
    if taken and not taken & done:
        names = ", ".join(map(str, sorted(taken)))
        if replaced and context["reason"] in ("no-gait", "no-safe"):  # said below it
            return (
                f"Undone: the answer to trial {names} was taken back; its query proposed a gait "
                "flagged unsafe since, or in the region of avoidance now, and was withdrawn, but "
                "no new query could be proposed in its place."
            )
        if replaced and context["reason"] in ("paused", "validation"):  # no query asked yet
            when = (
                "the session is resumed"
                if context["reason"] == "paused"
                else "blind validation is ranked or withdrawn"
            )
            return (
                f"Undone: the answer to trial {names} was taken back; its query proposed a gait "
                "flagged unsafe since, or in the region of avoidance now, and was withdrawn: a "
                f"new query is proposed in its place once {when}."
            )
        if replaced:
            return (
                f"Undone: the answer to trial {names} was taken back; its query proposed a gait "
                "flagged unsafe since, or in the region of avoidance now, so a new query is "
                "proposed in its place."
            )
        return f"Undone: the answer to trial {names} was taken back; run it again."
    # a query withdrawn by the flag or the exclusion: the device must be set to the new one
    anew = (
        " The pending query proposed a gait {why} and was withdrawn: the query below is a new "
        "one; set the device to it."
    )
    if flagged and flagged in unsafe:
        said = f"Trial {flagged} flagged unsafe: its gait (and those near it) will not be proposed."
        return said + (anew.format(why="near it") if replaced else "")
    if excluded and any(r.trial == excluded and r.excluded for r in context["chronology"]):
        said = f"Trial {excluded} excluded: its answers left the model."
        why = "in the region of avoidance of the model without them"
        return said + (anew.format(why=why) if replaced else "")
    if withdrawn and withdrawn in done and withdrawn not in unsafe:
        return f"The unsafe flag of trial {withdrawn} was withdrawn."
    return ""


@router.post("/sessions/{session_id}/answer")
async def post_answer(request: Request, session_id: SessionId) -> Response:
    fields, _ = await read_form(request)
    query_id = views.read_int(fields, "query_id")
    comparisons, suggestions = views.read_answer_form(fields)
    note = views.free_text(fields.get("note", "").strip(), "note", "the note")
    service = service_of(request)
    ordinal = await run_in_threadpool(lambda: service.get(session_id).config.ordinal)
    categories = ordinal.categories if ordinal is not None else ()
    ratings = read_rating_fields(fields, len(categories))
    if fields.get("confirmed") != "1":

        def summary(session: Session) -> list[str] | tuple[int, ...]:
            pending = session.pending
            if pending is None or pending.id != query_id:
                repeat = _repeat_of(session, query_id, comparisons, suggestions, ratings)
                if repeat is not None:
                    return repeat  # the trials it answered: already saved
                raise session_query_error(session, query_id)
            space = session.space
            said = [(r.action, categories[int(r.label) - 1]) for r in ratings]
            return views.unanswered(
                space, pending, comparisons, session.gait_name
            ) + views.answer_summary(
                space, pending, comparisons, suggestions, session.gait_name, said
            )

        lines = await run_in_threadpool(service.read, session_id, summary)
        if isinstance(lines, tuple):
            return _already_saved(session_id, lines)
        return confirm_page(
            request,
            session_id,
            "answer",
            lines,
            fields,
            f"/sessions/{session_id}/answer",
            note=note,
        )
    try:
        answered, _ = await run_in_threadpool(
            service.answer, session_id, query_id, comparisons, suggestions, note, ratings
        )
    except (QueryError, SessionStateError):  # answered already? (finished or paused since)

        def repeat_of(session: Session) -> tuple[int, ...] | None:
            return _repeat_of(session, query_id, comparisons, suggestions, ratings)

        repeat = await run_in_threadpool(service.read, session_id, repeat_of)
        if repeat is None:
            raise
        return _already_saved(session_id, repeat)
    trials = ",".join(map(str, answered.trials))
    unchecked = "&stop_unchecked=1" if answered.stop_warning is not None else ""
    return see_other(f"/sessions/{session_id}?answered={trials}{unchecked}")


def _repeat_of(
    session: Session,
    query_id: int,
    comparisons: list[tuple[int, int, str]],
    suggestions: list[tuple[int, str, str]],
    ratings: list[Rating],
) -> tuple[int, ...] | None:
    """For an answer form posted to a query that is not pending: the trials of the query's
    logged answer when it is the same answer (a second post of the same form: nothing to do);
    :class:`AnsweredDifferentlyError` when it is another; None when the query has no answer in
    force (stale or unknown: the session's own refusal says so)."""
    logged = logged_answer(session, query_id, comparisons, suggestions, ratings)
    if logged is None:
        return None
    if logged.same:
        return logged.trials
    words = views.answer_summary(
        session.space,
        logged.query,
        logged.comparisons,
        logged.suggestions,
        session.gait_name,
        logged.ratings,
    )
    words += [f"an answer of kind {kind!r}" for kind in logged.other_kinds]
    names = ", ".join(map(str, logged.trials))
    raise AnsweredDifferentlyError(
        f"query {query_id} (trial {names}) was already answered, with a different answer than "
        f"this form's: {'; '.join(words)}. To change the answer, undo it on the trial page "
        f'("Undo last answer"; answers given after it must be undone first) and answer '
        f"trial {names} again"
    )


def _already_saved(session_id: int, trials: tuple[int, ...]) -> Response:
    """The redirect after a second post of an answer that is saved already."""
    return see_other(f"/sessions/{session_id}?answered={','.join(map(str, trials))}&again=1")


@router.post("/sessions/{session_id}/undo")
async def post_undo(request: Request, session_id: SessionId) -> Response:
    fields, _ = await read_form(request)
    query_id = views.read_int(fields, "query_id")
    service = service_of(request)
    if fields.get("confirmed") != "1":

        def summary(session: Session) -> list[str]:
            check_undo_query(session, query_id)  # stale (another tab moved on): 409 now
            session.check_change("undo")  # nothing to undo, a flagged or excluded trial: 409
            trials = session.trials()
            last = [t for t in trials if t.query == trials[-1].query]  # n > 1: the whole query
            if len(last) == 1:
                return [
                    f"Take back the answer to trial {last[0].number} "
                    f"({session.describe(last[0].action)})"
                ]
            numbers = ", ".join(str(t.number) for t in last)
            return [f"Take back the answer to trials {numbers}, one query:"] + [
                f"trial {t.number} ({session.describe(t.action)})" for t in last
            ]

        lines = await run_in_threadpool(service.read, session_id, summary)
        return confirm_page(
            request,
            session_id,
            "undo",
            lines,
            fields,
            f"/sessions/{session_id}/undo",
        )
    done = await run_in_threadpool(service.undo, session_id, query_id)
    flag = "&replaced=1" if done.withdrawn else ""
    return see_other(f"/sessions/{session_id}?undone={','.join(map(str, done.trials))}{flag}")


@router.post("/sessions/{session_id}/ask")
async def post_ask(request: Request, session_id: SessionId) -> Response:
    """Ask again after an ask that stopped (a reload does not: it would make gaits each time)."""
    await read_form(request)  # the CSRF check
    await run_in_threadpool(service_of(request).read, session_id, ask_again)
    return see_other(f"/sessions/{session_id}")


@router.post("/sessions/{session_id}/note")
async def post_note(request: Request, session_id: SessionId) -> Response:
    fields, _ = await read_form(request)
    text = views.free_text(fields.get("text", "").strip(), "text", "the note")
    if not text:
        raise InputError("text", "the note is empty")
    if len(text) > 2000:
        raise InputError("text", "a note has at most 2000 characters")

    async def post() -> str:
        await run_in_threadpool(service_of(request).note, session_id, text)
        return f"/sessions/{session_id}"

    return see_other(await once_posts(request).run(fields.get(ONCE_FIELD), post))


@router.post("/sessions/{session_id}/trials/{trial}/exclude")
async def post_exclude(
    request: Request, session_id: SessionId, trial: Annotated[int, Path(ge=1, le=MAX_ID)]
) -> Response:
    fields, _ = await read_form(request)
    reason = fields.get("reason", "")
    if reason not in REASONS:
        raise InputError("reason", f"must be one of {', '.join(REASONS)}; got {quoted(reason)}")
    detail = views.free_text(fields.get("detail", "").strip(), "detail", "the detail")
    if len(detail) > 500:
        raise InputError("detail", f"at most 500 characters, got {len(detail)}")
    listing = trial_list(fields)
    service = service_of(request)
    if fields.get("confirmed") != "1":  # an exclusion cannot be taken back: confirmed first

        def summary(session: Session) -> list[str]:
            session.check_change("exclude", trial)  # undone, excluded since, finished: 409 now
            gait = next(t.action for t in session.trials() if t.number == trial)
            why = reason.replace("_", " ") + (f" ({detail})" if detail else "")
            return [
                f"Exclude trial {trial} ({session.describe(gait)}): {why}",
                "Its answers leave the model; they stay in the log, flagged. An exclusion "
                "cannot be taken back.",
            ]

        lines = await run_in_threadpool(service.read, session_id, summary)
        action = f"/sessions/{session_id}/trials/{trial}/exclude"
        back = trial_page_url(session_id, listing)
        return confirm_page(request, session_id, "exclude", lines, fields, action, back=back)
    replaced = await run_in_threadpool(service.exclude, session_id, trial, reason, detail)
    done = f"excluded={trial}&replaced={int(replaced)}"
    return see_other(trial_page_url(session_id, done, listing))


@router.get("/sessions/{session_id}/posterior.png")
async def posterior_png(request: Request, session_id: SessionId) -> Response:
    """The posterior figure (1-D: mean +- 2 sd with the trials; 2-D: heat map with the trials)."""
    return await _figure(request, session_id, "posterior")


@router.get("/sessions/{session_id}/figure.png")
async def session_png(request: Request, session_id: SessionId) -> Response:
    """The paper-style session figure (posterior, chronology, blind ranking)."""
    return await _figure(request, session_id, "session")


async def _figure(request: Request, session_id: int, kind: str) -> Response:
    service = service_of(request)
    version = await run_in_threadpool(lambda: service.get(session_id).last_seq)
    renderer: figures.FigureRenderer = request.app.state.figures

    def fetch() -> tuple[int, figures.Picture]:  # in the drawing queue, not a request's thread
        return service.read(session_id, lambda s: (s.last_seq, figures.picture_of(s, kind)))

    png = await renderer.png(session_id, kind, version, fetch)
    return Response(png, media_type="image/png", headers={"cache-control": "no-store"})


# -- validation --------------------------------------------------------------------------------
@router.get("/sessions/{session_id}/validation", response_class=HTMLResponse)
async def validation_page(request: Request, session_id: SessionId) -> Response:
    return await run_in_threadpool(
        service_of(request).read, session_id, lambda s: _validation_page(request, s)
    )


def _validation_page(request: Request, session: Session) -> Response:
    space = session.space
    plan = session.validation_plan
    gaits = (
        []
        if plan is None
        else [(g.label, views.shown_view(space, g)) for g in session.validation_gaits()]
    )
    results = [
        (r, {g.label: views.shown_view(space, g) for g in session.validation_gaits(r.round)})
        for r in session.validations()
    ]
    opened = session.validation_rounds()[-1] if plan is not None else None
    undo_trials: list[int] = []  # the answer after which the [stop] rule opened it, if undoable
    if plan is not None and opened is not None and opened.opened_by == "rule":
        try:
            session.check_withdraw_validation(plan.round, undo=True)
            undo_trials = [t.number for t in session.trials() if t.query == opened.opened_after]
        except SessionStateError:
            pass  # undone since, or the session is finished: the round alone
    return render(
        request,
        "validation.html",
        session=session,
        plan=plan,
        opened_by=None if opened is None else opened.opened_by,
        undo_trials=", ".join(map(str, undo_trials)),
        gaits=gaits,
        shown=json.dumps([g.gait_id for _, g in gaits]),  # checked when the ranking is posted
        results=list(reversed(results)),
        trials=len(session.trials()),
    )


@router.post("/sessions/{session_id}/validation")
async def start_validation(request: Request, session_id: SessionId) -> Response:
    await read_form(request)
    await run_in_threadpool(service_of(request).start_validation, session_id)
    return see_other(f"/sessions/{session_id}/validation")


@router.post("/sessions/{session_id}/validation/{round_}")
async def post_ranking(
    request: Request, session_id: SessionId, round_: Annotated[int, Path(ge=1, le=MAX_ID)]
) -> Response:
    fields, _ = await read_form(request)
    ranking = [fields.get(f"rank{k}", "") for k in (1, 2, 3)]
    for k, label in enumerate(ranking, start=1):
        if not label:
            raise InputError(f"rank{k}", "choose a gait for every place")
        if len(label) > MAX_LABEL:
            raise InputError(
                f"rank{k}",
                f"a gait's label has at most {MAX_LABEL} characters (A, B, C); got {quoted(label)}",
            )
    shown = _shown(fields.get("shown"))
    service = service_of(request)
    if fields.get("confirmed") != "1":  # a ranking cannot be taken back: confirmed first

        def summary(session: Session) -> list[str]:
            check_ranking_labels(session, round_, ranking)
            session.check_validation_answer(round_, ranking, shown=shown)  # stale: 409 now
            places = ", ".join(f"{k}. {label}" for k, label in enumerate(ranking, start=1))
            return [f"Record the subject's ranking of round {round_}, best first: {places}"]

        lines = await run_in_threadpool(service.read, session_id, summary)
        return confirm_page(
            request,
            session_id,
            "ranking",
            lines,
            fields,
            f"/sessions/{session_id}/validation/{round_}",
            back=f"/sessions/{session_id}/validation",
        )
    await run_in_threadpool(service.rank, session_id, round_, ranking, shown)
    return see_other(f"/sessions/{session_id}/validation")


@router.post("/sessions/{session_id}/validation/{round_}/withdraw")
async def post_withdraw_round(
    request: Request, session_id: SessionId, round_: Annotated[int, Path(ge=1, le=MAX_ID)]
) -> Response:
    """Withdraw the open round, saying why (``undo``: with the answer after which the
    ``[stop]`` rule opened it); confirmed first.  Then the trial page: the trials go on."""
    fields, _ = await read_form(request)
    reason = fields.get("reason", "").strip()
    if not reason:
        raise InputError("reason", "say why the round is withdrawn (the reason is required)")
    if len(reason) > 2000:
        raise InputError("reason", "a reason has at most 2000 characters")
    views.free_text(reason, "reason", "the reason")
    undo = fields.get("undo") == "1"
    service = service_of(request)
    if fields.get("confirmed") != "1":

        def summary(session: Session) -> list[str]:
            session.check_withdraw_validation(round_, undo=undo)  # answered since...: 409 now
            lines = [f"Withdraw blind validation round {round_} unanswered: {reason}"]
            if undo:
                after = session.validation_rounds()[-1].opened_after
                trials = ", ".join(str(t.number) for t in session.trials() if t.query == after)
                lines.append(
                    f"Undo the answer to trial {trials}, after which the [stop] rule opened the "
                    "round: it is asked again."
                )
            lines.append("The round's log stays; the next round takes the next number.")
            return lines

        lines = await run_in_threadpool(service.read, session_id, summary)
        return confirm_page(
            request,
            session_id,
            "withdraw-round",
            lines,
            fields,
            f"/sessions/{session_id}/validation/{round_}/withdraw",
            back=f"/sessions/{session_id}/validation",
        )
    await run_in_threadpool(service.withdraw_validation, session_id, round_, reason, undo)
    return see_other(f"/sessions/{session_id}")


#: the most characters of a validation label (the JSON API's bound too: A, B, C are drawn)
MAX_LABEL = 4
#: the most gaits ``shown`` may name (a validation round shows three), and the most characters of
#: its text, measured before it is parsed (gait ids are a library's: no shorter bound is theirs)
MAX_SHOWN, MAX_SHOWN_TEXT = 8, 64_000


def _shown(text: str | None) -> list[str] | None:
    """The gaits a validation page showed, in label order (a JSON list of names; None: not
    said, as from a form made elsewhere), within bounds: the text is measured before it is
    parsed (a deeply nested one raised json's RecursionError)."""
    if text is None:
        return None
    what = f"the gaits the page showed, as a JSON list of at most {MAX_SHOWN} names"
    if len(text) > MAX_SHOWN_TEXT:
        raise InputError("shown", f"{what}; got {len(text):,} characters")
    try:
        names = json.loads(text)
    except (ValueError, RecursionError):
        names = None
    if (
        not isinstance(names, list)
        or len(names) > MAX_SHOWN
        or not all(isinstance(n, str) for n in names)
    ):
        raise InputError("shown", what)
    return names


# -- export ------------------------------------------------------------------------------------
@router.get("/sessions/{session_id}/export.zip")
async def export_zip(
    request: Request,
    session_id: SessionId,
    format: Annotated[str, Query(pattern="^(csv|json)$")] = "csv",
) -> Response:
    fmt: ExportFormat = "json" if format == "json" else "csv"
    data = await run_in_threadpool(service_of(request).export_zip, session_id, fmt)
    return Response(
        data,
        media_type="application/zip",
        headers={"content-disposition": f'attachment; filename="session-{session_id}-{fmt}.zip"'},
    )


__all__ = ["router"]
