"""The operator console: a FastAPI application over the session API (``gaitpref console``).

- :func:`create_app` (``app.py``): the application; pages (``pages.py``) and the JSON API
  (``api.py``), access token and CSRF (``security.py``), errors to statuses (``errors.py``);
- :class:`SessionService` (``service.py``): the one door to :class:`gaitpref.Session`.

FastAPI is imported only when the application is made, so ``gaitpref --help`` stays quick.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from gaitpref.console.app import create_app
    from gaitpref.console.service import SessionService

__all__ = ["SessionService", "create_app"]


def __getattr__(name: str) -> Any:
    if name == "create_app":
        from gaitpref.console.app import create_app

        return create_app
    if name == "SessionService":
        from gaitpref.console.service import SessionService

        return SessionService
    raise AttributeError(f"module 'gaitpref.console' has no attribute {name!r}")
