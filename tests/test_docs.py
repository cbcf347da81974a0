"""The documentation site builds in strict mode, and every relative link in the docs resolves.

``mkdocs build --strict`` (``mkdocs.yml``) fails on a broken link, a missing page, an unresolved
cross-reference or a docstring mkdocstrings cannot render, so building the site here makes a broken
doc fail ``make test``.  Without MkDocs (the ``dev`` extra) the build tests skip with a message;
under ``CI=true`` that skip is a failure, as ``tests/ci_rule.py`` does for PostgreSQL and Chromium.
"""

from __future__ import annotations

import html
import importlib
import importlib.util
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
FENCE = re.compile(r"^(```|~~~).*?^\1", re.MULTILINE | re.DOTALL)


def require_mkdocs() -> None:
    """Skip without MkDocs and its plugins; under ``CI=true`` fail instead (CI installs them)."""
    missing = [
        m for m in ("mkdocs", "material", "mkdocstrings") if importlib.util.find_spec(m) is None
    ]
    if not missing:
        return
    message = f"{', '.join(missing)} not installed: pip install -e '.[dev]' (or make venv)"
    if os.environ.get("CI", "").lower() == "true":
        pytest.fail(f"CI=true builds the docs, but {message}")
    pytest.skip(message)


def build(config_dir: Path, site: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "PYTHONPATH": str(ROOT / "src")}
    return subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)],
        cwd=config_dir,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    require_mkdocs()
    out = tmp_path_factory.mktemp("site")
    result = build(ROOT, out)
    assert result.returncode == 0, f"mkdocs build --strict failed:\n{result.stdout}{result.stderr}"
    return out


def page(site: Path, uri: str) -> str:
    path = site / uri / "index.html"
    assert path.is_file(), f"the site has no page {uri}/"
    return path.read_text(encoding="utf-8")


@pytest.mark.parametrize(
    ("uri", "anchor"),
    [
        ("reference/gaitpref", "gaitpref.CoSpar"),
        ("reference/gaitpref", "gaitpref.Session"),
        ("reference/sessions", "gaitpref.sessions.Session"),
        ("reference/feedback", "gaitpref.feedback"),
        ("reference/loop", "gaitpref.loop.CoSpar"),
        ("reference/config", "gaitpref.config.load_config"),
        ("reference/storage", "gaitpref.storage.Storage"),
        ("reference/model", "gaitpref.model.Posterior"),
        ("reference/strategies", "gaitpref.strategies.make_strategy"),
        ("reference/errors", "gaitpref.errors.GaitprefError"),
    ],
)
def test_api_reference_documents_the_public_surface(site: Path, uri: str, anchor: str) -> None:
    assert f'id="{anchor}"' in page(site, uri)


#: each package whose ``__all__`` is the public API, and its reference page
REFERENCE_PAGES = {
    "gaitpref": "reference/gaitpref",
    "gaitpref.config": "reference/config",
    "gaitpref.errors": "reference/errors",
    "gaitpref.feedback": "reference/feedback",
    "gaitpref.gaits": "reference/gaits",
    "gaitpref.loop": "reference/loop",
    "gaitpref.model": "reference/model",
    "gaitpref.sessions": "reference/sessions",
    "gaitpref.simulate": "reference/simulate",
    "gaitpref.storage": "reference/storage",
    "gaitpref.strategies": "reference/strategies",
}


@pytest.mark.parametrize("package", sorted(REFERENCE_PAGES))
def test_every_public_name_is_on_its_reference_page(site: Path, package: str) -> None:
    """Every name of the package's ``__all__`` (dunders aside) imports and has its anchor."""
    module = importlib.import_module(package)
    names = [n for n in module.__all__ if not n.startswith("__")]
    assert all(hasattr(module, n) for n in names), [n for n in names if not hasattr(module, n)]
    text = page(site, REFERENCE_PAGES[package])
    missing = [n for n in names if f'id="{package}.{n}"' not in text]
    assert not missing, f"{REFERENCE_PAGES[package]} does not document {missing}"


def test_storage_reference_has_the_contract_suite_when_it_exists(site: Path) -> None:
    storage = ROOT / "src" / "gaitpref" / "storage"
    exists = (storage / "testing.py").exists() or (storage / "testing").is_dir()
    assert ('id="gaitpref.storage.testing"' in page(site, "reference/storage")) == exists


