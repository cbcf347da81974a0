"""The posterior figure of a session as PNG bytes, drawn by :mod:`gaitpref.plots.posterior`.

1-D spaces: posterior mean +- 2 sd with the trials; 2-D: a heat map of the mean with the trials
in order; both shade the region of avoidance and mark the gaits flagged unsafe, with their
radius, when the session has them.  A space with no 1-D or 2-D grid (continuous features, the
line path, more features) gets the posterior at each trial's point instead
(:mod:`gaitpref.plots.trials`), for both figures.  matplotlib's figure registry is not
thread-safe, so drawing is serialized, in one drawing thread that requests await
(:class:`FigureRenderer`: a figure never holds a worker thread that an answer needs); finished
pictures are kept in a small cache keyed by (session, version), where the version changes with
every event the session writes.
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import os
import threading
from collections import OrderedDict
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from multiprocessing import get_context

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

from gaitpref.model import Posterior
from gaitpref.plots.posterior import PosteriorPicture, posterior_picture, render
from gaitpref.plots.session import (
    SessionPicture,
    render_session,
    session_picture,
    session_shading,
)
from gaitpref.plots.trials import TrialsPicture, on_a_grid, render_trials, trials_picture
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


Picture = PosteriorPicture | SessionPicture | TrialsPicture


def picture_of(session: Session, kind: str) -> Picture:
    """The data of a session's ``kind`` figure ("posterior" or "session"), read now."""
    post = session.posterior()
    trials = [t.action for t in session.trials()]
    title = f"session {session.id}: posterior after {len(trials)} trials"
    if not on_a_grid(post.space):  # continuous, or past 2-D: the posterior at the trials
        return trials_picture(post, trials, recommended=session.recommended(), title=title)
    if kind == "session":
        return session_picture(session)
    return posterior_picture(
        post,
        trials,
        samples=0,
        title=title,
        safety=session_shading(session, post),  # the region of avoidance and the unsafe flags
        recommending=True,
        recommended=session.recommended(),
    )


def png_of(pic: Picture, dpi: int = 90) -> bytes:
    """A picture's PNG bytes (a plain function of plain data: runs in the drawing process)."""
    if isinstance(pic, SessionPicture):
        return _png(lambda: render_session(pic), dpi)
    if isinstance(pic, TrialsPicture):
        return _png(lambda: render_trials(pic), dpi)
    return _png(lambda: render(pic), dpi)


def _yield_cpu() -> None:
    """In the drawing process: a lower CPU priority, so that answers go first on a busy machine."""
    with contextlib.suppress(OSError, AttributeError):
        os.nice(10)


@dataclass
class _Job:
    future: Future[bytes]
    started: bool = False


class FigureRenderer:
    """Figures drawn off the request path: in a drawing process, newest first, shared.

    - A figure request awaits its picture (``asyncio``) instead of holding one of the server's
      worker threads, so browsers asking for figures never take the threads answers need.
    - Drawing runs in one separate process (matplotlib holds the GIL for the whole drawing;
      in-process it would slow every answer); where no process can be started, in one thread.
    - At most one drawing per (session, kind) waits: it reads the session when it starts, so
      every request made before then gets the newest picture from one drawing.
    """

    def __init__(self, cache: FigureCache | None = None, *, processes: bool = True) -> None:
        self.cache = cache if cache is not None else FigureCache()
        self._queue = ThreadPoolExecutor(max_workers=1, thread_name_prefix="gaitpref-figures")
        self._waiting: dict[tuple[int, str], _Job] = {}
        self._lock = threading.Lock()
        self._processes = processes
        self._drawer: ProcessPoolExecutor | None = None

    async def png(
        self, session_id: int, kind: str, version: int, fetch: Callable[[], tuple[int, Picture]]
    ) -> bytes:
        """The ``kind`` picture of ``session_id`` at ``version`` or newer.

        ``fetch()`` reads the session's newest (version, picture) when the drawing starts.
        """
        png = self.cache.get((session_id, version, kind))
        if png is not None:
            return png
        with self._lock:
            job = self._waiting.get((session_id, kind))
            if job is None or job.started:
                job = _Job(Future())
                self._waiting[(session_id, kind)] = job
                self._queue.submit(self._run, session_id, kind, job, fetch)
        return await asyncio.wrap_future(job.future)

    def _run(
        self, session_id: int, kind: str, job: _Job, fetch: Callable[[], tuple[int, Picture]]
    ) -> None:
        with self._lock:
            job.started = True
            if self._waiting.get((session_id, kind)) is job:
                del self._waiting[(session_id, kind)]
        try:
            version, pic = fetch()
            key = (session_id, version, kind)
            png = self.cache.get(key) or self._draw(pic)
            self.cache.put(key, png)
            job.future.set_result(png)
        except BaseException as exc:  # the request that waits reports it
            job.future.set_exception(exc)

    def _draw(self, pic: Picture) -> bytes:
        if self._processes and self._drawer is None:
            try:
                self._drawer = ProcessPoolExecutor(
                    1, mp_context=get_context("spawn"), initializer=_yield_cpu
                )
            except (OSError, ValueError):
                self._processes = False
        if self._drawer is not None:
            try:
                return self._drawer.submit(png_of, pic).result()
            except BrokenProcessPool:
                self._drawer = None  # drawn here this time, a new process next time
        return png_of(pic)

    def close(self) -> None:
        self._queue.shutdown(wait=False, cancel_futures=True)
        if self._drawer is not None:
            self._drawer.shutdown(wait=False, cancel_futures=True)


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
