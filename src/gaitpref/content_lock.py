"""A cross-process lock per content-addressed file, on a sidecar lock file in its folder.

The console's uploaded gait libraries (``console/configs.py``: ``<libraries>/<sha256 prefix>/``)
and an imported session's copy of its library (``sessions/export.py``:
``lab.db.libraries/<sha256>.json``) are named by their content, so several sessions share one
file.  A request that wrote such a file removes it again if its session is then refused; without
a lock, a concurrent request for the same content could find the file there (and so not write
it), create its session reading it, and then lose it to the first request's removal.  Each such
request therefore holds :func:`content_lock` for its content from the moment it finds or writes
the file until the session reading it is committed or the file is removed: the two take turns,
and the second one either finds a file that stays or writes it anew.

- The lock is an exclusive ``fcntl.flock`` on ``<folder>/.<key>.lock``, never on the content
  file itself (that is replaced atomically by rename, so a lock on it would be on a file no
  longer there).  ``flock`` locks belong to an open file, so two threads of one process (each
  opens the lock file) and two processes (two ``gaitpref session import``, or a console and a
  command) take turns alike.  The file is opened for reading only (``flock`` needs no more), so
  a lock file another account made with its umask's mode still serves.  Waiting is not
  bounded: a holder holds it only while it creates one session, and a process that dies
  releases it.
- Locks are per key (the content's hash), so requests for other content never wait.
- Lock files are left in place: removing one races (a waiter holding the removed file's lock and
  a newcomer locking a new file of that name would both think they hold it).  They are empty.
- POSIX only, as ``storage/turns.py``: where ``fcntl`` is missing (Windows) the lock is no lock,
  and the race above is not closed there.  Where the lock file cannot be opened or made (a
  folder this account may not write) there is no lock either, as there: the caller goes on as
  before, and finds or fails to write its file as it would have.

This module imports nothing of gaitpref's: the console and the sessions package use it.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None  # type: ignore[assignment]

#: read-only is enough for ``flock``; created as ``open`` creates a file (0666 less the umask)
_FLAGS = os.O_RDONLY | os.O_CREAT | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_NOFOLLOW", 0)


def lock_path(folder: Path, key: str) -> Path:
    """The lock file of ``key`` in ``folder``: ``<folder>/.<key>.lock``."""
    return folder / f".{key}.lock"


@contextmanager
def content_lock(folder: Path, key: str) -> Iterator[None]:
    """Hold the exclusive lock of ``key`` (a content hash, a file-name-safe string) in
    ``folder``; waits for another holder.  No lock (the block runs as it is) without ``fcntl``
    or where the lock file cannot be opened."""
    fd = _open(lock_path(folder, key))
    if fd is None:
        yield
        return
    assert fcntl is not None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fd, fcntl.LOCK_UN)
    finally:
        os.close(fd)


def _open(path: Path) -> int | None:
    """The lock file, open (made if not there); None without ``fcntl`` or where it cannot be."""
    if fcntl is None:  # pragma: no cover - Windows
        return None
    try:
        return os.open(path, _FLAGS, 0o666)
    except OSError:  # a folder this account may not write (or none): no lock
        return None


__all__ = ["content_lock", "lock_path"]
