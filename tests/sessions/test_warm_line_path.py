"""A warm start needs the full grid: on the line path (continuous features, as the shipped
``compass-continuous-3d``) the loop takes none.  ``session new --prior-from`` said "answer
refused: ..." (the loop's ``QueryError``), naming no option, and the console's ``POST
/api/sessions`` answered 409, a stale query's status; now a ``PriorFromError`` names
``prior_from`` (CLI "error: prior_from: ...", console 422), before the database is read."""

from __future__ import annotations

from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from gaitpref import Session
from gaitpref.cli import app
from gaitpref.config import parse_config
from gaitpref.console.app import create_app
from gaitpref.errors import PriorFromError
from tests.sessions.gaitkit import CONTINUOUS


def test_a_warm_start_on_the_line_path_is_refused_naming_prior_from(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    config = parse_config(CONTINUOUS)
    with Session.create(url, config, "S01") as s:
        q = s.next_query()
        s.answer(q.id, [])
        earlier = s.id
    with pytest.raises(PriorFromError, match=r"^prior_from: .* runs on the line path"):
        Session.create(url, config, "S02", prior_from=[earlier])
    assert [r.id for r in Session.list_sessions(url)] == [earlier]

    path = tmp_path / "c.toml"
    path.write_text(config.text, encoding="utf-8")
    args = ["session", "new", "--config", str(path), "--subject", "S02", "--db", url]
    out = CliRunner().invoke(app, [*args, "--prior-from", "S01"])
    assert out.exit_code == 2
    assert "answer refused" not in out.output and "prior_from: " in out.output

    with TestClient(create_app(url)) as client:
        body = {"config": config.text, "subject": "S02", "prior_from": [earlier]}
        r = client.post("/api/sessions", json=body)
    assert r.status_code == 422 and "runs on the line path" in r.text
    assert [r.id for r in Session.list_sessions(url)] == [earlier]
