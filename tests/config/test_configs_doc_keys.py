"""docs/configs.md documents every key the config parser accepts, and the docs name no other.

The keys are the schema's own declarations, not a list kept here: ``schema.TABLES`` maps every
table the parser checks to its declared :class:`~gaitpref.config.schema.Key` objects, one table
per strategy for ``[cospar.strategy_settings]`` and one ``space.<feature>`` table for every
``[space.F]``.  The parser rejects any key not declared there (``check_table``), and every
``check_table`` call in ``src/gaitpref`` passes one of those tables, or the per-feature keys of
``[model] lengthscale = {F = ...}`` and ``[model.prior] lengthscale`` (whose keys are the
space's features, not the schema's): both are checked below, so a table that the parser reads
but ``TABLES`` leaves out fails here too.

A key is documented when a TOML block of docs/configs.md shows it under its table (``key = ...``
or the example ``# key = ...``), when a block has the sub-table it names (``[model] prior``:
``[model.prior]``), or when the prose names it as ``[table] key`` / ``[table].key``.  A strategy
setting must also name the strategy beside it (its comment, or the comment it shares with the
key line just above it), so that a setting added to a strategy is not documented by another's.

Every TOML block of docs/*.md is a config snippet (``tests/test_doc_examples.py`` parses them as
written); here each example line, ``# key = value`` uncommented, must name a key its table
declares, and its value, where the line is TOML by itself, must pass that key's own check.  A
number a key's comment states as its default (``default 20``) or a range (``0..100``) must be
the declared default and bounds.
"""

from __future__ import annotations

import ast
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

import pytest

from gaitpref.config import schema
from gaitpref.config.schema import STRATEGY_TABLES, TABLES, Key
from gaitpref.config.specs import Integer, Number, Spec, Table
from gaitpref.errors import ConfigError
from gaitpref.strategies import STRATEGIES

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
CONFIGS = DOCS / "configs.md"
SETTINGS = "cospar.strategy_settings"
HEADER = re.compile(r"^\[([^\[\]]+)\]")
# `key = value` at the start of a line, or the example `# key = value` at column 0 (an indented
# `#` continues the comment of the key above it).
KEY_LINE = re.compile(r"^(#\s*)?([A-Za-z_]\w*)\s*=")


@dataclass(frozen=True)
class Line:
    """One key line of a TOML block: its table (the header above it; '' at the top)."""

    page: str
    table: str
    key: str
    text: str  # the line, uncommented when it was an example
    notes: str  # its comment and the comment lines that continue it
    shared: str  # the notes of the key line directly above it, if it has no comment lines


def blocks(page: Path) -> list[str]:
    return re.findall(r"```toml\n(.*?)```", page.read_text(encoding="utf-8"), re.S)


def key_lines(page: Path) -> list[Line]:
    out: list[Line] = []
    for block in blocks(page):
        table = ""
        last: Line | None = None  # the key line just above, while nothing came between
        lines = block.splitlines()
        for i, line in enumerate(lines):
            header = HEADER.match(line)
            if header:
                table, last = header.group(1).strip(), None
                continue
            match = KEY_LINE.match(line)
            if not match:
                if not line.strip():
                    last = None
                continue
            text = line[len(match.group(1)) :] if match.group(1) else line
            notes = [text.split("#", 1)[1] if "#" in text else ""]
            for more in lines[i + 1 :]:
                if HEADER.match(more) or KEY_LINE.match(more) or not more.strip().startswith("#"):
                    break
                notes.append(more.strip().lstrip("#"))
            shared = last.notes if last is not None else ""
            item = Line(page.name, table, match.group(2), text, " ".join(notes), shared)
            out.append(item)
            last = item if len(notes) == 1 else None
    return out


def prose(page: Path) -> str:
    """The page without its code blocks."""
    return re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)


def declared(header: str) -> dict[str, Key] | None:
    """The keys of the table a block's ``[header]`` opens (None: no such table)."""
    if header.startswith("space."):
        return TABLES["space.<feature>"]
    if header == SETTINGS:
        return {k: key for table in STRATEGY_TABLES.values() for k, key in table.items()}
    return TABLES.get(header)


def header_matches(table: str, header: str) -> bool:
    if table == "space.<feature>":
        return header.startswith("space.") and header.count(".") == 1
    if table.startswith(SETTINGS):
        return header == SETTINGS
    return header == table


