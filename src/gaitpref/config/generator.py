"""``[gaits] generator = "NAME"``: gaits made on demand over ``[space]`` (issue 13, item 4).

A config names a gait generator (``gaitpref.gaits.generator``) instead of a library; the
generator's fixed settings are keys of ``[gaits]`` (``speed`` for ``compass-hzd``),
``max_iterations`` bounds the solver iterations of one gait (every generator is given it; it has
a default since defaults version 0.5, and configs recorded before get ``None``: no budget) and
``avoid_radius`` is the neighbourhood (a fraction of each feature's range, as ``[safety]
unsafe_radius``) that a proposal whose gait cannot be made takes out of every later query;
``max_infeasible`` bounds how many such proposals one ask makes before it stops proposing
(``sessions/gaits.py``), and their product, the solver iterations one ask may spend on gaits
that cannot be made, is at most :data:`~gaitpref.config.schema.MAX_ASK_ITERATIONS`;
``recommend`` says which gaits a session may recommend (``"made"``, the default since defaults
version 0.13: the best gait it made; ``"any"``: the best point of the model, as before)::

    [space.step_length]
    min = 0.08
    max = 0.18
    num = 11

    [gaits]
    generator = "compass-hzd"
    speed = 0.2
    avoid_radius = 0.05
    max_iterations = 60
    max_infeasible = 20
    recommend = "made"

The generator is built once here to check that it understands the features; gaits/ (SciPy's
optimizers) is imported only when a config names a generator.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from gaitpref.config.schema import DEFAULT_MAX_INFEASIBLE, MAX_ASK_ITERATIONS, RECOMMEND
from gaitpref.config.specs import fail
from gaitpref.space import Space

if TYPE_CHECKING:
    from gaitpref.gaits.generator import GaitGenerator

#: ``[gaits]`` keys that are a generator's fixed settings (passed to its factory when not None;
#: ``max_iterations`` has a default, so every generator is given it and may ignore it).
GENERATOR_SETTINGS = ("speed", "max_iterations")


@dataclass(frozen=True)
class GeneratorSpec:
    """The generator a config names, its fixed settings and the infeasible neighbourhood."""

    name: str
    settings: dict[str, Any] = field(default_factory=dict)
    avoid_radius: float = 0.0
    max_infeasible: int = DEFAULT_MAX_INFEASIBLE
    #: ``[gaits] recommend``: "made", a session recommends the best gait it made (defaults 0.13
    #: on), or "any", the best point of the model, made or not (``sessions/confidence.py``)
    recommend: str = "made"

    def __post_init__(self) -> None:
        if self.recommend not in RECOMMEND:
            raise ValueError(
                f"recommend must be one of {', '.join(RECOMMEND)}, got {self.recommend!r}"
            )

    @property
    def recommends_made(self) -> bool:
        """Whether the recommendation is restricted to the gaits made (``recommend = "made"``)."""
        return self.recommend == "made"

    def make(self, space: Space) -> GaitGenerator:
        """The generator over ``space``'s features."""
        from gaitpref.gaits.generator import make_generator

        return make_generator(self.name, space.names, self.settings)


def check_ask_cost(max_iterations: int | None, max_infeasible: int) -> None:
    """Refuse ``[gaits] max_iterations x max_infeasible`` past :data:`MAX_ASK_ITERATIONS`: the
    solver iterations one ask may spend on gaits that cannot be made (each key alone is bounded;
    10,000 x 1,000 was about a day of solver time for one ask).  ``max_iterations = None`` (a
    session recorded under defaults before 0.5, which had no ``max_infeasible`` either, so 20)
    leaves each gait to the generator's own bound and is not checked.  Like the other checks of
    :func:`~gaitpref.config.new.check_new` it is made for a new session or run only: a session
    stored under an earlier release with a larger product reopens and replays as it ran."""
    if max_iterations is None:
        return
    iterations = max_iterations * max_infeasible
    if iterations > MAX_ASK_ITERATIONS:
        fail(
            "gaits",
            "max_infeasible",
            f"max_iterations x max_infeasible is {max_iterations:,} x {max_infeasible:,} = "
            f"{iterations:,} solver iterations one ask may spend on gaits that cannot be made; "
            f"at most {MAX_ASK_ITERATIONS:,} are allowed (about 10 ms each with compass-hzd): "
            "lower [gaits] max_iterations or max_infeasible",
        )


def check_units(spec: GeneratorSpec, space: Space) -> None:
    """Refuse a ``[space.F] unit`` that is not the unit the generator reads ``F`` in
    (:meth:`~gaitpref.gaits.generator.GaitGenerator.units`; an empty unit is taken as it): the
    generator takes a point's values as they are, so ``step_length`` from 4 to 16 with ``unit =
    "cm"`` asked ``compass-hzd`` for steps of 4 to 16 m, which it could not pose, and a duration
    in ms for steps of minutes.  Made for a new session or run only (:func:`check_ask_cost`)."""
    units = spec.make(space).units()
    for feature in space:
        want = units.get(feature.name)
        if want is not None and feature.unit not in ("", want):
            fail(
                f"space.{feature.name}",
                "unit",
                f"[gaits] generator {spec.name!r} reads {feature.name} in {want!r}, got "
                f"{feature.unit!r}: give min and max (or values) in {want} with unit = "
                f"{want!r}",
            )


def parse_generator(gaits: dict[str, Any], space: Space) -> GeneratorSpec:
    """The checked ``[gaits]`` table of a generator config, tried on ``space``."""
    from gaitpref.errors import GaitGeneratorError

    settings = {k: gaits[k] for k in GENERATOR_SETTINGS if gaits[k] is not None}
    spec = GeneratorSpec(
        gaits["generator"],
        settings,
        gaits["avoid_radius"],
        gaits["max_infeasible"],
        gaits["recommend"],
    )
    try:
        generator = spec.make(space)
    except GaitGeneratorError as exc:
        fail("gaits", "generator", str(exc))
    first = [f.values[0] for f in space]
    for k, feature in enumerate(space):
        if feature.continuous:  # its points' ids carry a content hash (gaits/on_demand.py)
            continue
        ids = set()
        for value in feature.values:
            point = list(first)
            point[k] = value
            ids.add(generator.gait_id(point))  # type: ignore[arg-type]
        if len(ids) != len(feature):
            fail(
                f"space.{feature.name}",
                None,
                f"values too close to give distinct gait ids (ids show {generator.name}'s "
                "rounding)",
            )
    return spec


__all__ = [
    "GENERATOR_SETTINGS",
    "GeneratorSpec",
    "check_ask_cost",
    "check_units",
    "parse_generator",
]
