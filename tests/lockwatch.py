"""Force two requests for one content-addressed file to interleave, without sleeps.

Request A runs in the test's thread and, at the point where it is about to fail, starts request
B in a thread and waits until B has *settled*: B either went through to the end (no lock stopped
it) or is blocked on the content's lock (:mod:`gaitpref.content_lock`), which :func:`watch_locks`
tells by trying the lock without blocking first.  A then fails and removes what it wrote; B goes
on.  Without the lock, B finds A's file, commits its session and then loses the file.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import pytest

import gaitpref.content_lock as content_lock_module

#: the most A waits for B (a bound for a broken test, never a synchronisation)
BOUND_S = 60.0


class Other:
    """Request B, in its own thread; :attr:`settled` is set once it is done or blocked."""

    def __init__(self, request: Callable[[], Any]) -> None:
        self.request = request
        self.settled = threading.Event()
        self.result: Any = None
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, name="request-B", daemon=True)

    def _run(self) -> None:
        try:
            self.result = self.request()
        except BaseException as exc:  # reported by join
            self.error = exc
        finally:
            self.settled.set()

    def start_and_settle(self) -> None:
        """Start B and return once it is done or waits for the lock."""
        self.thread.start()
        assert self.settled.wait(BOUND_S), "request B neither finished nor waited for the lock"

    def join(self) -> Any:
        self.thread.join(BOUND_S)
        assert not self.thread.is_alive(), "request B did not finish"
        if self.error is not None:
            raise self.error
        return self.result


def watch_locks(monkeypatch: pytest.MonkeyPatch, other: Other) -> None:
    """Make B's thread set ``other.settled`` when it finds the content lock taken, just before
    it blocks on it."""
    real = getattr(content_lock_module, "fcntl")  # noqa: B009 - not exported
    assert real is not None

    class Watched:
        LOCK_EX = real.LOCK_EX
        LOCK_NB = real.LOCK_NB
        LOCK_UN = real.LOCK_UN

        @staticmethod
        def flock(fd: int, how: int) -> None:
            if how == real.LOCK_EX and threading.current_thread() is other.thread:
                try:
                    real.flock(fd, real.LOCK_EX | real.LOCK_NB)
                    return
                except BlockingIOError:
                    other.settled.set()
            real.flock(fd, how)

    monkeypatch.setattr(content_lock_module, "fcntl", Watched)
