"""Schemathesis fuzzing of the JSON API from its OpenAPI schema: valid and invalid requests
generated from the schema never get a 500, and a refused request (4xx) writes nothing."""

from __future__ import annotations

import atexit
import shutil
import tempfile
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import schemathesis
from hypothesis import HealthCheck, settings
from schemathesis import GenerationMode

from gaitpref.console import create_app
from gaitpref.console.service import SessionService

_ROOT = Path(tempfile.mkdtemp(prefix="gaitpref-fuzz-"))
atexit.register(shutil.rmtree, _ROOT, True)  # also when the module's tests are deselected
APP = create_app(f"sqlite:///{_ROOT / 'fuzz.db'}")
SERVICE: SessionService = APP.state.service
schema = schemathesis.openapi.from_asgi("/openapi.json", APP)
schema.config.generation.update(modes=[GenerationMode.POSITIVE, GenerationMode.NEGATIVE])


def _seed() -> None:
    """Session 1 with a few answers and an open query; session 2 with a validation open."""
    for k in (1, 2):
        session = SERVICE.create("exo-1d-step-length", f"S0{k}")
        for _ in range(3):
            q = session.next_query()
            pairs = [(q.actions[0], b, "first") for b in q.buffer]
            session.answer(q.id, pairs, [])
        if k == 2:
            session.start_validation()
        else:
            session.next_query()


_seed()


STATUSES: Counter[int] = Counter()
#: generated ids folded onto the ids that exist, so that requests reach real sessions and queries
_FOLD = {"session_id": 3, "query_id": 24, "trial": 5, "round_": 2}


@pytest.fixture(scope="module", autouse=True)
def _cleanup() -> Iterator[None]:
    yield
    SERVICE.close()
    shutil.rmtree(_ROOT, ignore_errors=True)
    # the fuzzing reached the sessions: successes and every kind of refusal were seen
    assert {200, 404, 409, 422} <= set(STATUSES), STATUSES


def _fold(case: schemathesis.Case[Any]) -> None:
    params = case.path_parameters or {}
    for name, size in _FOLD.items():
        value = params.get(name)
        if isinstance(value, int) and not isinstance(value, bool) and value > 0:
            params[name] = value % size + 1
    body = case.body
    query_id = body.get("query_id") if isinstance(body, dict) else None
    if isinstance(body, dict) and isinstance(query_id, int) and query_id > 0:
        body["query_id"] = query_id % _FOLD["query_id"] + 1


def _snapshot() -> list[tuple[int, int, str]]:
    return [(r.id, r.last_seq, r.status) for r in SERVICE.storage.list_sessions()]


@schema.parametrize()
@settings(
    max_examples=25,
    deadline=None,
    derandomize=True,
    suppress_health_check=list(HealthCheck),
    database=None,
)
def test_no_server_error_and_no_write_when_refused(case: schemathesis.Case[Any]) -> None:
    _fold(case)
    before = _snapshot()
    response = case.call()
    STATUSES[response.status_code] += 1
    assert response.status_code < 500, (case.method, case.path, response.text[:500])
    if response.status_code >= 400:
        assert _snapshot() == before, f"{case.method} {case.formatted_path} was refused but wrote"
