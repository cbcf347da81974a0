"""User text the console shows or draws: feature names, units, labels, notes and reasons.

Each test is a defect an operator hit: a unit ``$\\foo$`` made every figure of the session a
422 (matplotlib read it as mathtext), a feature named ``Schrittlänge`` could not be given a
suggestion, ...
"""

from __future__ import annotations

from importlib import resources

import pytest
from fastapi.testclient import TestClient

from tests.console.conftest import answer_once

EXO_1D = (resources.files("gaitpref.config") / "shipped" / "exo-1d-step-length.toml").read_text(
    encoding="utf-8"
)


def _session(client: TestClient, config: str) -> int:
    r = client.post("/api/sessions", json={"config": config, "subject": "S01"})
    assert r.status_code == 201, r.text
    return int(r.json()["id"])


@pytest.mark.parametrize("unit", ["$\\\\foo$", "$x", "$x$", "m$"])
def test_a_unit_with_dollar_signs_is_drawn_as_text(client: TestClient, unit: str) -> None:
    sid = _session(client, EXO_1D.replace('unit = "m"', f'unit = "{unit}"'))
    answer_once(client, sid)
    for figure in ("figure.png", "posterior.png"):
        r = client.get(f"/sessions/{sid}/{figure}")
        assert r.status_code == 200, r.text
        assert r.content.startswith(b"\x89PNG")