def prose_names(table: str, key: str, text: str) -> bool:
    name = r"\[space\.\w+\]" if table == "space.<feature>" else re.escape(f"[{table}]")
    return re.search(rf"{name}(\.| ){re.escape(key)}\b", text) is not None


def labels(notes: str) -> set[str]:
    """The strategies a setting's comment labels it for: ``gated-eubo: ...``, ``eubo,
    confident-eubo: ...``, ``gated-eubo (default 1), plausible-eubo (default 3): ...`` (a name
    merely mentioned, as in "run self-sparring", is no label)."""
    name = "|".join(re.escape(s) for s in sorted(STRATEGIES, key=len, reverse=True))
    one = rf"(?<![\w-])({name})(?![\w-])(\s*\([^)]*\))?"
    found: set[str] = set()
    for run in re.finditer(rf"{one}(\s*(,|and)\s*{one})*\s*:", notes):
        found |= set(re.findall(rf"(?<![\w-])({name})(?![\w-])", run.group(0)))
    return found


def undocumented(page: Path = CONFIGS, tables: dict[str, dict[str, Key]] = TABLES) -> list[str]:
    """``[table] key`` for every key of ``tables`` that ``page`` does not document."""
    lines = key_lines(page)
    headers = {
        h.strip() for block in blocks(page) for h in re.findall(r"^\[([^\[\]]+)\]", block, re.M)
    }
    text = prose(page)
    missing = []
    for table, keys in tables.items():
        strategy = table[len(SETTINGS) + 2 : -1] if table.startswith(SETTINGS) else None
        for key, spec in keys.items():
            shown = [ln for ln in lines if ln.key == key and header_matches(table, ln.table)]
            if strategy is not None:
                # its own labels, or (none) the labels of the key line it shares a comment with
                shown = [ln for ln in shown if strategy in (labels(ln.notes) or labels(ln.shared))]
                ok = bool(shown)
            else:
                sub = "space" if table == "" and key == "space" else f"{table}.{key}".lstrip(".")
                has_table = isinstance(spec.spec, Table) and any(
                    h == sub or h.startswith(sub + ".") for h in headers
                )
                ok = bool(shown) or has_table or (bool(table) and prose_names(table, key, text))
            if not ok:
                missing.append(f"[{table}] {key}")
    return missing


def test_configs_md_documents_every_declared_key() -> None:
    assert undocumented() == []


def test_every_key_table_of_the_schema_is_in_tables() -> None:
    """A table declared in schema.py but left out of TABLES would escape the check above."""
    tables = [
        name
        for name, value in vars(schema).items()
        if isinstance(value, dict)
        and value
        and all(isinstance(k, str) and isinstance(v, Key) for k, v in value.items())
    ]
    listed = [id(t) for t in TABLES.values()]
    assert tables  # TOP, MODEL, ...
    assert [name for name in tables if id(getattr(schema, name)) not in listed] == []
    assert set(STRATEGY_TABLES) == set(STRATEGIES)


def test_the_parser_checks_only_the_schema_s_tables() -> None:
    """Every ``check_table(raw, table, keys)`` in src/gaitpref passes a table of ``TABLES`` (by
    name in schema.py), a strategy's table, or the per-feature ``keys`` of a lengthscale."""
    names = {n for n, v in vars(schema).items() if any(v is t for t in TABLES.values())}
    seen = []
    for path in sorted((ROOT / "src" / "gaitpref").rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if not (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Name)
                and node.func.id == "check_table"
            ):
                continue
            keys = node.args[2] if len(node.args) > 2 else None
            source = ast.unparse(keys) if keys is not None else "?"
            table = ast.unparse(node.args[1]) if len(node.args) > 1 else "?"
            seen.append((path.name, table, source))
    assert len(seen) >= 10
    odd = [
        s
        for s in seen
        if not (
            s[2] in names
            or s[2] == "STRATEGY_TABLES[name]"
            or (s[2] == "keys" and "lengthscale" in s[1])
        )
    ]
    assert odd == []


def doc_pages() -> list[Path]:
    return [page for page in sorted(DOCS.glob("*.md")) if blocks(page)]


