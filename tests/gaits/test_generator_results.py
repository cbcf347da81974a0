"""What a gait generator returns is checked before it is cached, logged or shown.

Before, a generator's gait was taken as it came: a feasible gait with NaN coefficients, a
negative or other step length than asked, a delta^2 of 2, a solver message of 100,000
characters or a number, a ``numpy.bool`` verdict were logged as ``gait_made`` and the gait shown
to the subject (or the write failed deep in the storage with 'not storable as JSON' or a
pydantic error).  Each is now a :class:`~gaitpref.errors.GaitGeneratorFaultError` naming the
generator, the gait and what is wrong: nothing is cached or logged, the ask says so, and the
terminal pauses the session.  And :func:`register_generator` no longer replaces a registered
generator silently.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from tests.sessions.gaitkit import CONFIG, NAME, FakeSteps

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.errors import GaitGeneratorError, GaitGeneratorFaultError
from gaitpref.gaits import Gait, GaitCache, GaitGenerator, OnDemandGaits, register_generator
from gaitpref.gaits.generator import generator_names, make_generator
from gaitpref.gaits.on_demand import MAX_GAIT_MESSAGE
from gaitpref.space import FloatArray
from gaitpref.storage import MemoryStorage

BAD: dict[str, tuple[Callable[[Gait], object], str]] = {
    "nan alpha": (
        lambda g: dataclasses.replace(g, alpha=np.full((1, 7), np.nan)),
        "non-finite coefficients",
    ),
    "nan cot": (lambda g: dataclasses.replace(g, cot=float("nan")), "bad cot/delta"),
    "delta 2": (lambda g: dataclasses.replace(g, delta_squared=2.0), "bad cot/delta"),
    "negative step": (lambda g: dataclasses.replace(g, step_length=-0.4), "not a positive one"),
    "other step": (lambda g: dataclasses.replace(g, step_length=0.9), "not the 0.4 asked for"),
    "inf step": (
        lambda g: dataclasses.replace(g, step_length=float("inf")),
        "not a finite number",
    ),
    "residual": (
        lambda g: dataclasses.replace(g, min_normal_force=float("nan")),
        "constraint residuals",
    ),
    "not a gait": (lambda g: "a gait", "it returned a str, not a Gait"),
    "message number": (
        lambda g: dataclasses.replace(g, message=7),  # type: ignore[arg-type]
        "message is a int, not text",
    ),
    "message long": (
        lambda g: dataclasses.replace(g, message="x" * (MAX_GAIT_MESSAGE + 1)),
        f"message has 2,001 characters, more than {MAX_GAIT_MESSAGE}",
    ),
    "message escape": (
        lambda g: dataclasses.replace(g, message="optimal\x1b[2J"),
        "message holds",
    ),
    "numpy bool": (
        lambda g: dataclasses.replace(g, feasible=np.bool_(True)),  # type: ignore[arg-type]
        "feasible is a numpy.bool",
    ),
    "status float": (
        lambda g: dataclasses.replace(g, status=1.5),  # type: ignore[arg-type]
        "status is a float",
    ),
    "alpha shape": (
        lambda g: dataclasses.replace(g, alpha=np.zeros((2, 3))),
        "alpha has shape (2, 3)",
    ),
}


def _spoiled(monkeypatch: pytest.MonkeyPatch, spoil: Callable[[Gait], object]) -> None:
    made = FakeSteps.make

    def make(self: FakeSteps, vector: FloatArray, warm_start: Gait | None = None) -> Gait:
        return spoil(made(self, vector, warm_start))  # type: ignore[return-value]

    monkeypatch.setattr(FakeSteps, "make", make)
    monkeypatch.setattr(FakeSteps, "below", 0.3)


@pytest.mark.parametrize("case", list(BAD))
def test_a_generator_result_unfit_to_use_is_a_fault_and_nothing_is_cached(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, case: str
) -> None:
    spoil, problem = BAD[case]
    _spoiled(monkeypatch, spoil)
    cache = GaitCache(tmp_path)
    gaits = OnDemandGaits(FakeSteps(["step_length"], {}), cache, ranges=[1.0])
    with pytest.raises(GaitGeneratorFaultError, match="unfit to use") as err:
        gaits.get(np.array([0.4]))
    assert problem in str(err.value) and f"generator {NAME!r}" in str(err.value)
    assert gaits.made == [] and list(tmp_path.iterdir()) == []


def test_in_a_session_it_is_never_logged_nor_shown(monkeypatch: pytest.MonkeyPatch) -> None:
    _spoiled(monkeypatch, BAD["nan alpha"][0])
    s = Session.create(MemoryStorage(), parse_config(CONFIG), "S01")
    with pytest.raises(GaitGeneratorFaultError, match="non-finite coefficients"):
        s.next_query()
    assert [e.kind for e in s.events()] == ["created"] and s.pending is None


def test_an_infeasible_gait_at_a_point_no_gait_can_pose_is_still_taken(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A step length of 0 with NaN numbers is how compass-hzd says no gait can be posed."""
    g = make_generator("compass-hzd", ["step_length"], {"speed": 0.2})
    gaits = OnDemandGaits(g, GaitCache(tmp_path), ranges=[0.1])
    made, new = gaits.get(np.array([0.0]))
    assert new and not made.feasible and "no gait can be posed" in made.gait.message


