"""A quick stand-in gait generator for tests of gaits on demand (no optimisation).

``FakeSteps`` makes a "gait" over a ``step_length`` feature (and any labels) at once: feasible
when the step length is at least ``FakeSteps.below`` (a class setting a test may change), and it
records every call with the step length of its warm start, so tests can see what was made and
from where (and :func:`never_made`, patched in, that nothing is).  :func:`logged_as_version_1`
copies a session as gaitpref wrote it before the log carried the gaits; :func:`copied` copies
one with its events edited.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pytest

from gaitpref import Session
from gaitpref.config import ExperimentConfig
from gaitpref.gaits import Gait, GaitGenerator, register_generator
from gaitpref.sessions import SessionQuery
from gaitpref.space import FloatArray
from gaitpref.storage import EventRecord, NewEvent, SessionSpec, Storage

NAME = "test-steps"


class FakeSteps(GaitGenerator):
    name: ClassVar[str] = NAME
    below: ClassVar[float] = 0.3
    calls: ClassVar[list[tuple[float, float | None]]] = []  # (step length, warm start's)

    def __init__(self, features: Sequence[str], settings: Mapping[str, Any]) -> None:
        self.features = tuple(features)
        self.k = self.features.index("step_length")

    def settings(self) -> dict[str, Any]:
        return {"below": self.below}

    def parameters(self, vector: FloatArray) -> dict[str, float]:
        return {"step_length": float(self.check(vector)[self.k])}

    def gait_id(self, vector: FloatArray) -> str:
        return "-".join(
            f"{n[0].upper()}{v:.3f}" for n, v in zip(self.features, vector, strict=True)
        )

    def make(self, vector: FloatArray, warm_start: Gait | None = None) -> Gait:
        length = self.parameters(vector)["step_length"]
        FakeSteps.calls.append((length, None if warm_start is None else warm_start.step_length))
        ok = length >= self.below
        return Gait(
            step_length=length,
            step_duration=1.0,
            alpha=np.full((1, 7), length),
            phase_start=-0.1,
            phase_end=0.1,
            orbit_state=np.zeros(4),
            cot=(length - 0.5) ** 2,
            delta_squared=0.9,
            feasible=ok,
            status=0 if ok else 8,
            message="optimal: fake" if ok else f"infeasible: step length {length:.3f} too short",
            min_normal_force=100.0,
            max_friction_ratio=0.1,
        )


register_generator(NAME, FakeSteps)


def never_made(self: object, vector: FloatArray, warm_start: Gait | None = None) -> Gait:
    """A generator's ``make`` for a test that no gait is made (monkeypatch it in)."""
    raise AssertionError(f"the gait of {vector} was made again")


def prefer_short_steps(s: Session, queries: int) -> None:
    """Answer ``queries`` queries as a subject who prefers the shorter step (on a grid or the
    line path): drives the loop towards the short steps, which have no gait."""
    for _ in range(queries):
        q = s.next_query()
        a, b = q.actions[0], (q.buffer[0] if q.buffer else None)
        if b is None or b == a:
            s.answer(q.id, [])
            continue
        shorter = q.points[0][0] < s.space.points[b][0]
        s.answer(q.id, [(a, b, "first" if shorter else "second")])


def paired_line_session(storage: Storage, seed: int, jitter: float | None = None) -> Session:
    """A session of :data:`CONTINUOUS` (the line path) with ``seed`` and two gaits per query;
    ``jitter``: the model's (None: the config's 0, under which some seeds' visited points stop
    being positive definite, as before defaults 0.7).  One line per query (``line_count = 1``,
    the default before defaults 0.10): the seeds the tests name reach their cases with it."""
    from gaitpref.config import parse_config

    text = CONTINUOUS.replace("seed = 4", f"seed = {seed}\nn = 2\nline_count = 1")
    if jitter is not None:
        text = text.replace("jitter = 0.0", f"jitter = {jitter!r}")
    return Session.create(storage, parse_config(text), subject="S01")


def prefer_shorter_pairs(s: Session, queries: int, suggest: bool) -> None:
    """Answer ``queries`` two-gait queries as a subject who prefers the shorter step (and, with
    ``suggest``, asks for a shorter one still): drives the proposals into the steps that have
    no gait."""
    for _ in range(queries):
        q = s.next_query()
        a, b = q.actions
        shorter = "first" if q.points[0][0] < q.points[1][0] else "second"
        suggestions = [(a, "step_length", "-small")] if suggest else []
        s.answer(q.id, [] if a == b else [(a, b, shorter)], suggestions)


GAIT_EVENTS = ("gait_made", "gait_infeasible")


