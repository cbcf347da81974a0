"""A line-path session whose config leaves out ``[model] jitter`` runs on (defaults 0.7).

Without a nugget, the prior covariance of the visited points stops being positive definite in
floating point once the subject's choices cluster them (here: near the shortest steps that have
a gait), and every answer after that was refused with ``PriorNotPositiveDefiniteError``: 20 of 20
such sessions stopped within 40 queries under the 0.6 defaults (jitter 0).
"""

from __future__ import annotations

import pytest

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.errors import PriorNotPositiveDefiniteError
from gaitpref.storage import MemoryStorage
from tests.sessions.gaitkit import CONTINUOUS, FakeSteps, prefer_shorter_pairs


def _session(defaults: str) -> Session:
    FakeSteps.below, FakeSteps.calls = 0.3, []
    text = CONTINUOUS.replace("seed = 4", "seed = 28\nn = 2").replace("jitter = 0.0\n", "")
    assert "jitter" not in text  # left to the defaults
    return Session.create(MemoryStorage(), parse_config(text, defaults=defaults), subject="S01")


def test_without_a_jitter_the_0_6_defaults_stop_and_0_7_runs_on() -> None:
    with pytest.raises(PriorNotPositiveDefiniteError, match="increase the kernel's jitter"):
        prefer_shorter_pairs(_session("0.6"), 40, True)
    session = _session("0.7")
    prefer_shorter_pairs(session, 40, True)
    assert len(session.trials()) == 80
