"""The posterior figure of a session as PNG bytes, drawn by :mod:`gaitpref.plots.posterior`.

1-D spaces: posterior mean +- 2 sd with the trials; 2-D: a heat map of the mean with the trials
in order.  matplotlib's figure registry is not thread-safe, so drawing is serialized; finished
pictures are kept in a small cache keyed by (session, version), where the version changes with
every event the session writes.
"""

from __future__ import annotations

import io
import threading
from collections import OrderedDict
from collections.abc import Callable, Sequence

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

from gaitpref.model import Posterior
from gaitpref.plots.posterior import posterior_picture, render
from gaitpref.plots.session import render_session, session_picture
from gaitpref.sessions.session import Session

_DRAW_LOCK = threading.Lock()


def _png(draw: Callable[[], Figure], dpi: int) -> bytes:
    """Draw a figure (under the lock: pyplot is not thread-safe) and return it as PNG bytes."""
    with _DRAW_LOCK:
        fig = draw()
        try:
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=dpi)
        finally:
            plt.close(fig)
    return buf.getvalue()


def posterior_png(
    posterior: Posterior, trials: Sequence[int], *, title: str = "", dpi: int = 90
) -> bytes:
    """The posterior figure (mean, +- 2 sd or heat map, trials) as PNG bytes."""
    pic = posterior_picture(posterior, list(trials), samples=0, title=title)
    return _png(lambda: render(pic), dpi)


def session_png(session: Session, *, dpi: int = 90) -> bytes:
    """The paper-style figure of the session (``gaitpref.plots.session``) as PNG bytes."""
    pic = session_picture(session)
    return _png(lambda: render_session(pic), dpi)


class FigureCache:
    """The last ``size`` pictures, keyed by ``(session id, version, kind)``."""

    def __init__(self, size: int = 16) -> None:
        self._size = size
        self._items: OrderedDict[tuple[int, int, str], bytes] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, key: tuple[int, int, str]) -> bytes | None:
        with self._lock:
            png = self._items.get(key)
            if png is not None:
                self._items.move_to_end(key)
            return png

    def put(self, key: tuple[int, int, str], png: bytes) -> None:
        with self._lock:
            self._items[key] = png
            self._items.move_to_end(key)
            while len(self._items) > self._size:
                self._items.popitem(last=False)
