"""The operator's first hour (issue 15, item 12): no config chosen for them, and nothing broken
at 1024 px (a landscape tablet)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import httpx
import pytest
from fastapi.testclient import TestClient

from gaitpref.console import create_app
from tests.console.htmlforms import forms_of
from tests.console.live import serve


def test_the_new_session_form_preselects_no_config(client: TestClient) -> None:
    html = client.get("/").text
    select = re.search(r'<select name="config".*?</select>', html, re.S)
    assert select is not None
    options = re.findall(r"<option([^>]*)>", select.group(0))
    assert options[0] == ' value="" selected'  # "choose a config"
    assert all("selected" not in o for o in options[1:])  # compass-gait is not chosen for them
    form = forms_of(html)["create-form"]
    r = client.post(
        "/sessions",
        data={**form.fields, "subject": "S01", "config": ""},
        files={"config_file": ("", b"")},
    )
    assert r.status_code == 422 and "choose a shipped config" in r.text
    assert client.get("/api/sessions").json() == []


#: per suggestion button: a word split across lines; per value: its unit on another line
LAYOUT_PROBLEMS = """() => {
  const problems = [];
  const lines = (node, start, end) => {
    const range = document.createRange();
    range.setStart(node, start); range.setEnd(node, end);
    const rects = [...range.getClientRects()].filter(r => r.width > 0);
    rects.sort((a, b) => a.top - b.top);
    let count = 0, bottom = -Infinity;  // rects that overlap vertically are one line
    for (const r of rects) {
      if (r.top >= bottom - 2) count += 1;
      bottom = Math.max(bottom, r.bottom);
    }
    return count;
  };
  for (const span of document.querySelectorAll('.choice.move span')) {
    for (const node of span.childNodes) {
      if (node.nodeType !== Node.TEXT_NODE) continue;
      for (const m of node.textContent.matchAll(/\\S+/g)) {
        if (lines(node, m.index, m.index + m[0].length) > 1) problems.push('word ' + m[0]);
      }
    }
    if (span.scrollWidth > span.clientWidth + 1) problems.push('overflow ' + span.textContent);
  }
  for (const q of document.querySelectorAll('.values .qty')) {
    if (lines(q, 0, q.childNodes.length) > 1) problems.push('unit ' + q.textContent);
  }
  return problems;
}"""


@pytest.mark.browser
@pytest.mark.parametrize("config", ["exo-2d-length-duration", "exo-2d-length-width"])
def test_the_trial_page_at_1024_px_breaks_no_word(
    chromium: Any, tmp_path: Path, config: str
) -> None:
    with serve(create_app(f"sqlite:///{tmp_path / 'b.db'}")) as url:
        sid = httpx.post(f"{url}/api/sessions", json={"config": config, "subject": "S1"})
        page = chromium.new_page(viewport={"width": 1024, "height": 768})
        page.goto(f"{url}/sessions/{sid.json()['id']}")
        assert page.locator(".choice.move span").count() >= 5
        assert page.locator(".values .qty").count() >= 2
        assert page.evaluate(LAYOUT_PROBLEMS) == []
        page.close()
