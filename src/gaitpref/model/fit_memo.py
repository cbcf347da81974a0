"""Remembered Laplace modes: a large fit already made is checked at its mode, not made again.

A session rebuilt from its log (``sessions/replay.py``) makes every fit its answers made, in
order; a warm start's answer makes six fits over every (gait, subject) pair, 9 Newton iterations
each (about 9 s an answer at 1,501 pairs), so reopening a 30-answer session took minutes.  A
:class:`FitMemo` maps a fit's problem, a SHA-256 of everything :func:`~gaitpref.model.laplace.
fit_laplace` reads (the prior covariance ``K_VV``, the observations' indices, the likelihoods,
the start, the tolerance), to the whitened mode ``u`` it converged to and the gradient's norm
there.  While a memo is active (:func:`remembering`), a fit over at least :data:`MEMO_FROM`
visited actions whose problem is remembered evaluates the objective once, at the remembered
mode, and returns it if the gradient there passes the fit's own convergence test (or is the
remembered norm exactly, where the fit had stopped on rounding).  Everything it returns is then
what the original fit computed in its last iteration, the same arithmetic on the same numbers:
the same bits (only ``iterations`` says 1).  Anything else (a problem not remembered, an entry
that fails the test) is fitted as without a memo, so a memo can make a fit faster, never
different; a wrong entry costs one evaluation of the objective.

The sessions package keeps a session's memo in a file beside a SQLite database
(``sessions/fit_cache.py``); it is a cache, never data: deleting it costs time only.
"""

from __future__ import annotations

import contextlib
import hashlib
import pickle
import threading
from collections import OrderedDict
from collections.abc import Iterator
from contextvars import ContextVar
from dataclasses import dataclass

import numpy as np

from gaitpref.space import FloatArray

#: Fits over fewer visited actions are not remembered (they take milliseconds).
MEMO_FROM = 256
#: The most modes one memo holds (the least recently used go first): about 2,000 answers of a
#: warm start's six fits, 12 MB a thousand at 1,500 pairs.
MAX_ENTRIES = 4096


@dataclass(frozen=True)
class Remembered:
    """A fit's whitened mode and the gradient's max-norm there, as it converged."""

    mode: FloatArray
    gradient_norm: float


class FitMemo:
    """Remembered modes by problem digest (thread-safe; the share weighing fits in threads)."""

    def __init__(self) -> None:
        self._entries: OrderedDict[bytes, Remembered] = OrderedDict()
        self._lock = threading.Lock()
        self.dirty = False  # something was added since it was loaded or saved

    def __len__(self) -> int:
        return len(self._entries)

    def get(self, key: bytes) -> Remembered | None:
        with self._lock:
            entry = self._entries.get(key)
            if entry is not None:
                self._entries.move_to_end(key)
            return entry

    def put(self, key: bytes, entry: Remembered) -> None:
        with self._lock:
            if key in self._entries:
                self._entries.move_to_end(key)
                return
            self._entries[key] = entry
            while len(self._entries) > MAX_ENTRIES:
                self._entries.popitem(last=False)
            self.dirty = True

    def items(self) -> list[tuple[bytes, Remembered]]:
        with self._lock:
            return list(self._entries.items())


_ACTIVE: ContextVar[FitMemo | None] = ContextVar("gaitpref_fit_memo", default=None)


@contextlib.contextmanager
def remembering(memo: FitMemo | None) -> Iterator[None]:
    """Fits inside the block (and in threads started from it with the context copied, as
    :func:`~gaitpref.model.threads.in_threads` does) consult and fill ``memo``; None: no memo."""
    token = _ACTIVE.set(memo)
    try:
        yield
    finally:
        _ACTIVE.reset(token)


def active() -> FitMemo | None:
    """The memo of the current context, if any."""
    return _ACTIVE.get()


def problem_key(*parts: object) -> bytes | None:
    """A SHA-256 of a fit's inputs: arrays by dtype, shape and bytes, None as a marker, other
    objects (likelihoods) by their pickle; None if one cannot be pickled (not remembered)."""
    digest = hashlib.sha256(b"gaitpref-fit-memo-1")
    for part in parts:
        if part is None:
            digest.update(b"\x00none")
        elif isinstance(part, np.ndarray):
            array = np.ascontiguousarray(part)
            digest.update(f"\x01{array.dtype.str}{array.shape}".encode())
            digest.update(array.tobytes())
        else:
            try:
                digest.update(b"\x02" + pickle.dumps(part, protocol=5))
            except Exception:  # a likelihood holding something unpicklable: not remembered
                return None
    return digest.digest()


__all__ = [
    "MAX_ENTRIES",
    "MEMO_FROM",
    "FitMemo",
    "Remembered",
    "active",
    "problem_key",
    "remembering",
]
