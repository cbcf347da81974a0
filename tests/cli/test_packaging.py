"""The console is an extra: the core install declares no web framework and imports none."""

from __future__ import annotations

import ast
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
WEB = {"fastapi", "starlette", "uvicorn", "jinja2", "multipart", "python_multipart"}
WEB_DISTRIBUTIONS = {"fastapi", "starlette", "uvicorn", "jinja2", "python-multipart"}


def _names(requirements: list[str]) -> set[str]:
    out = set()
    for req in requirements:
        name = req.split(";")[0]
        for sep in "<>=![ ":
            name = name.split(sep)[0]
        out.add(name.strip().lower())
    return out


def test_web_dependencies_are_the_console_extra() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    core = _names(project["dependencies"])
    extras = project["optional-dependencies"]
    assert core & WEB_DISTRIBUTIONS == set()
    assert {"pydantic", "typer", "rich", "sqlalchemy"} <= core  # the config schema needs pydantic
    assert _names(extras["console"]) == WEB_DISTRIBUTIONS
    assert "gaitpref[console]" in extras["dev"]


def _top_level_web_imports(path: Path) -> list[str]:
    """Web modules imported at module level (not inside a function or TYPE_CHECKING)."""
    tree = ast.parse(path.read_text(), str(path))
    found = []
    for node in tree.body:
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module]
        found += [n for n in names if n.split(".")[0] in WEB]
    return found


def test_only_the_console_package_imports_the_web_stack() -> None:
    src = ROOT / "src" / "gaitpref"
    offenders = {
        str(p.relative_to(src)): hits
        for p in sorted(src.rglob("*.py"))
        if "console" not in p.relative_to(src).parts[:1] and (hits := _top_level_web_imports(p))
    }
    assert offenders == {}
    # the scan does see the console's own imports
    assert _top_level_web_imports(src / "console" / "app.py")
