"""How much an ``.npz`` archive would unpack to, read from its headers before any array is.

A small compressed member can unpack to gigabytes (a "zip bomb"), and an ``.npy`` header may
claim a shape far larger than the member holds, which NumPy allocates whole before it fails.
:func:`npz_problem` reads only the zip directory and each member's ``.npy`` header (formats 1.0
and 2.0, what NumPy writes) and says what is wrong, so that a reader can refuse the file (a COT
curve, ``simulate/hzd.py``) or drop it (a cache, ``sessions/fit_cache.py``).
"""

from __future__ import annotations

import numpy as np


def npz_problem(data: np.lib.npyio.NpzFile, limit: int, what: str) -> str | None:
    """What keeps ``data`` (``what``, such as "a COT curve file") from being read within
    ``limit`` bytes unpacked, or None.

    Refused: a closed archive, members that unpack past ``limit`` in all, a member in an
    ``.npy`` format other than 1.0 or 2.0, and a member whose header claims more bytes
    (shape times item size) than it holds unpacked."""
    archive = data.zip
    if archive is None:
        return "the archive is closed"
    infos = archive.infolist()
    total = sum(info.file_size for info in infos)
    if total > limit:
        return f"its arrays unpack to {total:,} bytes, more than the {limit:,} {what} may"
    for info in infos:
        with archive.open(info) as member:
            version = np.lib.format.read_magic(member)
            if version == (1, 0):
                shape, _, dtype = np.lib.format.read_array_header_1_0(member)
            elif version == (2, 0):
                shape, _, dtype = np.lib.format.read_array_header_2_0(member)
            else:
                return f"{info.filename}: .npy format {version} is not read"
            if int(np.prod(shape, dtype=object)) * dtype.itemsize > info.file_size:
                return f"{info.filename}: its header claims shape {shape}, more than it holds"
    return None
