"""Size limits on what a client sends the console, enforced before anything is parsed.

==========================  ==============  ==================================================
what                        limit           beyond it
==========================  ==============  ==================================================
a JSON body (``/api/...``)  1 MB            413, before the JSON is read
a form body (pages)         66 MB           413 (a config upload and a gait library fit)
an uploaded config          200 kB          422 naming ``config_file``
an uploaded gait library    64 MB           422 naming ``library_file``
a list in a JSON body       256 items       413 naming the field (``comparisons``, ...)
==========================  ==============  ==================================================

The byte limits are checked on ``Content-Length`` when the client sends one and on the bytes
actually received otherwise (a chunked body is cut off as soon as it passes the limit), so a
50 MB body costs the server the time to read 1 MB, not to parse 50 MB.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # annotations only: `gaitpref --help` does not import Starlette
    from starlette.types import ASGIApp, Message, Receive, Scope, Send

#: the most bytes of a JSON request body
MAX_JSON_BODY = 1_000_000
#: the most items of any list in a JSON request body (comparisons, suggestions, ranking)
MAX_LIST = 256
#: the most bytes of an uploaded config file
MAX_UPLOAD = 200_000
#: the most bytes of an uploaded gait library
MAX_LIBRARY_BYTES = 64_000_000
#: the most bytes of a form body (a config and a library upload, with room for the fields)
MAX_FORM_BODY = MAX_LIBRARY_BYTES + MAX_UPLOAD + 2_000_000


def body_limit(scope: Scope) -> int:
    """The most bytes a request with this scope may send."""
    return MAX_JSON_BODY if scope["path"].startswith("/api/") else MAX_FORM_BODY


def too_large(limit: int) -> str:
    return (
        f"the request body is larger than {limit:,} bytes, the most this console accepts "
        "(see the limits in docs/console.md)"
    )


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
        if declared is not None and (not declared.isdigit() or int(declared) > limit):
            await _send_413(send, limit)
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
                    await _send_413(send, limit)
                return  # whatever the app answers to a cut-off body is replaced by the 413
            started = started or message["type"] == "http.response.start"
            await send(message)

        try:
            await self.app(scope, counting_receive, guarded_send)
        except Exception:
            if not over:
                raise
        if over and not started:
            await _send_413(send, limit)


async def _send_413(send: Send, limit: int) -> None:
    data = json.dumps({"detail": too_large(limit)}).encode()
    headers = [
        (b"content-type", b"application/json"),
        (b"content-length", str(len(data)).encode()),
        (b"connection", b"close"),
    ]
    await send({"type": "http.response.start", "status": 413, "headers": headers})
    await send({"type": "http.response.body", "body": data})
