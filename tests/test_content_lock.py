"""The content lock is held across processes, per key, and leaves its lock file in place."""

from __future__ import annotations

import fcntl
import os
import subprocess
import sys
from pathlib import Path

from gaitpref.content_lock import content_lock, lock_path

HOLD = """
import sys
from pathlib import Path
from gaitpref.content_lock import content_lock
with content_lock(Path(sys.argv[1]), "abc"):
    print("held", flush=True)
    sys.stdin.readline()
"""


def _free(path: Path) -> bool:
    fd = os.open(path, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    finally:
        os.close(fd)
    return True


def test_another_process_holding_the_lock_blocks_this_one_for_that_key_only(
    tmp_path: Path,
) -> None:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(tmp_path)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    assert holder.stdout is not None and holder.stdin is not None
    try:
        assert holder.stdout.readline() == "held\n"
        assert not _free(lock_path(tmp_path, "abc"))
        with content_lock(tmp_path, "other"):  # another key: not waited for
            pass
    finally:
        holder.stdin.write("\n")
        holder.stdin.close()
        assert holder.wait(60) == 0
    assert _free(lock_path(tmp_path, "abc"))  # released when the holder left the block
    with content_lock(tmp_path, "abc"):
        assert not _free(lock_path(tmp_path, "abc"))
    assert sorted(p.name for p in tmp_path.iterdir()) == [".abc.lock", ".other.lock"]