def copied(
    storage: Storage, session_id: int, edit: Callable[[EventRecord], NewEvent | None]
) -> int:
    """A new session in ``storage`` with the spec and events of ``session_id``, each event as
    ``edit`` gives it (None: as it is); the copy's id."""
    rec = storage.get_session(session_id)
    spec = SessionSpec(
        rec.subject, rec.config_name, rec.config_text, rec.config_sha256, rec.seed,
        rec.software_version, dict(rec.meta),
    )  # fmt: skip
    events = [
        edit(e) or NewEvent(e.kind, e.payload, e.at, e.version) for e in storage.events(session_id)
    ]
    return storage.create_session(spec, events, rec.status).id


def from_the_log_alone(
    monkeypatch: pytest.MonkeyPatch, url: str, folder: Path, session_id: int
) -> Session:
    """The session reopened with no gait cache (``lab.db.gaits`` in ``folder`` removed) and a
    generator that makes nothing (:func:`never_made`): every gait must come from the log."""
    monkeypatch.setattr(FakeSteps, "make", never_made)
    shutil.rmtree(folder / "lab.db.gaits")
    return Session.open(url, session_id)


def logged_as_version_1(storage: Storage, session_id: int) -> int:
    """A copy of the session whose gait events are as gaitpref wrote them before they carried
    their gait: payload version 1, the same fields but ``gait``; the copy's id."""

    def old(e: EventRecord) -> NewEvent | None:
        if e.kind not in GAIT_EVENTS or e.version == 1:
            return None
        return NewEvent(e.kind, {k: v for k, v in e.payload.items() if k != "gait"}, e.at, 1)

    return copied(storage, session_id, old)


CONFIG = f"""
name = "on-demand-1d"
[space.step_length]
min = 0.0
max = 1.0
num = 21
unit = "m"
[space.step_width]
values = [0.2, 0.3]
[gaits]
generator = "{NAME}"
avoid_radius = 0.1
[model]
lengthscale = 0.2
signal_variance = 0.005
noise = 0.02
jitter = 0.0
fit = "fixed"
[cospar]
seed = 4
strategy = "self-sparring"
"""

#: the fake over a continuous step length (the line path) and a continuous width label
CONTINUOUS = (
    CONFIG.replace("num = 21\n", "").replace("values = [0.2, 0.3]", "min = 0.2\nmax = 0.3")
    + "line_points = 12\n"
)

#: the real compass-hzd generator on a grid whose shortest step (0.02 m) has no gait at 0.2 m/s;
#: with its seed, a subject who always prefers the new gait reaches it by the third query
COMPASS = """
name = "compass-on-demand"
[space.step_length]
values = [0.02, 0.04, 0.06, 0.08, 0.10, 0.12, 0.14]
unit = "m"
[gaits]
generator = "compass-hzd"
speed = 0.2
avoid_radius = 0.0
[model]
lengthscale = 0.03
signal_variance = 1e-4
noise = 0.01
jitter = 0.0
fit = "fixed"
[cospar]
strategy = "self-sparring"
seed = 3
"""


def fresh_fake_steps(below: float = 0.3) -> Iterator[None]:
    """The body of an autouse fixture: :class:`FakeSteps` refusing steps under ``below``, with no
    calls recorded, during a test, and back to its defaults after it."""
    FakeSteps.below, FakeSteps.calls = below, []
    yield
    FakeSteps.below, FakeSteps.calls = 0.3, []


def fail_once(
    monkeypatch: pytest.MonkeyPatch, call: int, fault: BaseException
) -> list[tuple[str, float]]:
    """``FakeSteps`` raises ``fault`` at its ``call``-th gait (counted from 1), once; the gait
    id and the step length it was asked for at the failure."""
    make = FakeSteps.make
    count, failed = [0], []

    def failing(self: FakeSteps, vector: FloatArray, warm_start: Gait | None = None) -> Gait:
        count[0] += 1
        if count[0] == call:
            failed.append((self.gait_id(vector), self.parameters(vector)["step_length"]))
            raise fault
        return make(self, vector, warm_start)

    monkeypatch.setattr(FakeSteps, "make", failing)
    return failed


def logged(s: Session) -> list[tuple[str, dict[str, Any]]]:
    """What a session logged after its creation: each event's kind and payload."""
    return [(e.kind, e.payload) for e in s.events() if e.kind != "created"]


def reference_ask(url: str, config: ExperimentConfig) -> tuple[Session, SessionQuery, int]:
    """A session of ``config`` at ``url`` that asked once without a failure: the session, its
    query and the gaits the ask made (at least 4, so that a failure at the 3rd comes part-way);
    ``FakeSteps.calls`` is cleared after it."""
    reference = Session.create(url, config, subject="S01")
    expected = reference.next_query()
    made = len(FakeSteps.calls)
    assert made >= 4, "too few gaits made: a failure would not come part-way"
    FakeSteps.calls.clear()
    return reference, expected, made
