"""Gait generators: a point of a config's space in, an optimised gait out (issue 13, item 4).

The paper ends with "going beyond precomputed gait libraries to generating new gaits".  A
generator makes the gait of one parameter vector when a session first proposes it: the vector is
a float array in the features' units, in the space's feature order, so a grid point and (later) a
point of a continuous space are the same thing to it.  ``compass-hzd`` is the HZD optimisation of
:mod:`gaitpref.gaits.optimize` (the paper's Section "Gait Generation for Bipedal Robots", eqs.
(3)-(5): minimum mechanical COT, Reher et al. 2016 eqs. 17-18) at a fixed forward speed or over a
``step_duration`` feature; a ``step_width`` feature is a label, as in a library (the planar compass
gait has no width).

A generator's :meth:`~GaitGenerator.key` is a SHA-256 of its name, its fixed settings and the
parameters that decide the gait: the content address of the gait in a cache
(:mod:`gaitpref.gaits.gait_cache`).  Generators are registered by name
(:func:`register_generator`); a config names one with ``[gaits] generator = "compass-hzd"``.
"""

from __future__ import annotations

import hashlib
import json
import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping, Sequence
from typing import Any, ClassVar

import numpy as np

from gaitpref.errors import GaitGeneratorError
from gaitpref.gaits.gait import Gait, GaitRequest, HZDSettings
from gaitpref.gaits.library import AXES, gait_id_of
from gaitpref.gaits.optimize import optimize_gait
from gaitpref.gaits.params import CompassGaitParams
from gaitpref.space import FloatArray


class GaitGenerator(ABC):
    """Makes the gait of a parameter vector over ``features`` (names, in the space's order)."""

    name: ClassVar[str]
    features: tuple[str, ...]

    @abstractmethod
    def settings(self) -> dict[str, Any]:
        """The fixed settings (JSON), part of every gait's key."""

    @abstractmethod
    def parameters(self, vector: FloatArray) -> dict[str, float]:
        """The values of ``vector`` that decide its gait (labels left out)."""

    @abstractmethod
    def gait_id(self, vector: FloatArray) -> str:
        """The id shown and logged for the gait of ``vector`` (as a library's)."""

    @abstractmethod
    def make(self, vector: FloatArray, warm_start: Gait | None = None) -> Gait:
        """The gait of ``vector`` (flagged infeasible, with the reason, when there is none)."""

    def units(self) -> dict[str, str]:
        """The unit each feature that decides a gait is read in, by name: a new session refuses
        a ``[space.F] unit`` other than this (an empty unit is taken as this one).  Default:
        none, nothing checked."""
        return {}

    def document(self, vector: FloatArray) -> dict[str, Any]:
        """What decides ``vector``'s gait: the generator's name, settings and the parameters."""
        return {
            "generator": self.name,
            "settings": self.settings(),
            "parameters": self.parameters(vector),
        }

    def key(self, vector: FloatArray) -> str:
        """The content address of ``vector``'s gait: :func:`content_key` of its document."""
        return content_key(self.document(vector))

    def check(self, vector: FloatArray) -> FloatArray:
        arr = np.asarray(vector, dtype=np.float64)
        if arr.shape != (len(self.features),) or not np.all(np.isfinite(arr)):
            raise GaitGeneratorError(
                f"{self.name}: a parameter vector has {len(self.features)} finite values "
                f"({', '.join(self.features)}), got {vector!r}"
            )
        return arr