def test_docstrings_render_as_markdown(site: Path) -> None:
    errors = page(site, "reference/errors")
    assert "<table>" in errors  # the reST table of error families
    assert ":class:`" not in errors
    assert "<code>ConfigError</code>" in errors


def test_pages_of_every_section_are_built(site: Path) -> None:
    for uri in (
        "getting-started",
        "architecture",
        "sessions",
        "results",
        "results/paper-2d/summary",
    ):
        page(site, uri)
    for bench in sorted((ROOT / "benchmarks" / "results").glob("*.md")):
        title = bench.read_text(encoding="utf-8").splitlines()[0].removeprefix("# ")
        assert html.escape(title, quote=False) in page(site, f"benchmarks/results/{bench.stem}")
    # a link from docs/ to ../benchmarks/results/*.md lands on the pulled-in page
    assert 'href="../benchmarks/results/console/' in page(site, "console")


def test_site_fetches_no_web_fonts(site: Path) -> None:
    assert "fonts.googleapis.com" not in page(site, "getting-started")


def test_strict_build_fails_on_a_broken_link_and_reference(tmp_path: Path) -> None:
    require_mkdocs()
    shutil.copy(ROOT / "mkdocs.yml", tmp_path)
    shutil.copytree(ROOT / "docs", tmp_path / "docs")
    shutil.copytree(ROOT / "benchmarks" / "results", tmp_path / "benchmarks" / "results")
    (tmp_path / "src").symlink_to(ROOT / "src")
    with (tmp_path / "docs" / "index.md").open("a", encoding="utf-8") as f:
        f.write("\n[gone](no-such-page.md) and [gone too][gaitpref.NoSuchThing]\n")
    result = build(tmp_path, tmp_path / "site")
    output = result.stdout + result.stderr
    assert result.returncode != 0
    assert "no-such-page.md" in output
    assert "gaitpref.NoSuchThing" in output


def markdown_files() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


@pytest.mark.parametrize("doc", markdown_files(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_relative_links_resolve(doc: Path) -> None:
    text = FENCE.sub("", doc.read_text(encoding="utf-8"))
    broken = []
    for target in LINK.findall(text):
        if "://" in target or target.startswith(("#", "mailto:")):
            continue
        path = target.split("#", 1)[0]
        if not (doc.parent / path).exists():
            broken.append(target)
    assert not broken, f"{doc.relative_to(ROOT)} links to missing files: {broken}"


#: a page of this repository cited in a source docstring: ``docs/model.md``
CITED = re.compile(r"``((?:docs|design)/[\w./-]+\.md)``")


def test_source_docstrings_cite_pages_and_sections_that_exist() -> None:
    """A source file's ``docs/...md`` (or ``design/...md``) is a page here, and each section it
    names in quotes after it (``docs/model.md``, "Laplace mode") is a heading of that page: six
    modules cited ``design/algorithm.md`` and six gait modules ``design/gaits.md``, files the
    repository does not contain."""
    wrong = []
    for source in sorted((ROOT / "src" / "gaitpref").rglob("*.py")):
        text = source.read_text(encoding="utf-8")
        for cite in CITED.finditer(text):
            page, where = ROOT / cite.group(1), source.relative_to(ROOT)
            if not page.is_file():
                wrong.append(f"{where}: {cite.group(1)} is not in the repository")
                continue
            # the quoted names up to the end of the citation's sentence or parenthesis
            after = re.split(r"\)\.|\.\s|:\s", text[cite.end() : cite.end() + 160])[0]
            named = re.findall(r'"([^"]+)"', re.sub(r"\s+", " ", after))
            lines = page.read_text(encoding="utf-8").splitlines()
            headings = [line.lstrip("#").strip() for line in lines if line.startswith("#")]
            wrong += [
                f"{where}: {cite.group(1)} has no section {name!r}"
                for name in named
                if not any(h.startswith(name) for h in headings)
            ]
    assert not wrong, "\n".join(wrong)


@pytest.mark.parametrize(
    ("ci", "outcome"), [("true", pytest.fail.Exception), ("", pytest.skip.Exception)]
)
def test_without_mkdocs_the_build_skips_locally_and_fails_on_ci(
    monkeypatch: pytest.MonkeyPatch, ci: str, outcome: type[BaseException]
) -> None:
    monkeypatch.setattr(importlib.util, "find_spec", lambda name: None)
    monkeypatch.setenv("CI", ci)
    with pytest.raises(outcome, match="mkdocs, material, mkdocstrings not installed"):
        require_mkdocs()
