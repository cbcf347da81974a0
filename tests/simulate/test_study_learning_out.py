"""``benchmarks/study_learning.py report --out DIR``: a report made to try the command goes to
``DIR``, and the committed ``docs/results/learning/`` is left as it was (it was overwritten)."""

from __future__ import annotations

import hashlib
import importlib
import sys
from pathlib import Path
from typing import Any

import pytest


def _digests(folder: Path) -> dict[str, str]:
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def test_report_writes_into_out_and_leaves_the_committed_results(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    study: Any = importlib.import_module("benchmarks.study_learning")  # not followed by mypy
    monkeypatch.setattr(study, "CACHE", tmp_path / "cache")  # the runs' cache, not out/
    paper = next(a for a in study.ARMS if a.name == "paper")
    study.run([paper], ["noiseless"], objectives=2, jobs=1)  # two runs of 150 trials
    committed = _digests(study.RESULTS)
    assert "summary.md" in committed  # the folder the default writes into
    out = tmp_path / "trial" / "learning"  # made, parents and all
    monkeypatch.setattr(sys, "argv", ["study_learning.py", "report", "--out", str(out)])
    study.main()
    assert {"runs.csv", "curves.csv", "summary.md", "learning.png"} <= set(_digests(out))
    assert "## noiseless subject (2 objectives)" in (out / "summary.md").read_text()
    assert _digests(study.RESULTS) == committed
