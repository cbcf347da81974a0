"""An ask with gaits made on demand cut short part-way, after it found gaits:

- by the gait generator's error: not logged (a ``query_stopped`` cannot say why, and replay
  could not re-derive where it ends; ``sessions/gaits.py``), the error says how many gaits the
  ask had found, and the next ask derives the same gaits again, from the gait cache, and logs
  exactly what an ask without the failure would have;
- on the line path by lines too short for the query's ``n`` (``ShortLinesError``): logged as an
  ask that ran out (``query_stopped``, ``infeasible`` under ``limit``), replayed from the log.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.errors import (
    GaitError,
    GaitGeneratorError,
    InfeasibleProposalsError,
    NoSafeGaitError,
    ShortLinesError,
)
from gaitpref.sessions.gaits import unlogged_error
from gaitpref.storage import NewEvent
from tests.sessions.gaitkit import (
    CONFIG,
    CONTINUOUS,
    NAME,
    FakeSteps,
    fail_once,
    from_the_log_alone,
    logged,
    reference_ask,
)

#: step lengths 0.00 .. 0.90 have no gait: most of the space
MOSTLY_INFEASIBLE = 0.95

#: the grid, and the line path; no ask stops at the limit before it proposes
PATHS = pytest.mark.parametrize(
    "base",
    [
        CONFIG.replace("avoid_radius = 0.1\n", "avoid_radius = 0.1\nmax_infeasible = 1000\n"),
        CONTINUOUS.replace("avoid_radius = 0.1\n", "avoid_radius = 0.1\nmax_infeasible = 1000\n"),
    ],
    ids=["grid", "line"],
)


@PATHS
def test_an_ask_the_generator_cuts_short_is_not_logged_and_asking_again_logs_the_same_gaits(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, base: str
) -> None:
    FakeSteps.below = MOSTLY_INFEASIBLE
    config = parse_config(base)
    # the same ask without a failure
    reference, expected, made = reference_ask(f"sqlite:///{tmp_path / 'ref.db'}", config)

    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, config, subject="S01")
    failed = fail_once(monkeypatch, 3, GaitGeneratorError("solver crashed"))
    with pytest.raises(GaitGeneratorError) as caught:
        s.next_query()
    # the operator learns what became of the two gaits found before it; nothing is logged
    message = str(caught.value)
    assert message.startswith("solver crashed.  This ask had found 2 gaits before it")
    assert "none is logged" in message and "in the gait cache" in message
    assert [e.kind for e in s.events()] == ["created"] and s.pending is None
    assert len(FakeSteps.calls) == 2
    # asking again: the two from the cache, the failed one made again, then as the reference
    q = s.next_query()
    assert len(FakeSteps.calls) == made
    assert FakeSteps.calls[2][0] == failed[0][1]
    assert logged(s) == logged(reference)
    assert (q.loop_id, q.actions, q.points) == (expected.loop_id, expected.actions, expected.points)
    # and the log alone gives the same state, with no gait made again
    again = from_the_log_alone(monkeypatch, url, tmp_path, s.id)
    assert again.pending == q and again.infeasible_gaits() == s.infeasible_gaits()


def test_a_generator_error_before_any_gait_is_raised_as_it_is(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    s = Session.create(f"sqlite:///{tmp_path / 'lab.db'}", parse_config(CONFIG), subject="S01")
    fail_once(monkeypatch, 1, GaitGeneratorError("solver crashed"))
    with pytest.raises(GaitGeneratorError, match=r"^solver crashed$"):
        s.next_query()
    assert [e.kind for e in s.events()] == ["created"]


def test_the_unlogged_error_keeps_the_generators_class_where_it_can() -> None:
    events = [
        NewEvent("gait_infeasible", {"gait_id": "G1"}),
        NewEvent("gait_infeasible", {"gait_id": "G1"}),  # proposed again: one gait
        NewEvent("gait_made", {"gait_id": "G2"}),
    ]
    out = unlogged_error(GaitGeneratorError("solver crashed."), events)
    assert type(out) is GaitGeneratorError
    assert str(out).startswith("solver crashed.  This ask had found 2 gaits before it (1 that")

    class CodedError(GaitError):
        def __init__(self, code: int) -> None:
            super().__init__(f"code {code}")

    other = unlogged_error(CodedError(7), events)
    assert type(other) is GaitError and str(other).startswith("code 7.  This ask had found 2")


#: the line path over two discrete features: a line snaps to few of their values, and with the
#: seed, after two proposals the ask finds only lines that hold fewer than n = 4 points
SHORT_LINES = f"""
name = "short-lines"
[space.step_length]
values = [0.0, 0.25, 0.5, 0.75, 1.0]
[space.step_width]
values = [0.2, 0.25, 0.3]
[gaits]
generator = "{NAME}"
avoid_radius = 0.5
[model]
lengthscale = 0.2
signal_variance = 0.005
noise = 0.02
jitter = 0.0
fit = "fixed"
[cospar]
seed = 53
strategy = "self-sparring"
subspace = "line"
n = 4
line_points = 8
line_count = 1
"""


def test_an_ask_left_with_only_short_lines_logs_the_gaits_it_found(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The loop's "none of the lines tried holds n points" after gaits found infeasible: the
    ask wrote nothing (its gaits in the cache only) and the loop's ValueError reached the
    operator; it is the ask running out, and is logged as such."""
    FakeSteps.below = 0.6
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, parse_config(SHORT_LINES), subject="S01")
    with pytest.raises(NoSafeGaitError) as caught:
        s.next_query()
    err = caught.value
    assert not isinstance(err, InfeasibleProposalsError)
    assert "3 gaits that cannot be made" in str(err)
    assert "holds fewer than the query's n = 4 points" in str(err)
    assert "a smaller [cospar] n" in str(err)
    kinds = [e.kind for e in s.events()]
    found = ["gait_made", "gait_infeasible"] * 2 + ["gait_infeasible"]
    assert kinds == ["created", *found, "query_stopped"]
    assert s.events()[-1].payload == {"infeasible": 3, "limit": 20}
    logged = [e.payload["gait_id"] for e in s.events() if e.kind == "gait_infeasible"]
    assert [g.gait_id for g in s.infeasible_gaits()] == logged and s.pending is None
    # asking again, nothing changed: the loop refuses at once; nothing written, nothing made
    made = len(FakeSteps.calls)
    with pytest.raises(ShortLinesError, match="none of the 12 lines tried holds n = 4 points") as e:
        s.next_query()
    # no gait may be proposed: the terminal pauses and the console answers 409 as for any
    # NoSafeGaitError (a ValueError too, as before it had a class)
    assert isinstance(e.value, NoSafeGaitError) and isinstance(e.value, ValueError)
    assert [e.kind for e in s.events()] == kinds and len(FakeSteps.calls) == made
    # a reload says the stop again from the log
    with pytest.raises(NoSafeGaitError, match="holds fewer than the query's n = 4"):
        s.next_query(retry=False)
    # the log alone gives the same state (no gait made again); replay checks the stop
    again = from_the_log_alone(monkeypatch, url, tmp_path, s.id)
    assert again.infeasible_gaits() == s.infeasible_gaits() and again.pending is None
    with pytest.raises(NoSafeGaitError, match="holds fewer than the query's n = 4"):
        again.next_query(retry=False)