@pytest.mark.parametrize(
    ("name", "said"), [(7, "a int"), ("L" * 201, "201 characters"), ("L\x1b[2J", "U+001B")]
)
def test_a_gait_id_unfit_to_show_is_a_fault(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, name: object, said: str
) -> None:
    monkeypatch.setattr(FakeSteps, "gait_id", lambda self, vector: name)
    gaits = OnDemandGaits(FakeSteps(["step_length"], {}), GaitCache(tmp_path), ranges=[1.0])
    with pytest.raises(GaitGeneratorFaultError, match="named the gait") as err:
        gaits.get(np.array([0.4]))
    assert said in str(err.value) and list(tmp_path.iterdir()) == []


class _Other(GaitGenerator):
    name = "other"

    def __init__(self, features: Sequence[str], settings: Mapping[str, Any]) -> None:
        self.features = tuple(features)


def test_register_generator_refuses_to_replace_a_name_unless_told() -> None:
    """register_generator('compass-hzd', ...) silently replaced the shipped generator for every
    session whose config names it."""
    with pytest.raises(GaitGeneratorError, match="'compass-hzd' is registered already"):
        register_generator("compass-hzd", _Other)
    assert type(make_generator("compass-hzd", ["step_length"], {"speed": 0.2})).__name__ == (
        "CompassHZD"
    )
    register_generator(NAME, FakeSteps)  # the same factory again: harmless
    from gaitpref.gaits import generator as module

    try:
        register_generator("test-other", _Other)
        register_generator("test-other", FakeSteps, replace=True)
        assert isinstance(make_generator("test-other", ["step_length"]), FakeSteps)
    finally:
        module._GENERATORS.pop("test-other", None)
    assert "test-other" not in generator_names()


def test_a_cached_gait_unfit_to_use_is_made_again_not_logged(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A cache file (edited, or written before results were checked) whose gait has a message
    of 3,000 characters was taken as it was, and logged with it."""
    from gaitpref.gaits import CachedGait

    monkeypatch.setattr(FakeSteps, "below", 0.3)
    generator = FakeSteps(["step_length"], {})
    vector = np.array([0.4])
    good = generator.make(vector)
    cache = GaitCache(tmp_path)
    key = generator.key(vector)
    spoiled = dataclasses.replace(good, message="x" * 3000)
    cache.put(CachedGait(key, spoiled, None), generator.document(vector))
    calls = len(FakeSteps.calls)
    made, new = OnDemandGaits(generator, GaitCache(tmp_path), ranges=[1.0]).get(vector)
    assert new and not made.from_cache and made.gait.message == good.message
    assert len(FakeSteps.calls) == calls + 1
