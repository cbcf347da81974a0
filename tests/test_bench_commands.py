"""Every command line the docs quote to re-run a study or a benchmark names what exists.

The command lines under ``docs/results/``, ``benchmarks/results/``, ``docs/learning.md``,
``docs/sweeps.md`` and the README, and the usage lines of each ``benchmarks/*.py`` docstring:
a ``python benchmarks/X.py ...`` names an existing script and only options its ``--help`` lists
(in process, ``--help`` exits before any work); a ``gaitpref bench|simulate ...`` names an
existing command and only options it accepts.  A script without ``argparse`` takes no options.
"""

from __future__ import annotations

import ast
import contextlib
import io
import re
import runpy
import sys
from functools import cache
from pathlib import Path

import pytest
import typer.main

from gaitpref.cli.main import app

ROOT = Path(__file__).resolve().parent.parent
BENCHMARKS = ROOT / "benchmarks"

SCRIPT = re.compile(r"python[0-9.]* benchmarks/(\w+\.py)((?:(?!python)[^\n`#|&;(])*)")
GAITPREF = re.compile(r"gaitpref (bench|simulate)( [^\n`#|&;(]*)")
OPTION = re.compile(r"(?<![\w-])--[a-z][\w-]*")


def quoted_texts() -> list[tuple[str, str]]:
    """(where, text) of every document and docstring that quotes command lines."""
    docs = sorted((ROOT / "docs" / "results").rglob("*.md"))
    docs += [ROOT / "docs" / "learning.md", ROOT / "docs" / "sweeps.md", ROOT / "README.md"]
    docs += sorted((BENCHMARKS / "results").glob("*.md"))
    texts = [(str(p.relative_to(ROOT)), joined_spans(p.read_text(encoding="utf-8"))) for p in docs]
    for p in sorted(BENCHMARKS.glob("*.py")):
        doc = ast.get_docstring(ast.parse(p.read_text(encoding="utf-8"))) or ""
        texts.append((str(p.relative_to(ROOT)), doc))
    # a line ending in a backslash goes on on the next one
    return [(where, re.sub(r"\\\n\s*", " ", text)) for where, text in texts]


def joined_spans(markdown: str) -> str:
    """``markdown`` with each inline code span that wraps (outside fenced blocks) on one line."""
    parts = re.split(r"(```.*?```)", markdown, flags=re.S)
    for i in range(0, len(parts), 2):
        parts[i] = re.sub(r"`[^`]+`", lambda m: m.group(0).replace("\n", " "), parts[i])
    return "".join(parts)


def script_lines() -> list[tuple[str, str, str]]:
    return [
        (where, m.group(1), m.group(2))
        for where, text in quoted_texts()
        for m in SCRIPT.finditer(text)
    ]


def gaitpref_lines() -> list[tuple[str, str, str]]:
    return [
        (where, m.group(1), m.group(2))
        for where, text in quoted_texts()
        for m in GAITPREF.finditer(text)
    ]


@cache
def script_options(script: str, subcommand: str | None) -> frozenset[str]:
    """The options ``benchmarks/SCRIPT [SUBCOMMAND] --help`` lists (none without argparse)."""
    path = BENCHMARKS / script
    if "argparse" not in path.read_text(encoding="utf-8"):
        return frozenset()
    argv = [str(path), *([subcommand] if subcommand else []), "--help"]
    out = io.StringIO()
    saved_argv, saved_path = sys.argv, list(sys.path)
    sys.argv, sys.path = argv, [str(BENCHMARKS), *sys.path]
    try:
        with contextlib.redirect_stdout(out), pytest.raises(SystemExit) as stop:
            runpy.run_path(str(path), run_name="__main__")
    finally:
        sys.argv, sys.path = saved_argv, saved_path
    assert stop.value.code in (0, None), f"{' '.join(argv)} failed"
    return frozenset(OPTION.findall(out.getvalue()))


def test_the_docs_quote_command_lines() -> None:
    assert len(script_lines()) > 50
    assert len(gaitpref_lines()) > 10


@pytest.mark.parametrize(("where", "script", "rest"), script_lines())
def test_a_quoted_benchmark_script_takes_the_options_given(
    where: str, script: str, rest: str
) -> None:
    assert (BENCHMARKS / script).is_file(), f"{where}: no benchmarks/{script}"
    words = rest.split()
    subcommand = None
    if (
        words
        and re.fullmatch(r"[a-z][a-z-]*", words[0])
        and "add_subparsers" in (BENCHMARKS / script).read_text(encoding="utf-8")
    ):
        subcommand = words[0]
    accepted = script_options(script, subcommand)
    for option in OPTION.findall(rest):
        assert option in accepted, f"{where}: benchmarks/{script} takes no {option}"


def gaitpref_options(command: str, rest: str) -> frozenset[str] | None:
    """The options of ``gaitpref bench NAME`` or ``gaitpref simulate``; None for ``bench ...``."""
    root = typer.main.get_command(app)
    group = root.commands[command]  # type: ignore[attr-defined]
    if command == "bench":
        names = [w for w in re.split(r"[\s|\[\]]+", rest) if w and not w.startswith("-")]
        if not names or names[0] == "...":
            return None
        for name in names[0].split("|"):
            assert name in group.commands, f"no gaitpref bench {name}"
        group = group.commands[names[0].split("|")[0]]
    return frozenset(o for p in group.params for o in [*p.opts, *p.secondary_opts])


@pytest.mark.parametrize(("where", "command", "rest"), gaitpref_lines())
def test_a_quoted_gaitpref_command_takes_the_options_given(
    where: str, command: str, rest: str
) -> None:
    accepted = gaitpref_options(command, rest)
    if accepted is None:
        return
    for option in OPTION.findall(rest):
        assert option in accepted, (
            f"{where}: gaitpref {command} {rest.split()[:1]} takes no {option}"
        )
