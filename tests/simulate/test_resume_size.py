"""A resumed sweep reads its partial file whole, so a file past ``MAX_PARTIAL_BYTES`` is
refused naming the file and its size, and is neither read nor changed."""

from __future__ import annotations

from pathlib import Path

import pytest

import gaitpref.simulate.resume as resume
from gaitpref.limits import MAX_PARTIAL_BYTES, MAX_STUDY_TRIALS
from gaitpref.simulate import ResumeError
from gaitpref.simulate.resume import partial_bytes
from gaitpref.simulate.resume_lines import read_lines


def test_the_bound_holds_the_largest_study_table() -> None:
    assert MAX_PARTIAL_BYTES >= MAX_STUDY_TRIALS * 100  # about 100 bytes a row


def test_a_partial_file_within_the_bound_is_read(tmp_path: Path) -> None:
    path = tmp_path / "runs.partial.csv"
    path.write_bytes(b"setting,objective\n")
    assert partial_bytes(path) == b"setting,objective\n"


def test_a_partial_file_past_the_bound_is_refused_unread(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(resume, "MAX_PARTIAL_BYTES", 16)
    path = tmp_path / "bench.jsonl"
    text = '{"gaitpref bench": {}}\n{"seed": 0}\n'
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ResumeError, match=r"bench\.jsonl: 35 bytes, more than the 16 a resumed"):
        read_lines(path, {})
    assert path.read_text(encoding="utf-8") == text
