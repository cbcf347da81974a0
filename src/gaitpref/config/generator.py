"""``[gaits] generator = "NAME"``: gaits made on demand over ``[space]`` (issue 13, item 4).

A config names a gait generator (``gaitpref.gaits.generator``) instead of a library; the
generator's fixed settings are keys of ``[gaits]`` (``speed`` for ``compass-hzd``),
``max_iterations`` bounds the solver iterations of one gait (every generator is given it; it has
a default since defaults version 0.5, and configs recorded before get ``None``: no budget) and
``avoid_radius`` is the neighbourhood (a fraction of each feature's range, as ``[safety]
unsafe_radius``) that a proposal whose gait cannot be made takes out of every later query;
``max_infeasible`` bounds how many such proposals one ask makes before it stops proposing
(``sessions/gaits.py``)::

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

The generator is built once here to check that it understands the features; gaits/ (SciPy's
optimizers) is imported only when a config names a generator.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

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
    max_infeasible: int = 20

    def make(self, space: Space) -> GaitGenerator:
        """The generator over ``space``'s features."""
        from gaitpref.gaits.generator import make_generator

        return make_generator(self.name, space.names, self.settings)


def parse_generator(gaits: dict[str, Any], space: Space) -> GeneratorSpec:
    """The checked ``[gaits]`` table of a generator config, tried on ``space``."""
    from gaitpref.errors import GaitGeneratorError

    settings = {k: gaits[k] for k in GENERATOR_SETTINGS if gaits[k] is not None}
    spec = GeneratorSpec(
        gaits["generator"], settings, gaits["avoid_radius"], gaits["max_infeasible"]
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


__all__ = ["GENERATOR_SETTINGS", "GeneratorSpec", "parse_generator"]
