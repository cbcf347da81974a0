"""``npz_problem``: an archive is judged from its zip directory and ``.npy`` headers alone."""

from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np

from gaitpref.npz_sizes import npz_problem


def test_a_plain_archive_within_the_limit_passes(tmp_path: Path) -> None:
    path = tmp_path / "ok.npz"
    np.savez(path, a=np.arange(10.0), b=np.zeros((3, 4)))
    with np.load(path) as data:
        assert npz_problem(data, 10_000, "a test file") is None
        total = sum(info.file_size for info in data.zip.infolist())
        assert npz_problem(data, 100, "a test file") == (
            f"its arrays unpack to {total:,} bytes, more than the 100 a test file may"
        )


def test_a_compressed_bomb_is_refused_by_its_unpacked_size(tmp_path: Path) -> None:
    path = tmp_path / "bomb.npz"
    np.savez_compressed(path, a=np.zeros(2_000_000))  # 16 MB of zeros, a few kB on disk
    assert path.stat().st_size < 100_000
    with np.load(path) as data:
        problem = npz_problem(data, 1_000_000, "a test file")
    assert problem is not None and "unpack to 16,000," in problem


def _member(header_shape: tuple[int, ...], payload: bytes) -> bytes:
    buffer = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        buffer, {"descr": "<f8", "fortran_order": False, "shape": header_shape}
    )
    return buffer.getvalue() + payload  # the header writer writes the magic too


def test_a_header_claiming_more_than_its_member_holds_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "liar.npz"
    with zipfile.ZipFile(path, "w") as archive:  # claims 10^9 doubles, holds 8 bytes
        archive.writestr("a.npy", _member((10**9,), b"\x00" * 8))
    with np.load(path) as data:
        problem = npz_problem(data, 10**12, "a test file")
    assert problem == "a.npy: its header claims shape (1000000000,), more than it holds"


def test_a_closed_archive_is_named(tmp_path: Path) -> None:
    path = tmp_path / "ok.npz"
    np.savez(path, a=np.arange(3.0))
    data = np.load(path)
    data.close()
    assert npz_problem(data, 10_000, "a test file") == "the archive is closed"
