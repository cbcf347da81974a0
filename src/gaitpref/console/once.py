"""One post per form: a second post of the same form gets the first's answer, not a second write.

Without JavaScript (which disables a form's button once it is sent) a double click on "Create"
or "Add note" posted the form twice, and the console created two sessions or wrote the note
twice.  The create and note forms now carry a hidden ``once`` token, new each time a page is
rendered; the console remembers the tokens of its last :data:`REMEMBERED` such posts (a bounded
memory) and answers a second post of one with the first's redirect, after waiting for the first
to finish.  A first post that fails forgets its token, so that sending the form again (after
fixing it) is taken.  A form without the token (a script, a form made elsewhere) is taken as
before; a token that is not one this console makes is refused (422 naming ``once``).
"""

from __future__ import annotations

import asyncio
import re
import secrets
from collections import OrderedDict
from collections.abc import Awaitable, Callable

from gaitpref.console.errors import InputError

#: the form field that carries the token
ONCE_FIELD = "once"
#: how many posts' tokens are remembered (the oldest is forgotten first)
REMEMBERED = 4096
_TOKEN = re.compile(r"[A-Za-z0-9_-]{16,64}")


def new_token() -> str:
    """A fresh token for one rendered form."""
    return secrets.token_urlsafe(16)


class OncePosts:
    """The tokens of recent posts and, for each, the redirect it answered (or will answer)."""

    def __init__(self, remembered: int = REMEMBERED) -> None:
        self._remembered = remembered
        self._seen: OrderedDict[str, asyncio.Future[str | None]] = OrderedDict()

    def __len__(self) -> int:
        return len(self._seen)

    async def run(self, token: str | None, post: Callable[[], Awaitable[str]]) -> str:
        """``post()`` (which writes and returns the URL to redirect to), unless a post of
        ``token`` came first: then the URL that one returned."""
        if token is None or token == "":
            return await post()
        if not _TOKEN.fullmatch(token):
            raise InputError(ONCE_FIELD, "not a form token of this console: reload the page")
        first = self._seen.get(token)
        if first is not None:
            url = await asyncio.shield(first)
            if url is not None:
                return url
            return await post()  # the first failed: this one is taken on its own
        mine: asyncio.Future[str | None] = asyncio.get_running_loop().create_future()
        self._seen[token] = mine
        while len(self._seen) > self._remembered:
            self._seen.popitem(last=False)
        try:
            url = await post()
        except BaseException:
            if self._seen.get(token) is mine:
                del self._seen[token]
            mine.set_result(None)
            raise
        mine.set_result(url)
        return url


__all__ = ["ONCE_FIELD", "REMEMBERED", "OncePosts", "new_token"]
