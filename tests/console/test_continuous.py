"""A console session on a continuous 3-parameter space with gaits made on demand (issue 13):
the config list names the space in words, the trial page, the posterior figures (the posterior
at the trials' points: there is no grid to draw), the API's posterior and the export all work."""

from __future__ import annotations

import io
import re
import zipfile

from fastapi.testclient import TestClient

from gaitpref import load_config
from tests.console.conftest import answer_once, new_session
from tests.console.htmlforms import forms_of

CONFIG = "compass-continuous-3d"
ID = re.compile(r"^L\d\.\d{3}-T\d\.\d{3}-W\d\.\d{3}#[0-9a-f]{8}$")


def test_a_continuous_generator_session_in_the_console(client: TestClient) -> None:
    listed = {c["name"]: c for c in client.get("/api/configs").json()}
    assert listed[CONFIG]["grid"] is None
    assert listed[CONFIG]["space"] == "continuous: step_length, step_duration, step_width"
    assert listed["exo-2d-length-duration"]["space"] == "15 x 10"
    assert "continuous: step_length, step_duration, step_width" in client.get("/").text
    sid = new_session(client, CONFIG)
    shown: list[str] = []
    for _ in range(5):
        q = client.get(f"/api/sessions/{sid}/query").json()
        shown += [g["gait_id"] for g in q["actions"]]
        body = {
            "query_id": q["query_id"],
            "comparisons": [[i, j, "first"] for i, j in q["comparisons"]],
        }
        assert client.post(f"/api/sessions/{sid}/answers", json=body).status_code == 200
    assert all(ID.match(g) for g in shown)
    logged = [
        e["payload"]["gait_id"]
        for e in client.get(f"/api/sessions/{sid}/events").json()
        if e["kind"] == "trial_executed"
    ]
    assert logged == shown
    page = client.get(f"/sessions/{sid}")
    assert page.status_code == 200 and shown[-1] in page.text
    for figure in ("posterior.png", "figure.png"):
        r = client.get(f"/sessions/{sid}/{figure}")
        assert r.status_code == 200 and r.content.startswith(b"\x89PNG")
    post = client.get(f"/api/sessions/{sid}/posterior").json()
    assert post["shape"] is None and len(post["mean"]) == len(post["sd"]) > len(shown)
    assert ID.match(post["argmax"]["gait_id"])
    export = client.get(f"/sessions/{sid}/export.zip")
    assert export.status_code == 200
    with zipfile.ZipFile(io.BytesIO(export.content)) as z:
        trials = next(n for n in z.namelist() if n.endswith("trials.csv"))
        text = z.read(trials).decode()
    assert all(g in text for g in shown)
    assert client.post(f"/api/sessions/{sid}/undo").status_code == 200
    assert client.get(f"/sessions/{sid}").status_code == 200


def test_a_line_session_over_a_grid_too_large_to_enumerate_serves_its_posterior(
    client: TestClient,
) -> None:
    """Discrete features whose grid (2,000 x 2,000) the line path never enumerates: the
    session's actions are the points so far, not a grid, and GET /posterior was a 500 (the
    point set's shape is a TypeError); its shape is null, as for continuous features."""
    config = "[model]\nlengthscale = 0.2\nsignal_variance = 0.005\nnoise = 0.02\n" + "".join(
        f"[space.x{i}]\nmin = 0\nmax = 1\nnum = 2000\n" for i in range(2)
    )
    sid = new_session(client, config)
    for _ in range(2):
        q = client.get(f"/api/sessions/{sid}/query").json()
        body = {"query_id": q["query_id"], "comparisons": [[*c, "first"] for c in q["comparisons"]]}
        assert client.post(f"/api/sessions/{sid}/answers", json=body).status_code == 200
    r = client.get(f"/api/sessions/{sid}/posterior")
    assert r.status_code == 200, r.text
    post = r.json()
    assert post["shape"] is None and 2 <= len(post["mean"]) == len(post["sd"]) < 2000
    assert client.get(f"/sessions/{sid}").status_code == 200


def _flag_confirm_page(client: TestClient, config: str) -> str:
    sid = new_session(client, config)
    answer_once(client, sid)
    html = client.get(f"/sessions/{sid}").text
    flag = next(f for f in forms_of(html).values() if f.action.endswith("/trials/1/unsafe"))
    ask = client.post(flag.action, data={**flag.fields, "reason": "hip pain"})
    assert ask.status_code == 200 and "Flag this trial unsafe?" in ask.text
    return " ".join(ask.text.split())


def test_the_flag_page_says_close_gaits_may_come_without_a_radius(client: TestClient) -> None:
    """compass-continuous-3d without its [safety] unsafe_radius (as shipped before): the flag
    removes that point alone, and on continuous features a gait however close to it may be
    proposed next."""
    text = load_config(CONFIG).text
    table = "[safety]\nunsafe_radius = 0.1\n"
    assert table in text
    page = _flag_confirm_page(client, text.replace(table, ""))
    assert "but gaits however close to it may be" in page


def test_the_shipped_continuous_config_keeps_gaits_near_an_unsafe_flag_away(
    client: TestClient,
) -> None:
    """compass-continuous-3d has a radius (0.1 of the ranges): the flag says the gaits within it
    go too, and nothing about gaits however close."""
    assert load_config(CONFIG).safety.unsafe_radius == 0.1
    page = _flag_confirm_page(client, CONFIG)
    assert "Its gait and the gaits within 0.1 of its range will not be proposed again" in page
    assert "however close" not in page
