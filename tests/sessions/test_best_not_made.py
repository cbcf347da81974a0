"""With gaits made on demand the "best so far" may be a point no query proposed: a coactive
suggestion's ("longer") is a point of the model, and often its highest.  ``session show`` and
the console named it as they name a walked gait, with a gait id, although its gait was never
made and may not be feasible (on ``compass-continuous-3d`` a subject who asked for shorter steps
had the best so far at 0.04 m, which has no gait); blind validation shows made gaits only.  Both
now say when its gait is not made (``Session.gait_made``).  Since defaults 0.13 the
recommendation is the best gait made (``test_recommend_made.py``); these tests keep the earlier
rule with ``[gaits] recommend = "any"``, which sessions recorded before 0.13 replay with."""

from __future__ import annotations

from pathlib import Path

from fastapi.testclient import TestClient
from typer.testing import CliRunner

from gaitpref import Session
from gaitpref.cli import app
from gaitpref.config import parse_config
from gaitpref.console.app import create_app
from gaitpref.sessions.gaits import NOT_MADE
from tests.sessions.gaitkit import CONTINUOUS as MADE_ONLY

#: the earlier rule: the best point of the model, made or not
CONTINUOUS = MADE_ONLY.replace("avoid_radius = 0.1\n", 'avoid_radius = 0.1\nrecommend = "any"\n')
assert CONTINUOUS != MADE_ONLY

runner = CliRunner()


def _show(url: str, sid: int) -> str:
    out = runner.invoke(app, ["session", "show", str(sid), "--no-figure", "--db", url])
    assert out.exit_code == 0, out.output
    return " ".join(out.output.split())


def _page(url: str, sid: int) -> str:
    with TestClient(create_app(url)) as client:
        page = client.get(f"/sessions/{sid}")
    assert page.status_code == 200
    return " ".join(page.text.split())


def test_a_best_so_far_whose_gait_is_not_made_is_said_so(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with Session.create(url, parse_config(CONTINUOUS), "S01") as s:
        q = s.next_query()
        s.answer(q.id, [], [(q.actions[0], "step_length", "+big")])  # the model's best: longer
        best = s.recommended()
        assert best is not None and best not in q.actions
        assert s.gait_made(best) is False and s.gait_made(q.actions[0]) is True
        sid, name = s.id, s.gait_name(best)
    text = _show(url, sid)
    assert f"best so far: {name} " in text and f"({NOT_MADE})" in text
    page = _page(url, sid)
    assert f'<span id="best-not-made">({NOT_MADE})</span>' in page


def _compare_only(s: Session, answers: int) -> None:
    """``answers`` queries answered with comparisons alone (the new gait preferred), no
    suggestion: every gait the model knows was proposed, and so made."""
    for _ in range(answers):
        q = s.next_query()
        a, b = q.actions[0], q.buffer[0] if q.buffer else q.actions[0]
        s.answer(q.id, [] if a == b else [(a, b, "first")])


def test_a_best_so_far_that_was_walked_says_nothing_more(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with Session.create(url, parse_config(CONTINUOUS), "S01") as s:
        _compare_only(s, 3)  # the best is a point a query proposed
        best = s.recommended()
        assert best is not None and s.gait_made(best) is True
        sid = s.id
    assert NOT_MADE not in _show(url, sid)
    assert "best-not-made" not in _page(url, sid)


def test_the_terminal_says_so_with_the_confidence(tmp_path: Path) -> None:
    from io import StringIO

    from rich.console import Console

    from gaitpref.terminal import Terminal

    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with Session.create(url, parse_config(CONTINUOUS), "S01") as s:
        keys = ["1", "0", "y", "q"]  # trial 1: step_length longer, no width move, write
        out = StringIO()
        Terminal(s, Console(file=out, width=400), read=lambda _: keys.pop(0)).run()
        best = s.recommended()
        assert best is not None and s.gait_made(best) is False
        lines = [line for line in out.getvalue().splitlines() if "of the best" in line]
        assert len(lines) == 1 and lines[0].endswith(f"is within 5% of the best ({NOT_MADE})")
        assert f"% that {s.gait_name(best)} is within" in lines[0]


def test_the_api_says_whether_a_gait_is_made(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with Session.create(url, parse_config(CONTINUOUS), "S01") as s:
        q = s.next_query()
        s.answer(q.id, [], [(q.actions[0], "step_length", "+big")])
        sid = s.id
    with TestClient(create_app(url)) as client:
        post = client.get(f"/api/sessions/{sid}/posterior").json()
        query = client.get(f"/api/sessions/{sid}/query").json()
        trials = client.get(f"/api/sessions/{sid}/trials").json()
    assert post["recommended"]["made"] is False
    assert [g["made"] for g in query["actions"] + query["buffer"]] == [True, True]
    assert [t["gait"]["made"] for t in trials] == [True]


def test_show_json_and_the_export_say_whether_the_best_is_made(tmp_path: Path) -> None:
    """``session show --json``'s and the manifest's posterior carry ``recommended_made`` and
    ``argmax_made``, and the confidence table ``made``: the console API's fact, from
    ``Session.gait_made``."""
    import csv
    import json

    from gaitpref.sessions.export import export_session

    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with Session.create(url, parse_config(CONTINUOUS), "S01") as s:
        q = s.next_query()
        s.answer(q.id, [], [(q.actions[0], "step_length", "+big")])  # the best: not made
        best = s.recommended()
        assert best is not None and s.gait_made(best) is False
        argmax = s.posterior().argmax
        export_session(s, tmp_path / "out", "csv")
        sid = s.id
    out = runner.invoke(app, ["session", "show", str(sid), "--no-figure", "--json", "--db", url])
    assert out.exit_code == 0, out.output
    shown = json.loads(out.output)["posterior"]
    assert shown["recommended"] == best and shown["recommended_made"] is False
    with Session.open(url, sid) as s:
        assert shown["argmax_made"] is s.gait_made(argmax)
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text(encoding="utf-8"))
    assert manifest["posterior"]["recommended_made"] is False
    with (tmp_path / "out" / "confidence.csv").open(newline="", encoding="utf-8") as f:
        (row,) = list(csv.DictReader(f))  # the one answer's row
    assert row["action"] == str(best) and row["made"] == "false"


def test_a_walked_best_is_made_in_show_json(tmp_path: Path) -> None:
    import json

    url = f"sqlite:///{tmp_path / 'lab.db'}"
    with Session.create(url, parse_config(CONTINUOUS), "S01") as s:
        _compare_only(s, 3)  # the best is a point a query proposed
        sid = s.id
        rows = s.confidence_history()
    out = runner.invoke(app, ["session", "show", str(sid), "--no-figure", "--json", "--db", url])
    assert out.exit_code == 0, out.output
    assert json.loads(out.output)["posterior"]["recommended_made"] is True
    assert rows and rows[-1]["made"] is True
