"""A session's remembered Laplace modes on disk, beside a SQLite database (a cache).

``<file>.fits/<session id>.npz`` (:meth:`~gaitpref.storage.Storage.folder_beside`): the
:class:`~gaitpref.model.fit_memo.FitMemo` that makes rebuilding a large warm-started session
from its log check each fit at its mode instead of making it again (``model/fit_memo.py``; the
same numbers, to the bit).  Never data: a missing, damaged or foreign file is ignored (an empty
memo), one that cannot be written is not written, and deleting the folder costs time only.  A
database that is not a local file (memory, PostgreSQL) keeps the memo in the process only.
"""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np

from gaitpref.atomic import write_bytes_atomic
from gaitpref.model.fit_memo import MAX_ENTRIES, FitMemo, Remembered
from gaitpref.npz_sizes import npz_problem
from gaitpref.storage import Storage

#: the folder beside a SQLite database: ``lab.db.fits/<session id>.npz``
FITS_SUFFIX = ".fits"
#: A memo file larger than this is not read (the session is rebuilt without it).
MAX_FILE_BYTES = 256 * 2**20


def memo_path(storage: Storage, session_id: int) -> Path | None:
    """Where ``session_id``'s memo is kept; None for a database that is not a local file."""
    folder = storage.folder_beside(FITS_SUFFIX)
    return None if folder is None else folder / f"{session_id}.npz"


def load_memo(path: Path) -> FitMemo:
    """The memo saved at ``path``; an empty one if there is none, or it is too large, damaged
    or not one (a cache: never an error)."""
    memo = FitMemo()
    try:
        if not path.is_file() or path.stat().st_size > MAX_FILE_BYTES:
            return memo
        with np.load(path, allow_pickle=False) as data:
            if npz_problem(data, MAX_FILE_BYTES, "a fit cache") is not None:
                return memo
            keys, norms = data["keys"], data["norms"]
            offsets, modes = data["offsets"], data["modes"]
            n = keys.shape[0]
            valid = (
                keys.dtype == np.uint8 and keys.shape == (n, 32) and norms.shape == (n,)
                and offsets.shape == (n + 1,) and modes.ndim == 1 and n <= MAX_ENTRIES
                and modes.dtype == np.float64 and norms.dtype == np.float64
                and offsets.dtype.kind == "i" and n >= 0 and offsets[0] == 0
                and bool(np.all(np.diff(offsets) >= 0)) and offsets[-1] == modes.shape[0]
                and bool(np.all(np.isfinite(modes))) and bool(np.all(np.isfinite(norms)))
            )  # fmt: skip
            if not valid:
                return memo
            for k in range(n):
                mode = modes[offsets[k] : offsets[k + 1]].copy()
                memo.put(keys[k].tobytes(), Remembered(mode, float(norms[k])))
    except Exception:  # damaged, truncated, not an npz: a cache, rebuilt without it
        return FitMemo()
    memo.dirty = False
    return memo


def save_memo(memo: FitMemo, path: Path) -> None:
    """Write ``memo`` to ``path`` atomically (a temporary file renamed into place); a folder
    that cannot be written leaves the memo unsaved, silently: it is a cache."""
    items = memo.items()
    keys = np.array([np.frombuffer(k, dtype=np.uint8) for k, _ in items], dtype=np.uint8)
    buffer = io.BytesIO()
    np.savez(
        buffer,
        keys=keys.reshape(len(items), 32),
        norms=np.array([e.gradient_norm for _, e in items], dtype=np.float64),
        offsets=np.cumsum([0, *(e.mode.shape[0] for _, e in items)]).astype(np.int64),
        modes=np.concatenate([e.mode for _, e in items]) if items else np.zeros(0),
    )
    with contextlib.suppress(OSError):
        path.parent.mkdir(parents=True, exist_ok=True)
        write_bytes_atomic(path, buffer.getvalue(), prefix=f".{path.stem}.")
        memo.dirty = False


__all__ = ["FITS_SUFFIX", "MAX_FILE_BYTES", "load_memo", "memo_path", "save_memo"]
