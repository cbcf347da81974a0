"""Rendering pages: one Jinja2 environment (autoescaped), the CSRF cookie, error pages."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from fastapi import Request
from fastapi.responses import HTMLResponse
from jinja2 import Environment, FileSystemLoader, select_autoescape

from gaitpref import __version__
from gaitpref.console.errors import Refusal
from gaitpref.console.once import ONCE_FIELD, new_token
from gaitpref.console.security import CSRF_COOKIE, CSRF_FIELD, Csrf

_ENV = Environment(
    loader=FileSystemLoader(Path(__file__).parent / "templates"),
    autoescape=select_autoescape(default=True),
    trim_blocks=True,
    lstrip_blocks=True,
)


def render(request: Request, template: str, status_code: int = 200, **context: Any) -> HTMLResponse:
    """``template`` with ``context``; the page carries a CSRF token for its forms."""
    csrf: Csrf = request.app.state.csrf
    token = request.cookies.get(CSRF_COOKIE)
    fresh = not csrf.valid(token)
    if fresh or token is None:
        token = csrf.issue()
    html = _ENV.get_template(template).render(
        request=request,
        csrf_field=CSRF_FIELD,
        csrf_token=token,
        once_field=ONCE_FIELD,
        once=new_token,
        version=__version__,
        **context,
    )
    response = HTMLResponse(html, status_code=status_code)
    response.headers["cache-control"] = "no-store"
    if fresh:
        response.set_cookie(CSRF_COOKIE, token, httponly=True, samesite="strict", path="/")
    return response


def confirm_page(
    request: Request,
    session_id: int,
    what: str,
    lines: list[str],
    fields: dict[str, str],
    action: str,
    *,
    note: str = "",
    back: str | None = None,
) -> HTMLResponse:
    """The confirm step as a page, for a browser without JavaScript: ``lines`` say what will be
    written, ``fields`` are posted again to ``action`` with ``confirmed=1``; Back goes to
    ``back`` (default: the session's page)."""
    return render(
        request,
        "confirm.html",
        session_id=session_id,
        what=what,
        lines=lines,
        fields=fields,
        note=note,
        action=action,
        back=back,
    )


def page_error(request: Request, ref: Refusal) -> HTMLResponse:
    """An error page that says what happened and that nothing was written."""
    return render(request, "error.html", status_code=ref.status, ref=ref)
