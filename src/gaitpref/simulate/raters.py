"""Simulated raters: a subject who rates each executed gait in ordinal categories.

As ROIAL's simulations: the category boundaries sit at quantiles of the objective over the grid
(``quantiles = (0.25, 0.5, 0.75)``: four categories, the worst a quarter of the gaits), and the
rater sees the normalised utility through Gaussian noise ``noise`` (ordinal noise: near a
boundary the rating is a coin flip).  With ``noise = 0`` the rating is the true category.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from gaitpref.feedback import Rating
from gaitpref.simulate.users import objective_on_grid
from gaitpref.space import FloatArray, Space


@dataclass
class OrdinalRater:
    """Rates actions ``1..K`` (``K = len(quantiles) + 1``) from ``objective`` on ``space``."""

    space: Space
    objective: FloatArray
    quantiles: Sequence[float]
    rng: np.random.Generator
    noise: float = 0.0  # on the normalised objective (0 worst gait, 1 best)
    minimize: bool = False
    boundaries: FloatArray = field(init=False, repr=False)
    utility: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        q = np.asarray(self.quantiles, dtype=np.float64)
        if q.ndim != 1 or q.size < 1 or np.any((q <= 0) | (q >= 1)) or np.any(np.diff(q) <= 0):
            raise ValueError(f"quantiles must increase strictly inside (0, 1), got {q.tolist()}")
        if not (np.isfinite(self.noise) and self.noise >= 0):
            raise ValueError(f"noise must be a finite number >= 0, got {self.noise!r}")
        grid = objective_on_grid(self.space, self.objective)
        utility = -grid if self.minimize else grid
        lo, hi = float(utility.min()), float(utility.max())
        self.utility = (utility - lo) / (hi - lo if hi > lo else 1.0)
        self.boundaries = np.quantile(self.utility, q)

    @property
    def categories(self) -> int:
        return int(self.boundaries.size) + 1

    def rate(self, action: int) -> int:
        """The rating of ``action``: ``1`` (worst) to ``K``."""
        seen = float(self.utility[action])
        if self.noise > 0:
            seen += self.noise * float(self.rng.standard_normal())
        return 1 + int(np.searchsorted(self.boundaries, seen, side="right"))

    def rate_all(self, actions: ArrayLike) -> list[Rating]:
        """One rating per distinct action, in order."""
        out: list[Rating] = []
        for a in dict.fromkeys(int(x) for x in np.asarray(actions).reshape(-1)):
            out.append(Rating(a, self.rate(a)))
        return out


__all__ = ["OrdinalRater"]
