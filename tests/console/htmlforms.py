"""A small reader of the console's HTML forms for TestClient tests (no browser)."""

from __future__ import annotations

from dataclasses import dataclass, field
from html.parser import HTMLParser


@dataclass
class Form:
    action: str
    fields: dict[str, str] = field(default_factory=dict)  # hidden/text inputs, checked radios
    radios: dict[str, list[str]] = field(default_factory=dict)  # radio name -> values
    selects: dict[str, list[str]] = field(default_factory=dict)


class _Reader(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.forms: dict[str, Form] = {}
        self._current: Form | None = None
        self._select: str | None = None
        self._count = 0

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = {k: v or "" for k, v in attrs}
        if tag == "form":
            self._count += 1
            self._current = Form(a.get("action", ""))
            self.forms[a.get("id") or f"form{self._count}"] = self._current
        elif self._current is None:
            return
        elif tag == "input" and "name" in a:
            if a.get("type") == "radio":
                self._current.radios.setdefault(a["name"], []).append(a.get("value", ""))
                if "checked" in a:
                    self._current.fields[a["name"]] = a.get("value", "")
            elif a.get("type") != "file":
                self._current.fields[a["name"]] = a.get("value", "")
        elif tag == "select":
            self._select = a.get("name")
            if self._select:
                self._current.selects[self._select] = []
        elif tag == "option" and self._select:
            self._current.selects[self._select].append(a.get("value", ""))

    def handle_endtag(self, tag: str) -> None:
        if tag == "form":
            self._current = None
        elif tag == "select":
            self._select = None


def forms_of(html: str) -> dict[str, Form]:
    """The page's forms by id (``formN`` for forms without an id, in page order)."""
    reader = _Reader()
    reader.feed(html)
    return reader.forms
