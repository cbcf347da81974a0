"""The trial page's unsafe flags: flag an answered trial (a reason, then a confirm step) and
withdraw a flag.

A flag is the operator's hard stop (:meth:`gaitpref.Session.flag_unsafe`): the trial's gait and
the gaits within the config's ``[safety] unsafe_radius`` are never proposed again, and a pending
query that proposed one of them is withdrawn, so the page the post redirects to shows the query
proposed after the flag.  Without JavaScript the confirm step is a server-rendered page.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import Response

from gaitpref.console.errors import InputError
from gaitpref.console.pages import (
    SessionId,
    read_form,
    see_other,
    service_of,
    trial_list,
    trial_page_url,
)
from gaitpref.console.schemas import MAX_ID
from gaitpref.console.templating import confirm_page
from gaitpref.console.views import free_text
from gaitpref.sessions.session import Session

router = APIRouter(include_in_schema=False)


@router.post("/sessions/{session_id}/trials/{trial}/unsafe")
async def post_unsafe(
    request: Request, session_id: SessionId, trial: Annotated[int, Path(ge=1, le=MAX_ID)]
) -> Response:
    """Flag an answered trial unsafe (a reason is required; confirmed first)."""
    fields, _ = await read_form(request)
    reason = fields.get("reason", "").strip()
    if not reason:
        raise InputError("reason", "say why the trial was unsafe (the reason is required)")
    free_text(reason, "reason", "the reason")
    listing = trial_list(fields)  # from the page listing every trial: back to it
    service = service_of(request)
    if fields.get("confirmed") != "1":

        def summary(session: Session) -> list[str]:
            session.check_change("unsafe", trial)  # undone, flagged since, finished: 409 now
            gait = next(t.action for t in session.trials() if t.number == trial)
            radius = session.config.safety.unsafe_radius
            near = f" and the gaits within {radius:g} of its range" if radius else ""
            close = (
                ", but gaits however close to it may be (unsafe_radius = 0 on a continuous feature)"
                if not radius and session.config.space.continuous
                else ""
            )
            return [
                f"Flag trial {trial} ({session.describe(gait)}) unsafe: {reason}",
                f"Its gait{near} will not be proposed again{close} (the flag can be withdrawn).",
            ]

        lines = await run_in_threadpool(service.read, session_id, summary)
        return confirm_page(
            request,
            session_id,
            "unsafe",
            lines,
            fields,
            f"/sessions/{session_id}/trials/{trial}/unsafe",
            back=trial_page_url(session_id, listing),
        )
    replaced = await run_in_threadpool(service.flag_unsafe, session_id, trial, reason)
    done = f"flagged={trial}&replaced={int(replaced)}"
    return see_other(trial_page_url(session_id, done, listing))


@router.post("/sessions/{session_id}/trials/{trial}/unsafe/withdraw")
async def post_withdraw_unsafe(
    request: Request, session_id: SessionId, trial: Annotated[int, Path(ge=1, le=MAX_ID)]
) -> Response:
    """Withdraw the unsafe flag of a trial (confirmed first)."""
    fields, _ = await read_form(request)
    listing = trial_list(fields)
    if fields.get("confirmed") != "1":
        await run_in_threadpool(  # withdrawn since (another tab), finished: 409 now
            service_of(request).read, session_id, lambda s: s.check_change("withdraw", trial)
        )
        lines = [f"Withdraw the unsafe flag of trial {trial}: its gait may be proposed again."]
        action = f"/sessions/{session_id}/trials/{trial}/unsafe/withdraw"
        back = trial_page_url(session_id, listing)
        return confirm_page(request, session_id, "withdraw", lines, fields, action, back=back)
    await run_in_threadpool(service_of(request).withdraw_unsafe, session_id, trial)
    return see_other(trial_page_url(session_id, f"withdrawn={trial}", listing))


__all__ = ["router"]
