"""A Griffe extension: the reStructuredText bits of gaitpref's docstrings, as Markdown.

The docstrings are prose with Sphinx roles (``:class:`Session```), double-backtick literals, ``::``
before an indented example, and the occasional simple table (``errors.py``).  mkdocstrings reads
Markdown, so on load each docstring's roles become code spans, ``::`` a colon, and simple tables
Markdown tables.  Only the rendered text changes; the source stays as it is.
"""

from __future__ import annotations

import ast
import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|attr|data|obj|exc|const):`~?([^`]+)`")
_LITERAL = re.compile(r"``([^`]+)``")
_BORDER = re.compile(r"^=+(?: +=+)+\s*$")


def _columns(border: str) -> list[int]:
    return [m.start() for m in re.finditer(r"=+", border)]


def _rows(lines: list[str], starts: list[int]) -> list[list[str]]:
    rows: list[list[str]] = []
    for line in lines:
        bounds = [*starts[1:], None]
        cells = [line[a:b].strip() for a, b in zip(starts, bounds, strict=True)]
        if rows and not cells[0]:  # a continuation line of the row above
            rows[-1] = [f"{old} {new}".strip() for old, new in zip(rows[-1], cells, strict=True)]
        else:
            rows.append(cells)
    return rows


def simple_tables(text: str) -> str:
    """Turn reST simple tables (border, header, border, body, border) into Markdown tables."""
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        borders = [j for j in range(i, len(lines)) if _BORDER.match(lines[j])][:3]
        if len(borders) < 3 or borders[0] != i:
            out.append(lines[i])
            i += 1
            continue
        first, second, third = borders
        starts = _columns(lines[first])
        header = _rows(lines[first + 1 : second], starts)
        body = _rows(lines[second + 1 : third], starts)
        out.append("| " + " | ".join(" ".join(c) for c in zip(*header, strict=True)) + " |")
        out.append("|" + "---|" * len(starts))
        out.extend("| " + " | ".join(row) + " |" for row in body)
        i = third + 1
    return "\n".join(out)


def to_markdown(text: str) -> str:
    """A gaitpref docstring (reST-flavoured prose) as Markdown."""
    text = simple_tables(text)
    text = _ROLE.sub(r"`\1`", text)
    text = _LITERAL.sub(r"`\1`", text)
    return re.sub(r"::\n", ":\n", text)


class RestToMarkdown(griffe.Extension):
    """Rewrite every docstring with :func:`to_markdown` as Griffe loads it."""

    def on_instance(
        self, *, node: ast.AST | griffe.ObjectNode, obj: griffe.Object, **kwargs: Any
    ) -> None:
        if obj.docstring is not None:
            obj.docstring.value = to_markdown(obj.docstring.value)
