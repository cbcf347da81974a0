"""An ask with gaits made on demand in which the gait generator fails unexpectedly: it raises
something other than gaitpref's own errors (a bug, a ``RuntimeError``, a ``LinAlgError`` from
numpy or scipy), rather than returning an infeasible gait or raising a
:class:`~gaitpref.errors.GaitError`.

Such a fault is a :class:`~gaitpref.errors.GaitGeneratorFaultError` (a ``GaitError``) naming the
generator, the gait and the original error, raised from it; it is handled as a generator's
``GaitError`` is (``sessions/gaits.py``): nothing is logged, the error says so, the next ask
derives the same gaits again and logs exactly what an ask without the fault would have, and the
log alone replays.  Before, the bare exception escaped: no word of which gait or generator, of
what became of the ask, and the terminal runner crashed leaving the session active.
"""

from __future__ import annotations

from io import StringIO
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.errors import GaitError, GaitGeneratorFaultError
from gaitpref.space import FloatArray
from gaitpref.terminal import Terminal
from tests.sessions.gaitkit import (
    CONFIG,
    NAME,
    FakeSteps,
    fail_once,
    from_the_log_alone,
    logged,
    reference_ask,
)

#: step lengths 0.00 .. 0.90 have no gait: an ask finds several before it proposes
MOSTLY_INFEASIBLE = 0.95
BASE = CONFIG.replace("avoid_radius = 0.1\n", "avoid_radius = 0.1\nmax_infeasible = 1000\n")

FAULTS = pytest.mark.parametrize(
    "fault",
    [
        RuntimeError("boom"),
        np.linalg.LinAlgError("Singular matrix"),
        ZeroDivisionError("float division by zero"),
    ],
    ids=["runtime", "linalg", "zerodivision"],
)


@FAULTS
def test_a_generator_fault_part_way_is_named_nothing_is_logged_and_asking_again_logs_the_same(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fault: Exception
) -> None:
    FakeSteps.below = MOSTLY_INFEASIBLE
    config = parse_config(BASE)
    # the same ask without the fault
    reference, expected, made = reference_ask(f"sqlite:///{tmp_path / 'ref.db'}", config)

    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, config, subject="S01")
    failed = fail_once(monkeypatch, 3, fault)
    with pytest.raises(GaitGeneratorFaultError) as caught:
        s.next_query()
    err = caught.value
    assert isinstance(err, GaitError)
    causes = [err.__cause__, err.__cause__.__cause__ if err.__cause__ else None]
    assert fault in causes  # the traceback keeps the generator's own error
    message = str(err)
    # what failed: the generator, the gait, the original error
    assert message.startswith(
        f"the gait generator {NAME!r} failed making gait {failed[0][0]}: "
        f"{type(fault).__name__}: {fault}"
    )
    # and that nothing was lost
    assert "This ask had found 2 gaits before it" in message
    assert "none is logged" in message and "asking again" in message
    assert [e.kind for e in s.events()] == ["created"] and s.pending is None
    assert s.status == "active" and s.infeasible_gaits() == []
    # asking again (the fault does not recur): the same gaits, logged as without the fault
    q = s.next_query()
    assert len(FakeSteps.calls) == made
    assert logged(s) == logged(reference)
    assert (q.loop_id, q.actions, q.points) == (expected.loop_id, expected.actions, expected.points)
    # and the log alone gives the same state, with no gait made again
    again = from_the_log_alone(monkeypatch, url, tmp_path, s.id)
    assert again.pending == q and again.infeasible_gaits() == s.infeasible_gaits()


def test_a_generator_fault_at_the_first_gait_says_nothing_is_logged(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, parse_config(CONFIG), subject="S01")
    failed = fail_once(monkeypatch, 1, RuntimeError("boom"))
    with pytest.raises(GaitGeneratorFaultError) as caught:
        s.next_query()
    message = str(caught.value)
    assert message.startswith(
        f"the gait generator {NAME!r} failed making gait {failed[0][0]}: RuntimeError: boom"
    )
    assert "Nothing is logged" in message and "asking again" in message
    assert [e.kind for e in s.events()] == ["created"]
    q = s.next_query()  # the retry works
    assert s.pending == q and Session.open(url, s.id).pending == q


def test_a_generator_fault_in_the_terminal_is_said_and_the_session_paused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, parse_config(CONFIG), "S01")
    fail_once(monkeypatch, 1, np.linalg.LinAlgError("Singular matrix"))
    out = StringIO()
    Terminal(s, Console(file=out, width=300), read=lambda _: "q").run()
    text = out.getvalue()
    assert "The next gait could not be made: the gait generator" in text
    assert "LinAlgError: Singular matrix" in text and "Paused." in text
    again = Session.open(url, s.id)
    assert again.status == "paused"
    assert [e.kind for e in again.events() if e.kind not in ("paused", "resumed")] == ["created"]


def test_an_interrupt_in_the_generator_is_not_a_fault(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C while a gait is made is not the generator's fault: it passes unchanged, and the
    session, which writes nothing, asks again from its log."""
    s = Session.create(f"sqlite:///{tmp_path / 'lab.db'}", parse_config(CONFIG), "S01")
    fail_once(monkeypatch, 1, KeyboardInterrupt())
    with pytest.raises(KeyboardInterrupt):
        s.next_query()
    assert [e.kind for e in s.events()] == ["created"]
    q = s.next_query()
    assert [e.kind for e in s.events()][-1] == "query_issued" and s.pending == q


@pytest.mark.parametrize("method", ["gait_id", "document"])
def test_a_fault_in_the_generators_other_methods_is_named_too(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, method: str
) -> None:
    """A generator of one's own may fail outside ``make``: naming or describing a gait."""
    url = f"sqlite:///{tmp_path / 'lab.db'}"
    s = Session.create(url, parse_config(CONFIG), subject="S01")
    original = getattr(FakeSteps, method)

    def broken(self: FakeSteps, vector: FloatArray) -> object:
        raise TypeError("unsupported operand")

    monkeypatch.setattr(FakeSteps, method, broken)
    with pytest.raises(GaitGeneratorFaultError) as caught:
        s.next_query()
    message = str(caught.value)  # the key is the document's hash: both fail naming the gait
    assert message.startswith(f"the gait generator {NAME!r} failed naming the gait of (")
    assert "TypeError: unsupported operand" in message and "Nothing is logged" in message
    assert [e.kind for e in s.events()] == ["created"]
    monkeypatch.setattr(FakeSteps, method, original)
    assert s.next_query() == Session.open(url, s.id).pending
