"""Size limits on what a client sends the console, enforced before anything is parsed.

==========================  ==============  ==================================================
what                        limit           beyond it
==========================  ==============  ==================================================
a JSON body (``/api/...``)  1 MB            413, before the JSON is read
a form body (pages)         66 MB           413 (a config upload and a gait library fit)
a form field (not a file)   1 MiB           413 saying so (a note, a reason, ...)
a form's fields             8,288           413 saying so (the largest answer form)
a form's files              1000            413 saying so
an uploaded config          200 kB          422 naming ``config_file``
a pasted config's text      200,000 chars   422 naming ``config``
an uploaded gait library    64 MB           422 naming ``library_file``
``comparisons``             6,112 items     413 naming the field (the most one answer holds)
``suggestions``             2,048 items     413 naming the field (a gait x feature each)
another list in a JSON      256 items       413 naming the field (``feedback``, ...)
==========================  ==============  ==================================================

A ``Content-Length`` that is not a number is a 400 saying so, not a 413.  The byte limits are
checked on ``Content-Length`` when the client sends one and on the bytes actually received
otherwise (a chunked body is cut off as soon as it passes the limit), so a 50 MB
body costs the server the time to read 1 MB, not to parse 50 MB.  The form limits are
Starlette's form parser's, given to it here (:func:`form_error` reads its refusals); they were
its defaults, and its refusal a bare JSON 400.  The API answers JSON; a page answers with the
console's HTML error page, which says what was too large.
"""

from __future__ import annotations

import json
import re
from typing import TYPE_CHECKING

from gaitpref.config.schema import MAX_FEATURES, MAX_QUERY
from gaitpref.console.errors import FormTooLargeError, FormUnreadableError, Refusal

if TYPE_CHECKING:  # annotations only: `gaitpref --help` does not import Starlette
    from starlette.types import ASGIApp, Message, Receive, Scope, Send

#: the most bytes of a JSON request body
MAX_JSON_BODY = 1_000_000
#: the most items of a list in a JSON request body (``feedback``, ``prior_from``, ...)
MAX_LIST = 256
#: the most gaits of each part of a query a config may have (``[cospar] n`` and ``buffer``)
#: and the most features (the config schema's bounds)
QUERY_MOST, FEATURES_MOST = MAX_QUERY, MAX_FEATURES
#: the most comparisons one answer holds: each pair of the query's gaits with one executed
#: now, ``n (n - 1) / 2 + n b`` (an answer of a config with ``n = 24`` had 276, past
#: :data:`MAX_LIST`, and no answer to all its pairs could be sent)
MAX_COMPARISONS = QUERY_MOST * (QUERY_MOST - 1) // 2 + QUERY_MOST * QUERY_MOST
#: the most coactive suggestions one answer holds: one per executed gait and feature
MAX_SUGGESTIONS = QUERY_MOST * FEATURES_MOST
#: the most bytes of an uploaded config file
MAX_UPLOAD = 200_000
#: the most characters of a config's text given in a field (a page's ``config``, the API's
#: ``config``), checked before it is parsed: as much as an uploaded config holds
MAX_CONFIG_TEXT = 200_000
#: the most bytes of an uploaded gait library
MAX_LIBRARY_BYTES = 64_000_000
#: the most bytes of a form body (a config and a library upload, with room for the fields)
MAX_FORM_BODY = MAX_LIBRARY_BYTES + MAX_UPLOAD + 2_000_000
#: the most bytes of one field of a form that is not a file (Starlette's default, made explicit)
MAX_FORM_FIELD = 1024 * 1024
#: the most fields of one form: the trial page's answer form for the largest query a config
#: may have (a field per comparison, per suggestion and per rating, and a few more); it was
#: Starlette's default, 1,000, which a query of 45 gaits passed
MAX_FORM_FIELDS = MAX_COMPARISONS + MAX_SUGGESTIONS + QUERY_MOST + 64
#: the most files of one form (Starlette's default, made explicit)
MAX_FORM_FILES = 1000


def body_limit(scope: Scope) -> int:
    """The most bytes a request with this scope may send."""
    return MAX_JSON_BODY if scope["path"].startswith("/api/") else MAX_FORM_BODY


def too_large(limit: int) -> str:
    return (
        f"the request body is larger than {limit:,} bytes, the most this console accepts "
        "(see the limits in docs/console.md)"
    )


