"""The page says so when an exclusion or an unsafe flag withdrew the pending query: the gait the
operator may already have set on the device is no longer the one to run.

The scenario is ``tests/sessions/regionkit.py``'s: query 6 proposes gait 1, allowed only while
trial 1's "good" rating is in the model; excluding trial 1 withdraws it (a new query is
proposed), excluding trial 4 does not.
"""

from __future__ import annotations

from fastapi.testclient import TestClient

from gaitpref import Session
from gaitpref.config import parse_config
from tests.console.htmlforms import forms_of
from tests.sessions import regionkit

WITHDRAWN = "was withdrawn: the query below is a new one; set the device to it"


def _pending_query_6(db_url: str, safety: str = "") -> int:
    """The scenario's session, query 6 pending; ``safety``: more ``[safety]`` keys."""
    with Session.create(db_url, parse_config(regionkit.CONFIG + safety), "S01") as s:
        regionkit.rate_trials(s, 5)
        assert s.next_query().actions == (regionkit.GAITS[5],)
        return s.id


def _exclude(client: TestClient, sid: int, trial: int) -> tuple[str, str]:
    """Exclude ``trial`` through its form on the trial page; the redirect and the page after."""
    html = client.get(f"/sessions/{sid}").text
    action = f"/sessions/{sid}/trials/{trial}/exclude"
    form = next(f for f in forms_of(html).values() if f.action == action)
    review = client.post(
        form.action, data={**form.fields, "reason": "device_fault"}, follow_redirects=False
    )
    assert review.status_code == 200  # the confirm step (an exclusion is for good)
    confirmed = forms_of(review.text)["form1"].fields
    assert confirmed["confirmed"] == "1"
    done = client.post(form.action, data=confirmed, follow_redirects=False)
    assert done.status_code == 303
    location = done.headers["location"]
    return location, client.get(location).text


def test_an_exclusion_that_withdrew_the_pending_query_says_so(
    client: TestClient, db_url: str
) -> None:
    sid = _pending_query_6(db_url)
    location, page = _exclude(client, sid, 1)
    assert location.endswith("?excluded=1&replaced=1")
    assert "Trial 1 excluded: its answers left the model." in page
    assert "in the region of avoidance of the model without them" in page and WITHDRAWN in page
    query = client.get(f"/api/sessions/{sid}/query").json()
    assert [a["index"] for a in query["actions"]] != [regionkit.GAITS[5]]


def test_an_exclusion_that_kept_the_pending_query_says_only_that(
    client: TestClient, db_url: str
) -> None:
    sid = _pending_query_6(db_url)
    location, page = _exclude(client, sid, 4)
    assert location.endswith("?excluded=4&replaced=0")
    assert "Trial 4 excluded: its answers left the model." in page and WITHDRAWN not in page
    query = client.get(f"/api/sessions/{sid}/query").json()
    assert [a["index"] for a in query["actions"]] == [regionkit.GAITS[5]]


def test_an_unsafe_flag_that_withdrew_the_pending_query_says_so(
    client: TestClient, db_url: str
) -> None:
    # gait 1 pending; trial 1 ran gait 2, 1/14 of the range from it
    sid = _pending_query_6(db_url, "unsafe_radius = 0.1\n")
    html = client.get(f"/sessions/{sid}").text
    action = f"/sessions/{sid}/trials/1/unsafe"
    flag = next(f for f in forms_of(html).values() if f.action == action)
    ask = client.post(action, data={**flag.fields, "reason": "knee"}, follow_redirects=False)
    assert ask.status_code == 200  # the confirmation step
    confirmed = forms_of(ask.text)["form1"].fields
    done = client.post(action, data=confirmed, follow_redirects=False)
    assert done.headers["location"].endswith("?flagged=1&replaced=1")
    page = client.get(done.headers["location"]).text
    assert "Trial 1 flagged unsafe" in page and "proposed a gait near it" in page
    assert WITHDRAWN in page
    page = client.get(f"/sessions/{sid}?excluded=1&replaced=1").text  # not excluded: nothing
    assert "excluded: its answers" not in page


def test_an_undo_whose_query_was_withdrawn_says_when_a_new_one_comes() -> None:
    """Paused, or with a blind validation round open, no query is proposed in the withdrawn
    one's place until then: the page said "a new query is proposed in its place" regardless."""
    from types import SimpleNamespace

    from gaitpref.console.pages import _flash

    rows = [SimpleNamespace(trial=t, excluded=False) for t in (1, 2)]

    def said(reason: str) -> str:
        context = {"chronology": rows, "unsafe": set(), "reason": reason}
        return _flash(context, None, "3", 1, None, None)

    assert said("").endswith("so a new query is proposed in its place.")
    assert said("paused").endswith("in its place once the session is resumed.")
    validation = said("validation")
    assert validation.endswith("in its place once blind validation is ranked or withdrawn.")
    assert "so a new query is proposed" not in said("paused") + validation
    assert said("no-safe").endswith("no new query could be proposed in its place.")
