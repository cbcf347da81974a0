"""The Python API table of ``docs/sessions.md`` matches ``gaitpref.Session``, so they cannot drift.

Each backticked ``name(args) -> ret`` of the table's member column is held to
``inspect.signature``: the same parameters in the same order, the same keyword-only marker
(``*``), the same defaults and, where the table gives one, the same return annotation.  A bare
``name`` (or ``name -> ret``) must be a property (with that return annotation) or an attribute
``__init__`` sets.  The Session.create example names every parameter of ``Session.create``.
"""

from __future__ import annotations

import ast
import dataclasses
import inspect
import re
from pathlib import Path
from typing import Any

import pytest

from gaitpref import Session

ROOT = Path(__file__).resolve().parent.parent
SESSIONS = ROOT / "docs" / "sessions.md"
MEMBER = re.compile(r"^(?:Session\.)?(\w+)(?:\((.*?)\))?(?:\s*->\s*(.+))?$")


def api_section() -> str:
    return SESSIONS.read_text(encoding="utf-8").split("## The Python API", 1)[1].split("\n## ")[0]


def members() -> list[str]:
    """The backticked items of the member column of the Python API table."""
    rows = [line for line in api_section().splitlines() if line.startswith("| `")]
    assert len(rows) > 20, "the Python API table of docs/sessions.md was not found"
    return [code for row in rows for code in re.findall(r"`([^`]+)`", row.split(" | ")[0])]


def normal(annotation: str) -> str:
    """A return type as the table writes it, as the code spells it: ``\\|`` is ``|`` and
    ``list[(A, B)]`` is ``list[tuple[A, B]]``."""
    text = annotation.replace("\\|", "|").strip()
    return re.sub(r"\(([^()]*)\)", r"tuple[\1]", text)


def documented_params(args: str) -> list[tuple[str, bool, Any]]:
    """``(name, keyword_only, default)`` of the table's ``args`` (``...`` for no default)."""
    out: list[tuple[str, bool, Any]] = []
    keyword_only = False
    for part in (a.strip() for a in args.split(",") if a.strip()):
        if part == "*":
            keyword_only = True
            continue
        name, _, default = part.partition("=")
        out.append((name.strip(), keyword_only, ast.literal_eval(default) if default else ...))
    return out


def code_params(fn: Any) -> list[tuple[str, bool, Any]]:
    params = [p for p in inspect.signature(fn).parameters.values() if p.name not in ("self", "cls")]
    return [
        (
            p.name,
            p.kind is inspect.Parameter.KEYWORD_ONLY,
            ... if p.default is inspect.Parameter.empty else p.default,
        )
        for p in params
    ]


def init_attributes() -> set[str]:
    source = inspect.getsource(Session.__init__)
    return set(re.findall(r"self\.(\w+)\s*[:=]", source))


@pytest.mark.parametrize("item", members())
def test_sessions_table_matches_the_code(item: str) -> None:
    match = MEMBER.match(item.strip())
    assert match, f"docs/sessions.md: cannot read {item!r} as name(args) -> ret"
    name, args, ret = match.groups()
    attr = inspect.getattr_static(Session, name, None)
    if args is None:
        if isinstance(attr, property):
            if ret is not None:
                assert normal(ret) == attr.fget.__annotations__["return"], item
            return
        assert attr is None and ret is None, f"{item}: documented as an attribute"
        assert name in init_attributes(), f"Session has no attribute {name!r} ({item})"
        return
    assert callable(getattr(Session, name, None)), f"Session has no method {name!r} ({item})"
    fn = getattr(Session, name)
    assert documented_params(args) == code_params(fn), (
        f"docs/sessions.md says {item}, the code has {name}{inspect.signature(fn)}"
    )
    if ret is not None:
        assert normal(ret) in (fn.__annotations__["return"], "T"), (
            f"docs/sessions.md says {item}, the code returns {fn.__annotations__['return']}"
        )


def test_create_example_names_every_parameter() -> None:
    block = re.search(r"```python\n(.*?)```", api_section(), re.S)
    assert block and "Session.create(" in block.group(1)
    call = next(
        node
        for node in ast.walk(ast.parse(block.group(1)))
        if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "create"
    )
    named = ["db", "config"][: len(call.args)] + [k.arg for k in call.keywords]
    assert named == [p for p, _, _ in code_params(Session.create)]


def test_records_fields_match_the_code() -> None:
    """``SessionQuery(...)`` and the fields of ``Answered`` and ``ShownGait`` as the table says."""
    from gaitpref.sessions import Answered, SessionQuery, ShownGait

    section = api_section()
    query = re.search(r"`SessionQuery\(([^)]*)\)`", section)
    assert query, "docs/sessions.md no longer spells SessionQuery(...)"
    assert [a.strip() for a in query.group(1).split(",")] == [
        f.name for f in dataclasses.fields(SessionQuery)
    ]
    answered = re.search(r"`Answered` has (.*?) \|", section)
    assert answered
    assert set(re.findall(r"`(\w+)`", answered.group(1))) == {
        f.name for f in dataclasses.fields(Answered)
    }
    shown = re.search(r"as the round showed them \((.*?)\) \|", section)
    assert shown
    assert set(re.findall(r"`(\w+)`", shown.group(1))) == {
        f.name for f in dataclasses.fields(ShownGait)
    }


def test_every_public_member_of_session_is_in_the_table() -> None:
    documented = {MEMBER.match(item.strip()).group(1) for item in members()}  # type: ignore[union-attr]
    documented |= {"create", "open"}  # the example above the table
    public = [name for name in vars(Session) if not name.startswith("_")]
    assert [name for name in public if name not in documented] == []
