"""The README's Python examples run as written, one after the other (a new user pastes them)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def printed_as_documented(blocks: list[str], out: str) -> None:
    """What the blocks print is what their ``print(...)  # "..."`` comments say, in order."""
    said = [m for b in blocks for m in re.findall(r'^print\(.*#\s*"([^"]*)"', b, re.M)]
    assert said, "no documented print"
    assert out.splitlines() == said


def test_readme_python_blocks_run(capsys: pytest.CaptureFixture[str]) -> None:
    text = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) >= 2
    scope: dict[str, object] = {}
    for block in blocks:
        exec(compile(block, "README.md", "exec"), scope)
    posterior = scope["posterior"]
    assert posterior.mean.shape == (15,)  # type: ignore[attr-defined]
    printed_as_documented(blocks, capsys.readouterr().out)
