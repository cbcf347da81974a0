"""The trial page's shortcuts as rendered (no browser): the undo's ``U`` is shown only where no
suggestion row takes it (a fourth feature's ``Y U I O P`` does), and a rating is skipped with
``0``; the browser checks are in ``test_browser_keys.py``."""

from __future__ import annotations

import re

from fastapi.testclient import TestClient

from tests.console.conftest import answer_once, new_session

FOUR_FEATURES = (
    'name = "four"\n'
    + "".join(f"[space.f{k}]\nmin = 0.0\nmax = 1.0\nnum = 3\n" for k in range(1, 5))
    + "[model]\nlengthscale = 0.3\nsignal_variance = 1.0\nnoise = 0.05\n"
)


def undo_button(html: str) -> str:
    m = re.search(r'<button[^>]*id="undo"[^>]*>(.*?)</button>', html, re.S)
    assert m, "no undo button"
    return m.group(1)


def test_the_undo_shows_its_key_where_it_has_one(client: TestClient) -> None:
    sid = new_session(client)
    answer_once(client, sid)
    html = client.get(f"/sessions/{sid}").text
    assert undo_button(html) == "Undo last answer <kbd>U</kbd>"
    assert "<kbd>U</kbd> undo the last answer" in html
    assert "the keys type; <kbd>Esc</kbd> leaves it. A held key acts once" in html


def test_with_four_features_u_is_a_suggestion_and_the_undo_a_button(client: TestClient) -> None:
    sid = new_session(client, config=FOUR_FEATURES)
    answer_once(client, sid)
    html = client.get(f"/sessions/{sid}").text
    assert undo_button(html) == "Undo last answer"
    assert "undo with its button (<kbd>U</kbd> is a suggestion's key here)" in html
    assert re.search(r'name="sug-\d+-f4" value="\+small" data-key="u"', html)
