"""Access control for the console: an access token for every request, CSRF tokens for forms.

- **Token.**  When the console is given a token (always when it listens beyond the loopback
  interface), every request must carry it: ``Authorization: Bearer <token>``, the header
  ``X-Gaitpref-Token``, or the ``gaitpref_token`` cookie.  A browser gets the cookie by opening
  the printed URL once (``/?token=<token>``): the console sets it (HttpOnly, SameSite=Strict) and
  redirects to the same page without the token in the address.  Anything else is refused with 401
  before a route runs, so a refused request never reaches the session API.
- **CSRF.**  Every HTML form carries a hidden ``csrf_token`` equal to the ``gaitpref_csrf`` cookie;
  the value is ``nonce.signature`` with an HMAC-SHA256 signature under a per-application secret,
  so a page from another origin can neither read nor forge it.  The JSON API needs no CSRF token:
  it only accepts ``application/json`` bodies, which a cross-origin page cannot send without a
  CORS preflight that this console never grants.
- **Origin.**  A request that can change something (any method but GET, HEAD and OPTIONS) is
  refused with 403 when a browser says it comes from another origin: an ``Origin`` header that
  names another host and port than the request's ``Host`` (or ``X-Forwarded-Host``), ``Origin:
  null``, or ``Sec-Fetch-Site: cross-site``.  So a foreign page cannot post the API's body-less
  actions (undo, withdraw a flag, open a validation round) as a "simple" request, which needs no
  preflight; scripts and command-line clients send no ``Origin`` and are unaffected.
- **Host.**  Optionally only listed ``Host`` headers are served (DNS-rebinding protection for a
  console on the loopback interface).
"""

from __future__ import annotations

import hashlib
import hmac
import json
import secrets
from collections.abc import Iterable
from http.cookies import SimpleCookie
from typing import TYPE_CHECKING
from urllib.parse import parse_qsl, quote, urlencode, urlsplit

if TYPE_CHECKING:  # annotations only: `gaitpref --help` does not import Starlette
    from starlette.types import ASGIApp, Receive, Scope, Send

TOKEN_COOKIE = "gaitpref_token"
TOKEN_HEADER = "x-gaitpref-token"
CSRF_COOKIE = "gaitpref_csrf"
CSRF_FIELD = "csrf_token"
TOKEN_ENV = "GAITPREF_TOKEN"


def new_token() -> str:
    """A random access token (URL-safe, 32 bytes of entropy)."""
    return secrets.token_urlsafe(32)


def _headers(scope: Scope) -> dict[str, str]:
    return {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope["headers"]}


def _cookies(headers: dict[str, str]) -> dict[str, str]:
    jar: SimpleCookie = SimpleCookie()
    try:
        jar.load(headers.get("cookie", ""))
    except Exception:  # a malformed cookie header carries no token
        return {}
    return {k: m.value for k, m in jar.items()}


async def _send_plain(
    send: Send, status: int, body: dict[str, object], extra: Iterable[tuple[bytes, bytes]] = ()
) -> None:
    data = json.dumps(body).encode()
    headers = [(b"content-type", b"application/json"), (b"content-length", str(len(data)).encode())]
    await send({"type": "http.response.start", "status": status, "headers": [*headers, *extra]})
    await send({"type": "http.response.body", "body": data})


def _hostname(header: str) -> str:
    """The name in a ``Host`` header, without port or IPv6 brackets."""
    if header.startswith("["):
        return header[1 : header.find("]")].lower() if "]" in header else header.lower()
    return header.rsplit(":", 1)[0].lower()


def local_path(path: str) -> str:
    """``path`` (decoded, as in the ASGI scope) as a redirect target: a path on this console.

    Never a network location: ``//evil.example/x`` or ``/\\evil.example`` would send a browser
    to another host, so the leading run of slashes and backslashes becomes one ``/``, and every
    character that could end the path or change its meaning is percent-encoded.
    """
    return "/" + quote(path.lstrip("/\\"), safe="/:@!$&'()*+,;=-._~")


SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})
_DEFAULT_PORTS = {"http": "80", "https": "443"}


def _authority(netloc: str, scheme: str) -> str:
    """``host[:port]`` lowercased, without the scheme's default port."""
    netloc = netloc.strip().lower()
    default = _DEFAULT_PORTS.get(scheme)
    if default and netloc.endswith(f":{default}"):
        return netloc[: -len(default) - 1]
    return netloc