def form_too_large(limit: int) -> str:
    """:func:`too_large` as a page says it: what the limit is made of."""
    return (
        f"the form is larger than {limit:,} bytes, the most this console takes in one form (an "
        f"uploaded config up to {MAX_UPLOAD // 1000} kB and a gait library up to "
        f"{MAX_LIBRARY_BYTES // 1_000_000} MB, with room for the fields; see the limits in "
        "docs/console.md)"
    )


def form_error(message: str) -> ValueError:
    """The console's error for Starlette's refusal ``message`` of a page's form: a
    :class:`~gaitpref.console.errors.FormTooLargeError` saying which limit it passed, else a
    :class:`~gaitpref.console.errors.FormUnreadableError` quoting it."""
    see = "nothing in this console's forms needs more; see the limits in docs/console.md"
    if message.startswith(("Field exceeded", "Part exceeded")):
        return FormTooLargeError(
            f"a field of the form is larger than {MAX_FORM_FIELD:,} bytes (1 MiB), the most "
            f"one field may hold (files are apart: a config up to {MAX_UPLOAD // 1000} kB, a "
            f"gait library up to {MAX_LIBRARY_BYTES // 1_000_000} MB); {see}"
        )
    if message.startswith("Too many fields"):
        return FormTooLargeError(
            f"the form has more than {MAX_FORM_FIELDS:,} fields, the most one form may have; {see}"
        )
    if message.startswith("Too many files"):
        return FormTooLargeError(
            f"the form has more than {MAX_FORM_FILES:,} files, the most one form may have; {see}"
        )
    return FormUnreadableError(f"the form could not be read: {message}")


class BodyLimitMiddleware:
    """Answer 413 to a request whose body passes :func:`body_limit`, before it is parsed."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        limit = body_limit(scope)
        declared = dict(scope["headers"]).get(b"content-length")
        if declared is not None and not declared.isdigit():  # not a size: not "too large"
            await _send_400(scope, send, "the Content-Length header is not a number of bytes")
            return
        if declared is not None and int(declared) > limit:
            await _send_413(scope, send, limit)
            return
        received = 0
        over = False
        started = False

        async def counting_receive() -> Message:
            nonlocal received, over
            if over:  # the app asks again after the cut: the client is gone as far as it knows
                return {"type": "http.disconnect"}
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > limit:
                    over = True
                    return {"type": "http.disconnect"}
            return message

        async def guarded_send(message: Message) -> None:
            nonlocal started
            if over:
                if not started:
                    started = True
                    await _send_413(scope, send, limit)
                return  # whatever the app answers to a cut-off body is replaced by the 413
            started = started or message["type"] == "http.response.start"
            await send(message)

        try:
            await self.app(scope, counting_receive, guarded_send)
        except Exception:
            if not over:
                raise
        if over and not started:
            await _send_413(scope, send, limit)


async def _send_413(scope: Scope, send: Send, limit: int) -> None:
    """The 413: JSON for the API, the console's HTML error page for a page."""
    ref = Refusal(413, "form too large", form_too_large(limit), None)
    await _send_refusal(scope, send, ref, too_large(limit))


async def _send_400(scope: Scope, send: Send, detail: str) -> None:
    """A 400 for a request whose headers are not HTTP's (a Content-Length that is no number)."""
    await _send_refusal(scope, send, Refusal(400, "request not readable", detail, None), detail)


async def _send_refusal(scope: Scope, send: Send, ref: Refusal, api_detail: str) -> None:
    """``ref`` as JSON (``api_detail``) for the API, as the console's HTML error page else."""
    if scope["path"].startswith("/api/"):
        data = json.dumps({"detail": api_detail}).encode()
        content_type = b"application/json"
    else:
        data = _error_page(scope, ref)
        content_type = b"text/html; charset=utf-8"
    headers = [
        (b"content-type", content_type),
        (b"content-length", str(len(data)).encode()),
        (b"connection", b"close"),
        (b"cache-control", b"no-store"),
    ]
    await send({"type": "http.response.start", "status": ref.status, "headers": headers})
    await send({"type": "http.response.body", "body": data})


def _error_page(scope: Scope, ref: Refusal) -> bytes:
    """The error page of ``ref`` (before routing: the session, if the path names one, is read
    from it for the page's link back to the trial)."""
    from starlette.requests import Request

    from gaitpref.console.templating import page_error

    named = re.match(r"/sessions/(\d+)(/|$)", scope["path"])
    params = {"session_id": named.group(1)} if named else {}
    request = Request({**scope, "path_params": params})
    return bytes(page_error(request, ref).body)
