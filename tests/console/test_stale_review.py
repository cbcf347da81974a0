"""A stale undo, unsafe flag or flag withdrawal is refused (409) at its review step already.

The confirm page (without JavaScript) of an undo named the last trial whatever query the
form was made for, and those of a flag or a withdrawal did not look at the session: after
another tab answered, undid, flagged or withdrew first, the operator was shown a change to
confirm that the final post then refused, or that undid another answer than the one seen.
"""

from __future__ import annotations

from fastapi.testclient import TestClient

from tests.console.conftest import answer_once, csrf_of, event_count, new_session


def _setup(client: TestClient) -> tuple[int, str, int]:
    """A session with two answered trials; its id, a CSRF token and the pending query."""
    sid = new_session(client)
    answer_once(client, sid)
    answer_once(client, sid)
    csrf = csrf_of(client.get(f"/sessions/{sid}").text)
    return sid, csrf, int(client.get(f"/api/sessions/{sid}/query").json()["query_id"])


def _refused(client: TestClient, sid: int, path: str, data: dict[str, str], said: str) -> None:
    before = event_count(client, sid)
    for confirmed in ("", "1"):  # the review step, then the final post
        r = client.post(
            f"/sessions/{sid}/{path}", data=data | {"confirmed": confirmed}, follow_redirects=False
        )
        assert r.status_code == 409, (confirmed, r.text)
        assert said in r.text, (confirmed, r.text)
    assert event_count(client, sid) == before


def test_an_undo_for_a_query_no_longer_pending_is_refused_at_review(client: TestClient) -> None:
    sid, csrf, pending = _setup(client)
    answer_once(client, sid)  # another tab answered first
    data = {"csrf_token": csrf, "query_id": str(pending)}
    _refused(client, sid, "undo", data, f"the undo was asked while query {pending} was pending")


def test_an_undo_of_a_flagged_trial_is_refused_at_review(client: TestClient) -> None:
    sid, csrf, pending = _setup(client)
    assert client.post(f"/api/sessions/{sid}/trials/2/unsafe", json={"reason": "knee"}).is_success
    pending = int(client.get(f"/api/sessions/{sid}/query").json()["query_id"])
    data = {"csrf_token": csrf, "query_id": str(pending)}
    _refused(client, sid, "undo", data, "withdraw the flag before undoing its answer")


def test_a_flag_of_a_trial_undone_or_flagged_since_is_refused_at_review(
    client: TestClient,
) -> None:
    sid, csrf, pending = _setup(client)
    assert client.post(f"/api/sessions/{sid}/undo", json={"query_id": pending}).is_success
    data = {"csrf_token": csrf, "reason": "knee"}
    _refused(client, sid, "trials/2/unsafe", data, "no trial 2 has been answered")
    assert client.post(f"/api/sessions/{sid}/trials/1/unsafe", json={"reason": "hip"}).is_success
    _refused(client, sid, "trials/1/unsafe", data, "trial 1 is already flagged unsafe")


def test_a_withdrawal_of_a_flag_withdrawn_since_is_refused_at_review(client: TestClient) -> None:
    sid, csrf, _ = _setup(client)
    assert client.post(f"/api/sessions/{sid}/trials/1/unsafe", json={"reason": "hip"}).is_success
    page = client.post(
        f"/sessions/{sid}/trials/1/unsafe/withdraw", data={"csrf_token": csrf, "confirmed": ""}
    )
    assert page.status_code == 200 and "Withdraw the unsafe flag of trial 1" in page.text
    assert client.post(f"/api/sessions/{sid}/trials/1/unsafe/withdraw").is_success  # another tab
    _refused(
        client, sid, "trials/1/unsafe/withdraw", {"csrf_token": csrf}, "trial 1 is not flagged"
    )
