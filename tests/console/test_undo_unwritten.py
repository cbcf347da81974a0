"""The console's undo (``POST /api/sessions/{id}/undo``) and withdrawal with undo (the API's and
the validation page's) whose undone answer's query, withdrawn (it proposed a gait flagged unsafe
since), is to be replaced by a new query that the database fails to write: the undo (and the
withdrawal) are written, so the request succeeds saying why no query is pending
(``next_query_error``), and the next ask proposes it.  They answered 503 "database failed" with
"the undo is written; ..." as if the request were refused."""

from __future__ import annotations

from typing import Any

from fastapi.testclient import TestClient

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.storage import StorageFailureError
from tests.console.htmlforms import forms_of
from tests.console.test_pages import post
from tests.sessions.test_unsafe import CONFIG, _answer, _flag_then_undo


def _refuse_new_queries(client: TestClient) -> list[int]:
    """The console's database fails every write of a new query; the list counts them."""
    storage = client.app.state.service.storage  # type: ignore[attr-defined]
    append = storage.append
    refused: list[int] = []

    def failing(*args: Any, **kwargs: Any) -> Any:
        if any(e.kind == "query_issued" for e in args[2]):
            refused.append(1)
            raise StorageFailureError(f"{storage.url}: disk I/O error; nothing was written")
        return append(*args, **kwargs)

    storage.append = failing
    return refused


def _round_with_flagged_answer(db_url: str) -> None:
    """Round 1 opened by the [stop] rule after trial 2 (gait 8, near trial 1's gait 6, flagged
    unsafe since): withdrawing it with undo withdraws trial 2's query too."""
    with Session.create(db_url, parse_config(CONFIG + "\n[stop]\nmax_trials = 2\n"), "S01") as s:
        _answer(s, 0)
        _answer(s, 1)
        assert [t.action for t in s.trials()] == [6, 8] and s.validation_plan is not None
        s.flag_unsafe(1, "ankle pain")


def test_the_api_undo_whose_new_query_is_not_written_stands_and_says_why(
    client: TestClient, db_url: str
) -> None:
    _flag_then_undo(db_url, pause=False)[0].close()
    refused = _refuse_new_queries(client)
    r = client.post("/api/sessions/1/undo")
    assert refused and r.status_code == 200, r.text
    body = r.json()
    assert body["pending_query_id"] is None and body["withdrawn"] is True
    assert body["trials"] == [2]
    assert "the undo is written" in body["next_query_error"]
    assert "disk I/O error" in body["next_query_error"]
    del client.app.state.service.storage.append  # type: ignore[attr-defined]  # works again
    asked = client.get("/api/sessions/1/query")  # the next ask proposes it
    assert asked.status_code == 200 and asked.json()["trials_done"] == 1, asked.text
    with Session.open(db_url, 1) as s:
        assert [t.number for t in s.trials()] == [1]
        assert s.pending is not None and s.pending.trials == (2,)


def test_the_api_withdrawal_with_undo_whose_new_query_is_not_written_stands(
    client: TestClient, db_url: str
) -> None:
    _round_with_flagged_answer(db_url)
    refused = _refuse_new_queries(client)
    r = client.post("/api/sessions/1/validation/1/withdraw", json={"reason": "x", "undo": True})
    assert refused and r.status_code == 200, r.text
    body = r.json()
    assert body["round"] == 1 and body["trials"] == [2] and body["pending_query_id"] is None
    assert "the undo is written" in body["next_query_error"]
    with Session.open(db_url, 1) as s:
        assert s.validation_plan is None and [t.number for t in s.trials()] == [1]
        assert [r.withdrawn for r in s.validation_rounds()] == ["x"]


def test_the_pages_withdrawal_with_undo_whose_new_query_is_not_written_redirects(
    client: TestClient, db_url: str
) -> None:
    _round_with_flagged_answer(db_url)
    form = forms_of(client.get("/sessions/1/validation").text)["withdraw-round-form"]
    refused = _refuse_new_queries(client)
    fields = {**form.fields, "reason": "mis-keyed", "undo": "1", "confirmed": "1"}
    r = post(client, form.action, fields)
    assert refused and r.status_code == 303, r.text  # not an error page
    assert r.headers["location"] == "/sessions/1"
    with Session.open(db_url, 1) as s:
        assert s.validation_plan is None and [t.number for t in s.trials()] == [1]


def test_an_undo_whose_own_write_fails_is_still_refused(client: TestClient, db_url: str) -> None:
    _flag_then_undo(db_url, pause=False)[0].close()
    storage = client.app.state.service.storage  # type: ignore[attr-defined]

    def failing(*args: Any, **kwargs: Any) -> Any:
        raise StorageFailureError(f"{storage.url}: disk I/O error; nothing was written")

    client.get("/api/sessions/1")  # opened before the database fails
    storage.append = failing
    r = client.post("/api/sessions/1/undo")
    assert r.status_code == 503 and "disk I/O error" in r.json()["detail"]
    with Session.open(db_url, 1) as s:
        assert [t.number for t in s.trials()] == [1, 2]