def foreign_origin(headers: dict[str, str], scheme: str) -> str | None:
    """Why a request comes from another origin, as a browser says (None: it does not say so)."""
    if headers.get("sec-fetch-site", "").strip().lower() == "cross-site":
        return "Sec-Fetch-Site: cross-site"
    origin = headers.get("origin")
    if origin is None:
        return None
    parts = urlsplit(origin.strip())
    if not parts.scheme or not parts.netloc:
        return f"Origin {origin[:100]!r}"
    served = headers.get("x-forwarded-host") or headers.get("host", "")
    here = {_authority(h, s) for h in served.split(",")[:1] for s in (scheme, parts.scheme)}
    if _authority(parts.netloc, parts.scheme) not in here:
        return f"Origin {origin[:100]!r} is not this console ({served[:100]!r})"
    return None


class AccessMiddleware:
    """Refuse requests without the access token (if one is set), with a foreign Host header, or
    changes a browser says come from another origin."""

    def __init__(
        self, app: ASGIApp, token: str | None, allowed_hosts: Iterable[str] | None = None
    ) -> None:
        self.app = app
        self.token = token
        self.allowed_hosts = None if allowed_hosts is None else {h.lower() for h in allowed_hosts}

    def _token_ok(self, candidate: str | None) -> bool:
        if self.token is None:
            return True
        if not candidate:
            return False
        return hmac.compare_digest(candidate.encode(), self.token.encode())

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = _headers(scope)
        if self.allowed_hosts is not None:
            host = _hostname(headers.get("host", ""))
            if host not in self.allowed_hosts:
                await _send_plain(send, 400, {"detail": f"host {host!r} is not served here"})
                return
        if scope["method"] not in SAFE_METHODS:
            foreign = foreign_origin(headers, scope.get("scheme", "http"))
            if foreign is not None:
                await _send_plain(
                    send,
                    403,
                    {
                        "detail": f"cross-origin request refused ({foreign}): this console takes "
                        "changes only from its own pages and from clients that send no Origin"
                    },
                )
                return
        if self.token is None:
            await self.app(scope, receive, send)
            return
        query = parse_qsl(scope.get("query_string", b"").decode("latin-1"))
        from_query = next((v for k, v in query if k == "token"), None)
        if from_query is not None and scope["method"] in ("GET", "HEAD"):
            if not self._token_ok(from_query):
                await _send_plain(send, 401, {"detail": "wrong access token in the address"})
                return
            rest = urlencode([(k, v) for k, v in query if k != "token"])
            location = local_path(scope.get("root_path", "") + scope["path"])
            location += f"?{rest}" if rest else ""
            cookie = f"{TOKEN_COOKIE}={self.token}; HttpOnly; SameSite=Strict; Path=/"
            await send(
                {
                    "type": "http.response.start",
                    "status": 303,
                    "headers": [
                        (b"location", location.encode("latin-1")),
                        (b"set-cookie", cookie.encode("latin-1")),
                        (b"content-length", b"0"),
                    ],
                }
            )
            await send({"type": "http.response.body", "body": b""})
            return
        auth = headers.get("authorization", "")
        bearer = auth[7:].strip() if auth.lower().startswith("bearer ") else None
        candidates = (bearer, headers.get(TOKEN_HEADER), _cookies(headers).get(TOKEN_COOKIE))
        if any(self._token_ok(c) for c in candidates if c):
            await self.app(scope, receive, send)
            return
        await _send_plain(
            send,
            401,
            {
                "detail": "this console needs its access token: open the URL it printed at start "
                "(with ?token=...), or send 'Authorization: Bearer <token>'"
            },
            [(b"www-authenticate", b"Bearer")],
        )


class Csrf:
    """Signed double-submit CSRF tokens under a per-application secret."""

    def __init__(self, secret: bytes | None = None) -> None:
        self._secret = secret if secret is not None else secrets.token_bytes(32)

    def _sign(self, nonce: str) -> str:
        return hmac.new(self._secret, nonce.encode(), hashlib.sha256).hexdigest()[:40]

    def issue(self) -> str:
        """A fresh token (``nonce.signature``)."""
        nonce = secrets.token_urlsafe(18)
        return f"{nonce}.{self._sign(nonce)}"

    def valid(self, token: str | None) -> bool:
        """Whether ``token`` was issued by this application."""
        if not token or token.count(".") != 1:
            return False
        nonce, sig = token.split(".")
        return hmac.compare_digest(sig.encode(), self._sign(nonce).encode())

    def check(self, cookie: str | None, field: str | None) -> bool:
        """Whether a form's ``field`` matches its ``cookie`` and both are this app's tokens."""
        if not (cookie and field and self.valid(cookie)):
            return False
        return hmac.compare_digest(cookie.encode(), field.encode())
