"""Physical parameters of the planar compass-gait biped (Goswami, Thuilot & Espiau 1998).

Two rigid legs of length ``l`` joined at the hip, point feet, one actuator at the hip.  Masses
are points: ``m_H`` at the hip and ``m`` on each leg at ``b`` from the hip (``a = l - b`` from the
foot).  Defaults are the ones used by Goswami et al. and by Drake's compass gait: ``m_H = 10 kg``,
``m = 5 kg``, ``a = b = 0.5 m``, ``l = 1 m``, ``g = 9.81 m/s^2``.

Notation: all quantities are scalars in SI units.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass


@dataclass(frozen=True)
class CompassGaitParams:
    """Masses (kg), lengths (m) and gravity (m/s^2) of the compass-gait biped."""

    hip_mass: float = 10.0
    leg_mass: float = 5.0
    leg_com: float = 0.5
    leg_length: float = 1.0
    gravity: float = 9.81

    def __post_init__(self) -> None:
        for name, value in asdict(self).items():
            if not isinstance(value, int | float) or not math.isfinite(value) or value <= 0:
                raise ValueError(
                    f"compass-gait parameter {name} must be a positive number, got {value!r}"
                )
        if self.leg_com >= self.leg_length:
            raise ValueError(
                f"leg_com (hip to leg mass, {self.leg_com} m) must be shorter than "
                f"leg_length ({self.leg_length} m)"
            )

    @property
    def foot_to_com(self) -> float:
        """``a = l - b``: distance from the foot to the leg's mass."""
        return self.leg_length - self.leg_com

    @property
    def total_mass(self) -> float:
        """``m_H + 2 m``."""
        return self.hip_mass + 2.0 * self.leg_mass

    def to_dict(self) -> dict[str, float]:
        return {k: float(v) for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, data: Mapping[str, object]) -> CompassGaitParams:
        """Parameters from a mapping with exactly this class's field names."""
        expected = set(cls.__dataclass_fields__)
        given = set(data)
        if given != expected:
            missing, extra = sorted(expected - given), sorted(given - expected)
            raise ValueError(f"model parameters: missing {missing}, unexpected {extra}")
        values: dict[str, float] = {}
        for key in sorted(expected):
            value = data[key]
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"model parameter {key} must be a number, got {value!r}")
            values[key] = float(value)
        return cls(**values)
