"""The ``>>>`` examples in gaitpref's docstrings run as written (they render in the API reference).

Every module under ``src/gaitpref`` whose source holds a ``>>>`` line is imported and its doctests
run, so an example that drifts from the code fails here.
"""

from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parent.parent / "src"


def modules_with_examples() -> list[str]:
    return sorted(
        ".".join(path.relative_to(SRC).with_suffix("").parts).removesuffix(".__init__")
        for path in (SRC / "gaitpref").rglob("*.py")
        if ">>> " in path.read_text(encoding="utf-8")
    )


def test_some_docstring_has_an_example() -> None:
    assert "gaitpref.model.gp" in modules_with_examples()


@pytest.mark.parametrize("name", modules_with_examples())
def test_docstring_examples_run(name: str) -> None:
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE, verbose=False)
    assert result.attempted > 0, f"{name} has a '>>> ' line but no doctest was found"
    assert result.failed == 0, f"{result.failed} docstring example(s) of {name} failed (above)"
