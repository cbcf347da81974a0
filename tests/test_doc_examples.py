"""The docs' Python examples run and their TOML snippets parse, as a new user would paste them.

The README's Python blocks are ``tests/test_readme.py``.  Here: the Python blocks of
``docs/getting-started.md`` one after the other, the Session API example of ``docs/sessions.md``
(in a temporary folder), and every TOML block of ``docs/*.md``, each completed into a config by
the tables of the shipped ``exo-1d-step-length`` that it does not define itself.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

import gaitpref
from gaitpref.config import check_ignored, parse_config
from tests.test_readme import printed_as_documented

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
HEADER = re.compile(r"^\[([^\]]+)\]")


def blocks(page: Path, lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", page.read_text(encoding="utf-8"), re.S)


def test_getting_started_python_blocks_run(capsys: pytest.CaptureFixture[str]) -> None:
    scope: dict[str, object] = {}
    found = blocks(DOCS / "getting-started.md", "python")
    assert len(found) >= 2
    for block in found:
        exec(compile(block, "getting-started.md", "exec"), scope)
    posterior = scope["posterior"]
    assert isinstance(posterior, gaitpref.Posterior)
    assert posterior.mean.shape == (15,)
    printed_as_documented(found, capsys.readouterr().out)  # it said "0.1371 m", printed 0.13


def test_session_api_example_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # the example writes sqlite:///lab.db in the working directory
    block = next(b for b in blocks(DOCS / "sessions.md", "python") if "Session.create" in b)
    scope: dict[str, object] = {}
    exec(compile(block, "sessions.md", "exec"), scope)
    session = scope["s"]
    assert isinstance(session, gaitpref.Session)
    with session:
        assert (session.id, session.subject, session.seed) == (1, "S01", 0)
    assert (tmp_path / "lab.db").is_file()


def tables(text: str) -> list[tuple[str, str]]:
    """``(root table, text)`` of each table of a TOML text; top-level keys have the root ''."""
    out: list[tuple[str, list[str]]] = [("", [])]
    for line in text.splitlines():
        header = HEADER.match(line)
        if header:
            out.append((header.group(1).split(".")[0].strip(), []))
        out[-1][1].append(line)
    return [(root, "\n".join(lines)) for root, lines in out]


def completed(snippet: str) -> str:
    """The snippet with the shipped exo-1d-step-length's tables whose roots it does not define."""
    defined = {root for root, _ in tables(snippet) if root}
    base = gaitpref.load_config("exo-1d-step-length").text
    kept = [text for root, text in tables(base) if root and root not in defined]
    return "\n".join([snippet, *kept]) + "\n"


def toml_blocks() -> list[tuple[str, int, str]]:
    """Every TOML block of the docs but those naming a gait library file (tests/gaits cover
    configs over a library): a skip would fail CI=true, and they cannot parse without one."""
    return [
        (page.name, i, block)
        for page in sorted(DOCS.glob("*.md"))
        for i, block in enumerate(blocks(page, "toml"))
        if not re.search(r"^library\s*=", block, re.M)
    ]


def test_the_docs_have_toml_snippets() -> None:
    assert len(toml_blocks()) >= 8


@pytest.mark.parametrize(
    ("page", "index", "snippet"), toml_blocks(), ids=[f"{p}-{i}" for p, i, _ in toml_blocks()]
)
def test_toml_snippet_parses(page: str, index: int, snippet: str) -> None:
    config = parse_config(completed(snippet), default_name=f"{page}-{index}")
    assert config.space.describe(0)
    check_ignored(config)  # a new session takes it: no key it gives is ignored


BENCHES = ("paper-2d", "compass-gait", "population", "continuous")


def documented_usage(command: str) -> set[str]:
    """The options of ``gaitpref bench COMMAND`` in docs/sweeps.md's usage blocks and examples:
    the lines that begin with it (in code blocks only) and the indented lines that continue
    them."""
    found: set[str] = set()
    lines = (DOCS / "sweeps.md").read_text(encoding="utf-8").splitlines()
    for i, line in enumerate(lines):
        if line.startswith(f"gaitpref bench {command} "):
            rest = [line]
            for more in lines[i + 1 :]:
                if not more.startswith(" "):
                    break
                rest.append(more)
            found |= set(re.findall(r"--[a-z][a-z0-9-]*", "\n".join(rest)))
    return found


@pytest.mark.parametrize("command", BENCHES)
def test_the_bench_usage_in_sweeps_md_names_every_option(command: str) -> None:
    """The usage blocks left out --seed, --table, --address and --no-baseline of some benches:
    each option is documented by one of its names, and nothing documented is not an option."""
    import typer.main

    from gaitpref.cli.main import app

    group: Any = typer.main.get_command(app)  # typer's own click: no click.Group to check
    options = [
        {o for o in (*p.opts, *p.secondary_opts) if o.startswith("--")}
        for p in group.commands["bench"].commands[command].params
        if p.param_type_name == "option" and p.name != "help"
    ]
    documented = documented_usage(command)
    assert documented, command
    assert [sorted(o) for o in options if not o & documented] == []
    assert documented <= set().union(*options)
