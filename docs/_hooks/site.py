"""MkDocs hooks for gaitpref's site (named in ``mkdocs.yml``; excluded from the pages).

- ``benchmarks/results/*.md`` (outside ``docs/``) become pages under ``benchmarks/results/``, and
  a link to one from a page in ``docs/`` (``../benchmarks/results/core.md``, right on GitHub) is
  pointed at that page, so both work.  Each is listed under Results > Speed benchmarks, named by
  its first heading, so a new benchmark's results need no edit here.
- The API reference of ``gaitpref.storage`` adds ``gaitpref.storage.testing`` (the storage contract
  suite) when that module exists.
"""

from __future__ import annotations

import posixpath
import re
from pathlib import Path
from typing import Any

from mkdocs.config.defaults import MkDocsConfig
from mkdocs.structure.files import File, Files
from mkdocs.structure.pages import Page

ROOT = Path(__file__).resolve().parents[2]
PULLED_IN = "benchmarks/results"  # a folder of the repository, pulled in under the same path
_LINK = re.compile(r"(\]\()([^)\s#]+)(#[^)\s]*)?(\))")


def _pulled_in() -> list[Path]:
    pages = sorted((ROOT / PULLED_IN).glob("*.md"))
    if not pages:
        raise FileNotFoundError(f"no pages in {ROOT / PULLED_IN} to pull into the site")
    return pages


def _title(path: Path) -> str:
    first = path.read_text(encoding="utf-8").split("\n", 1)[0]
    if not first.startswith("# "):
        raise ValueError(f"{path} must start with a '# title' line (it names the page in the nav)")
    return first.removeprefix("# ").strip()


def on_config(config: MkDocsConfig, **kwargs: Any) -> MkDocsConfig:
    """Every pulled-in page under Results > Speed benchmarks, named by its first heading."""
    results = [s for s in config.nav or [] if isinstance(s, dict) and "Results" in s]
    if len(results) != 1:
        raise ValueError("mkdocs.yml's nav needs one 'Results' section for the benchmark pages")
    section = [{_title(p): f"{PULLED_IN}/{p.name}"} for p in _pulled_in()]
    results[0]["Results"].append({"Speed benchmarks": section})
    return config


def on_files(files: Files, config: MkDocsConfig, **kwargs: Any) -> Files:
    for path in _pulled_in():
        files.append(File.generated(config, f"{PULLED_IN}/{path.name}", abs_src_path=str(path)))
    return files


def _retarget(page: Page, target: str) -> str:
    """A relative link from ``page`` into ``PULLED_IN`` on disk, as a link to the pulled-in page."""
    if "://" in target or target.startswith(("/", "mailto:")) or page.file.abs_src_path is None:
        return target
    on_disk = (Path(page.file.abs_src_path).parent / target).resolve()
    if not on_disk.is_relative_to(ROOT / PULLED_IN):
        return target
    in_site = on_disk.relative_to(ROOT).as_posix()
    return posixpath.relpath(in_site, posixpath.dirname(page.file.src_uri) or ".")


def on_page_markdown(markdown: str, page: Page, config: MkDocsConfig, **kwargs: Any) -> str:
    markdown = _LINK.sub(
        lambda m: m[1] + _retarget(page, m[2]) + (m[3] or "") + m[4],
        markdown,
    )
    storage = ROOT / "src" / "gaitpref" / "storage"
    has_suite = (storage / "testing.py").exists() or (storage / "testing").is_dir()
    if page.file.src_uri == "reference/storage.md" and has_suite:
        markdown += "\n::: gaitpref.storage.testing\n"
    return markdown