def test_the_docs_have_config_blocks() -> None:
    assert {p.name for p in doc_pages()} >= {"configs.md", "gaits.md", "sessions.md"}
    assert len(key_lines(CONFIGS)) >= 60


@pytest.mark.parametrize("page", doc_pages(), ids=lambda p: p.name)
def test_every_key_the_docs_show_is_one_the_parser_accepts(page: Path) -> None:
    wrong, bad_values = [], []
    for line in key_lines(page):
        keys = declared(line.table)
        if keys is None or line.key not in keys:
            wrong.append(f"[{line.table}] {line.key}")
            continue
        try:
            value = tomllib.loads(line.text)[line.key]
        except tomllib.TOMLDecodeError as e:
            if "..." not in line.text.split("#", 1)[0]:  # `values = [0.08, 0.10, ...]` elides
                bad_values.append(f"[{line.table}] {line.key}: not TOML ({e}): {line.text}")
            continue
        try:
            keys[line.key].spec.check(value, line.table, line.key)
        except ConfigError as e:
            bad_values.append(str(e))
    assert wrong == []
    assert bad_values == []


@pytest.mark.parametrize(
    "table", ["", "space.<feature>", "model.prior", "cospar", f"{SETTINGS} (gated-eubo)"]
)
@pytest.mark.parametrize("spec", [Number(), Table("a table")], ids=["number", "table"])
def test_a_key_declared_without_docs_is_found(table: str, spec: Spec) -> None:
    probe = {**TABLES, table: {**TABLES[table], "undocumented_key": Key(spec, None)}}
    assert undocumented(tables=probe) == [f"[{table}] undocumented_key"]


def test_a_setting_documented_for_another_strategy_is_found() -> None:
    """``beta`` is documented for confident-eubo, below ``trials`` (eubo-then-sparring's):
    given to eubo or to eubo-then-sparring too, theirs is undocumented."""
    beta = STRATEGY_TABLES["confident-eubo"]["beta"]
    for strategy in ("eubo", "eubo-then-sparring"):
        table = f"{SETTINGS} ({strategy})"
        probe = {**TABLES, table: {**TABLES[table], "beta": beta}}
        assert undocumented(tables=probe) == [f"[{table}] beta"]


# A number as the docs write one: 0.05, 1e-12, 1e6, 1,000,000 (not 2 of 2**63, nor "64," whole).
NUMBER = r"-?\d(?:\d|,(?=\d{3}))*(?:\.\d+)?(?:e-?\d+)?(?![\d*])"


def stated(notes: str) -> tuple[list[float], list[tuple[float, float]]]:
    """The numeric defaults (``default 20``, ``default: 0.05``) and ranges (``0..100``) that a
    key's comment states."""

    def value(text: str) -> float:
        return float(text.replace(",", ""))

    defaults = [value(d) for d in re.findall(rf"default:?\s+({NUMBER})", notes)]
    ranges = re.findall(rf"({NUMBER})\s*\.\.\s*({NUMBER})", notes)
    return defaults, [(value(lo), value(hi)) for lo, hi in ranges]


@pytest.mark.parametrize("page", doc_pages(), ids=lambda p: p.name)
def test_the_numeric_defaults_and_ranges_the_docs_state_are_the_declared_ones(page: Path) -> None:
    """Where a key's comment states a number as its default, or a range ``lo..hi``, they are the
    key's declared default (a strategy setting's: one of its strategies') and bounds."""
    wrong, checked = [], 0
    for line in key_lines(page):
        tables = [t for n, t in TABLES.items() if n.startswith(SETTINGS)]
        if line.table == SETTINGS:
            keys = [t[line.key] for t in tables if line.key in t]
        else:
            keys = [(declared(line.table) or {})[line.key]]
        defaults, ranges = stated(line.notes)
        numbers = [k.default for k in keys if type(k.default) in (int, float)]
        for default in defaults if numbers else []:
            checked += 1
            if default not in numbers:
                wrong.append(f"[{line.table}] {line.key}: default {default:g}, declared {numbers}")
        for lo, hi in ranges:
            checked += 1
            spec = keys[0].spec
            if not isinstance(spec, Integer | Number) or (lo, hi) != (spec.lo, spec.hi):
                wrong.append(f"[{line.table}] {line.key}: {lo:g}..{hi:g}, declared {spec}")
    assert wrong == []
    assert checked >= 30 or page.name != "configs.md"
