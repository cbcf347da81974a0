"""The console's FastAPI application: pages, the JSON API, static files, access control.

    app = create_app("sqlite:///lab.db")                  # loopback use, no token
    app = create_app("sqlite:///lab.db", token="s3cret")  # every request must carry the token

``gaitpref console`` serves it with uvicorn (``gaitpref.cli.console``).
"""

from __future__ import annotations

from collections.abc import AsyncIterator, Iterable
from contextlib import asynccontextmanager
from pathlib import Path

import pydantic
from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse, Response
from fastapi.staticfiles import StaticFiles

from gaitpref import __version__
from gaitpref.console import api, flag_pages, pages
from gaitpref.console.errors import HANDLED, refusal
from gaitpref.console.figures import FigureRenderer
from gaitpref.console.limits import MAX_LIST, BodyLimitMiddleware
from gaitpref.console.once import OncePosts
from gaitpref.console.security import AccessMiddleware, Csrf
from gaitpref.console.service import SessionService
from gaitpref.console.templating import page_error
from gaitpref.storage import Storage

HERE = Path(__file__).parent


def _plain(error: dict[str, object]) -> dict[str, object]:
    """A validation error as the API reports it: ``loc``, ``msg`` and ``type`` (FastAPI's
    shape) without the echoed ``input`` and ``ctx``, which need not be JSON (an infinite
    number, a lone surrogate) and would lose the field."""
    loc = error.get("loc", ())
    msg = str(error.get("msg", "invalid"))
    return {
        "loc": list(loc) if isinstance(loc, tuple | list) else [],
        "msg": msg.encode("utf-8", "backslashreplace").decode("utf-8"),
        "type": str(error.get("type", "value_error")),
    }


def create_app(
    db: str | Storage | None = None,
    token: str | None = None,
    *,
    csrf_secret: bytes | None = None,
    allowed_hosts: Iterable[str] | None = None,
    library_dir: str | Path | None = None,
) -> FastAPI:
    """The console over database ``db`` (a URL, a storage, or None for the default).

    ``token``: when given, every request must carry it (see :mod:`gaitpref.console.security`).
    ``allowed_hosts``: serve only these ``Host`` names (None: any).  ``library_dir``: where
    uploaded gait libraries are kept and configs may name them (default: ``gait-libraries/``
    beside a SQLite database, else in the working folder).
    """
    service = SessionService(db, library_dir)

    @asynccontextmanager
    async def lifespan(_: FastAPI) -> AsyncIterator[None]:
        yield
        app.state.figures.close()
        service.close()

    app = FastAPI(
        title="gaitpref operator console",
        version=__version__,
        description=(
            "Run a CoSpar gait-preference session at the bench. The JSON API under /api/ does "
            "what the pages do; 409 means the query is stale or already answered (nothing was "
            "written), 422 names the malformed field, 413 refuses a body over 1 MB or a list "
            "over 256 items."
        ),
        lifespan=lifespan,
    )
    app.state.service = service
    app.state.csrf = Csrf(csrf_secret)
    app.state.figures = FigureRenderer()
    app.state.once = OncePosts()
    app.state.token_required = token is not None
    app.include_router(api.router)
    app.include_router(pages.router)
    app.include_router(flag_pages.router)
    app.mount("/static", StaticFiles(directory=HERE / "static"), name="static")
    app.add_middleware(BodyLimitMiddleware)  # inside the token check: strangers get 401 first
    app.add_middleware(AccessMiddleware, token=token, allowed_hosts=allowed_hosts)

    async def handle(request: Request, exc: Exception) -> Response:
        if isinstance(exc, pydantic.ValidationError):
            raise exc  # a bug in the console's own models, not the client's input
        ref = refusal(exc, request.method)
        retry = {"retry-after": "1"} if ref.status == 503 else None
        if request.url.path.startswith("/api/"):
            return JSONResponse(ref.api_body(), status_code=ref.status, headers=retry)
        response = page_error(request, ref)
        response.headers.update(retry or {})
        return response

    for kind in HANDLED:
        app.add_exception_handler(kind, handle)

    async def invalid(request: Request, exc: Exception) -> Response:
        assert isinstance(exc, RequestValidationError)
        errors = exc.errors()
        if request.url.path.startswith("/api/"):
            long = [
                e
                for e in errors
                if e.get("type") == "too_long"
                and e.get("ctx", {}).get("max_length", MAX_LIST) >= MAX_LIST
            ]
            if long:  # a list past the documented maximum: 413, as for a body past its size
                where = ".".join(str(p) for p in long[0]["loc"][1:])
                most = long[0].get("ctx", {}).get("max_length", MAX_LIST)
                return JSONResponse(
                    {"detail": f"{where}: at most {most} items (see docs/console.md)"},
                    status_code=413,
                )
            return JSONResponse({"detail": [_plain(e) for e in errors]}, status_code=422)
        field = ".".join(str(p) for p in errors[0]["loc"][1:]) if errors else ""
        return page_error(
            request, refusal(ValueError(f"{field}: {errors[0]['msg']}" if errors else "bad input"))
        )

    app.add_exception_handler(RequestValidationError, invalid)
    return app
