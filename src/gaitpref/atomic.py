"""A file written atomically, with the mode a plain ``open(path, "w")`` would give it.

:func:`write_text_atomic` writes a temporary file beside the target and renames it over the
target, so that a reader sees the old file or the new one, never part of one, and a write that
fails (a full disk) leaves neither a partial file nor the temporary one.  The gait library files
(``gaits/library_io.py``), the gait cache's entries (``gaits/gait_cache.py``), an imported
session's copy of its library (``sessions/export.py``) and the console's uploaded libraries
(``console/configs.py``) are written so; the temporary name is unique, so two writers of one
target never share a temporary file.

``tempfile.mkstemp`` creates its file with mode 0600 whatever the umask, so a file renamed from
it could be read by its owner only: on a shared lab machine the group (a colleague's account,
the lab's analysis account) could not read a library or a cache entry that a plain ``open``
would have let it read.  The temporary file is therefore created as ``open`` creates a file,
with mode 0666 for the operating system to narrow by the process umask (and by a folder's
default ACL, where it has one): the umask is never read, so no other thread's files are made
under a changed one.  A target that exists keeps its mode, as it would when ``open`` rewrote it
(the export folder does the same: ``sessions/export.py``); its owner becomes the writer's, as
for any file written anew.
"""

from __future__ import annotations

import os
import secrets
import stat
from pathlib import Path

#: as ``tempfile.mkstemp`` opens its file, for writing only: O_NOFOLLOW and O_BINARY where they
#: exist
_FLAGS = (
    os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)
)
_TRIES = 100


def write_bytes_atomic(target: Path, data: bytes, prefix: str) -> None:
    """Write ``data`` to ``target`` atomically, through a temporary file named ``prefix`` +
    random hex + ``.tmp`` in ``target``'s folder, which must exist."""
    fd, tmp = _create(target.parent, prefix)
    try:
        with os.fdopen(fd, "wb") as out:
            out.write(data)
        _keep_mode(target, tmp)
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_text_atomic(target: Path, text: str, prefix: str) -> None:
    """:func:`write_bytes_atomic` of ``text`` in UTF-8 (its newlines as they are)."""
    write_bytes_atomic(target, text.encode("utf-8"), prefix)


def _create(folder: Path, prefix: str) -> tuple[int, Path]:
    """A new file in ``folder``, open for writing, created with mode 0666 (less the umask)."""
    for _ in range(_TRIES):
        path = folder / f"{prefix}{secrets.token_hex(6)}.tmp"
        try:
            return os.open(path, _FLAGS, 0o666), path
        except FileExistsError:
            continue
    raise FileExistsError(f"{folder}: no free temporary name {prefix}*.tmp in {_TRIES} tries")


def _keep_mode(target: Path, tmp: Path) -> None:
    """Give ``tmp`` the mode of ``target``, when ``target`` exists."""
    try:
        mode = stat.S_IMODE(os.stat(target).st_mode)
    except FileNotFoundError:
        return
    os.chmod(tmp, mode)


__all__ = ["write_bytes_atomic", "write_text_atomic"]
