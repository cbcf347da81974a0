"""The trial page's shortcuts as rendered (no browser): the undo's ``U`` is shown only where no
suggestion row takes it (a fourth feature's ``Y U I O P`` does), a rating is skipped with
``0``, and ``N`` (the last trial's unsafe flag) is no suggestion's key and is shown where its
button is; the browser checks are in ``test_browser_keys.py``."""

from __future__ import annotations

import re

import pytest
from fastapi.testclient import TestClient

from gaitpref.config.schema import MAX_FEATURES
from gaitpref.console import views
from gaitpref.space import Feature, Space
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


def flag_summary(html: str) -> str | None:
    last = r'<details class="unsafe" id="unsafe-last"[^>]*><summary[^>]*>(.*?)</summary>'
    m = re.search(last, html)
    return m.group(1) if m else None


FLAG_LISTED = "<kbd>N</kbd> flag trial"


def test_n_is_taken_by_no_suggestion_row_with_as_many_features_as_a_config_may_have() -> None:
    for ndim in range(1, MAX_FEATURES + 1):
        space = Space([Feature(f"f{k}", [0.0]) for k in range(ndim)])
        groups = views.suggestion_groups(space, [views.gait_view(space, 0, trial=1)])
        keys = {ch.key for g in groups for ch in g.choices}
        assert views.FLAG_KEY not in keys, ndim
    # nor by the other keys of the trial page: digits, the undo, the note, . and ,
    assert views.FLAG_KEY not in "0123456789" + views.UNDO_KEY + "m.,"


def test_the_flag_key_is_shown_on_its_button_and_listed_only_where_the_button_is(
    client: TestClient,
) -> None:
    sid = new_session(client)
    html = client.get(f"/sessions/{sid}").text
    assert flag_summary(html) is None and FLAG_LISTED not in html  # no trial yet
    answer_once(client, sid)
    html = client.get(f"/sessions/{sid}").text
    assert flag_summary(html) == "Flag trial 1 unsafe <kbd>N</kbd>"
    assert 'id="unsafe-last" data-key="n"' in html
    assert "<kbd>N</kbd> flag trial 1 unsafe: opens its reason" in html
    # the chronology's "unsafe" of each row has no key
    assert html.count('data-key="n"') == 1
    r = client.post(f"/api/sessions/{sid}/trials/1/unsafe", json={"reason": "knee buckled"})
    assert r.status_code == 200, r.text
    html = client.get(f"/sessions/{sid}").text
    assert flag_summary(html) is None and FLAG_LISTED not in html  # trial 1 is flagged
    answer_once(client, sid)
    html = client.get(f"/sessions/{sid}").text
    assert flag_summary(html) == "Flag trial 2 unsafe <kbd>N</kbd>"
    r = client.post(f"/api/sessions/{sid}/status", json={"status": "finished"})
    assert r.status_code == 200, r.text
    html = client.get(f"/sessions/{sid}").text
    assert flag_summary(html) is None and FLAG_LISTED not in html


def listed_rows(html: str) -> list[tuple[str, str]]:
    """The suggestion rows of the page's list of shortcuts: (feature, its keys) in order."""
    m = re.search(r'<details class="shortcuts">(.*?)</details>', html, re.S)
    assert m, "no list of shortcuts"
    found = re.findall(r"<li>([\w ]+): ((?:<kbd>[^<]</kbd> )+)\(from", m.group(1))
    return [(name, "".join(re.findall(r"<kbd>([^<])</kbd>", keys))) for name, keys in found]


def test_the_listed_suggestion_keys_are_views_suggestion_rows(client: TestClient) -> None:
    """The list of shortcuts is rendered from ``views.SUGGESTION_ROWS``, the keys the suggestion
    buttons take, never written out again (they could drift apart)."""
    sid = new_session(client, config=FOUR_FEATURES)
    html = client.get(f"/sessions/{sid}").text
    expected = [(f"f{k + 1}", row.upper()) for k, row in enumerate(views.SUGGESTION_ROWS[:4])]
    assert listed_rows(html) == expected
    for name, keys in expected:  # the buttons' keys, from "more" to "less"
        pressed = re.findall(rf'name="sug-\d+-{name}" value="[^"]*" data-key="(.)"', html)
        assert "".join(pressed).upper() == keys


def test_the_list_of_shortcuts_follows_a_change_of_the_rows(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(views, "SUGGESTION_ROWS", ("zxcvb", "qwert", "asdfg"))
    sid = new_session(client, config=FOUR_FEATURES)
    html = client.get(f"/sessions/{sid}").text
    assert listed_rows(html) == [("f1", "ZXCVB"), ("f2", "QWERT"), ("f3", "ASDFG")]  # f4: none
    assert not re.search(r'name="sug-\d+-f4" value="[^"]*" data-key="."', html)