def content_key(document: Mapping[str, Any]) -> str:
    """SHA-256 of a gait's document (generator, settings, parameters) as sorted, compact JSON."""
    decides = {k: document[k] for k in ("generator", "settings", "parameters")}
    text = json.dumps(decides, sort_keys=True, allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


class CompassHZD(GaitGenerator):
    """The compass gait's minimum-COT HZD gait (:func:`~gaitpref.gaits.optimize_gait`).

    Features: ``step_length`` (m, required), ``step_duration`` (s) or else a fixed ``speed``
    (m/s), and optionally ``step_width`` (a label with no effect on the dynamics).
    ``max_iterations`` bounds the SLSQP iterations of one gait, all starts together (``None``:
    each start may take ``hzd.max_iterations``, as before the budget); it decides verdicts, so
    it is one of the settings in every key, and left out of them when ``None`` (the keys of
    gaits made before it stay what they were).
    """

    name: ClassVar[str] = "compass-hzd"

    def __init__(
        self,
        features: Sequence[str],
        speed: float | None = None,
        params: CompassGaitParams | None = None,
        hzd: HZDSettings | None = None,
        max_iterations: int | None = None,
    ) -> None:
        self.features = tuple(features)
        unknown = [f for f in self.features if f not in AXES]
        if unknown or "step_length" not in self.features:
            raise GaitGeneratorError(
                f"{self.name} makes gaits over {', '.join(AXES)} (step_length required); "
                f"the space has {', '.join(self.features)}"
            )
        timed = "step_duration" in self.features
        if timed == (speed is not None):
            what = (
                f"the step_duration feature times each gait, so speed = {speed!r} has no use: "
                "remove [gaits] speed"
                if timed
                else "give [gaits] speed (m/s) or a step_duration feature"
            )
            raise GaitGeneratorError(
                f"{self.name} needs a fixed speed or a step_duration feature, exactly one "
                f"(features {', '.join(self.features)}): {what}"
            )
        if speed is not None and not (np.isfinite(speed) and speed > 0):
            raise GaitGeneratorError(f"{self.name}: speed must be positive, got {speed!r}")
        if max_iterations is not None and (
            isinstance(max_iterations, bool)
            or not isinstance(max_iterations, int)
            or max_iterations < 1
        ):
            raise GaitGeneratorError(
                f"{self.name}: max_iterations must be an integer >= 1, got {max_iterations!r}"
            )
        self.speed = None if speed is None else float(speed)
        self.max_iterations = max_iterations
        self.params = params or CompassGaitParams()
        self.hzd = hzd or HZDSettings()

    def settings(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "model": self.params.to_dict(),
            "formulation": self.hzd.to_dict(),
            "speed": self.speed,
        }
        if self.max_iterations is not None:
            out["max_iterations"] = self.max_iterations
        return out

    def _values(self, vector: FloatArray) -> dict[str, float]:
        """The vector's values by feature, in the library's axis order."""
        arr = self.check(vector)
        named = {n: float(v) for n, v in zip(self.features, arr, strict=True)}
        return {n: named[n] for n in AXES if n in named}

    def parameters(self, vector: FloatArray) -> dict[str, float]:
        values = self._values(vector)
        values.pop("step_width", None)  # a label: every width shares its gait
        return values

    def gait_id(self, vector: FloatArray) -> str:
        return gait_id_of(self._values(vector), self.speed)

    def units(self) -> dict[str, str]:
        """Metres and seconds (the library's axes); ``step_width`` is a label, in any unit."""
        return {n: AXES[n].unit for n in self.features if n != "step_width"}

    def make(self, vector: FloatArray, warm_start: Gait | None = None) -> Gait:
        p = self.parameters(vector)
        length, duration = p["step_length"], p.get("step_duration")
        reach = 2.0 * self.params.leg_length  # the guard asin(L / 2l) needs 0 < L < 2l
        if not 0.0 < length < reach:
            why = f"step_length {length:g} m is not in (0, {reach:g}) m (twice the leg length)"
            return unposed(length, self.hzd, why)
        if duration is not None and not duration > 0.0:
            return unposed(length, self.hzd, f"step_duration {duration:g} s is not positive")
        try:
            request = GaitRequest(length, step_duration=duration, speed=self.speed)
        except ValueError as exc:
            raise GaitGeneratorError(f"{self.name}: {exc}") from None
        return optimize_gait(
            request,
            self.params,
            self.hzd,
            warm_start=warm_start,
            max_iterations=self.max_iterations,
        )


def unposed(step_length: float, hzd: HZDSettings, why: str) -> Gait:
    """The infeasible gait of a request no optimisation can pose (``why``): nothing solved,
    every number but the step length not a number, ``status`` -1."""
    nan = math.nan
    return Gait(
        step_length=step_length,
        step_duration=nan,
        alpha=np.full((1, hzd.degree + 1), nan),
        phase_start=nan,
        phase_end=nan,
        orbit_state=np.full(4, nan),
        cot=nan,
        delta_squared=nan,
        feasible=False,
        status=-1,
        message=f"infeasible: no gait can be posed: {why}",
        min_normal_force=nan,
        max_friction_ratio=nan,
    )


GeneratorFactory = Callable[[Sequence[str], Mapping[str, Any]], GaitGenerator]


def _compass_hzd(features: Sequence[str], settings: Mapping[str, Any]) -> GaitGenerator:
    extra = sorted(set(settings) - {"speed", "max_iterations"})
    if extra:
        raise GaitGeneratorError(
            f"compass-hzd takes the settings speed and max_iterations only, got {extra}"
        )
    return CompassHZD(
        features, speed=settings.get("speed"), max_iterations=settings.get("max_iterations")
    )


_GENERATORS: dict[str, GeneratorFactory] = {CompassHZD.name: _compass_hzd}


def register_generator(name: str, factory: GeneratorFactory, *, replace: bool = False) -> None:
    """Make ``factory(features, settings)`` available as ``[gaits] generator = name``.

    A name already registered to another factory (``compass-hzd`` included) is refused unless
    ``replace=True``: sessions whose config names it would make their gaits with the new one
    (registering the same factory again is harmless)."""
    if not isinstance(name, str) or not name:
        raise GaitGeneratorError(f"a generator's name is a non-empty string, got {name!r}")
    known = _GENERATORS.get(name)
    if known is not None and known is not factory and not replace:
        raise GaitGeneratorError(
            f"a gait generator {name!r} is registered already; give replace=True to replace it "
            "(sessions whose config names it then make their gaits with the new one)"
        )
    _GENERATORS[name] = factory


def generator_names() -> tuple[str, ...]:
    return tuple(sorted(_GENERATORS))


def make_generator(
    name: str, features: Sequence[str], settings: Mapping[str, Any] | None = None
) -> GaitGenerator:
    """The generator ``name`` over ``features``; :class:`GaitGeneratorError` says what is wrong."""
    factory = _GENERATORS.get(name)
    if factory is None:
        raise GaitGeneratorError(
            f"no gait generator {name!r} (known: {', '.join(generator_names())})"
        )
    return factory(tuple(features), dict(settings or {}))


__all__ = [
    "CompassHZD",
    "GaitGenerator",
    "GeneratorFactory",
    "content_key",
    "generator_names",
    "make_generator",
    "register_generator",
]
