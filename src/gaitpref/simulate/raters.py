"""Simulated raters: a subject who rates each executed gait in ordinal categories.

As ROIAL's simulations: the category boundaries sit at quantiles of the objective over the grid
(``quantiles = (0.25, 0.5, 0.75)``: four categories, the worst a quarter of the gaits), and the
rater sees the normalised utility through Gaussian noise ``noise`` (ordinal noise: near a
boundary the rating is a coin flip).  With ``noise = 0`` the rating is the true category.

Ties: a gait whose utility lies exactly on a boundary goes to the category that holds the middle
of its block of equal values (the gaits sharing that utility, by rank, in ``np.quantile``'s
positions ``rank / (A - 1)``): the upper one when that middle is at or above the boundary's
quantile, else the lower.  A gait alone on a boundary is its own middle, so it goes up, as
before; a plateau of equal values at the bottom of the objective is rated worst, one at the top
best (before, every tie went up: a bottom plateau was never rated worst), and a flat objective,
every gait tied, is rated in one middle category (the position 0.5: category 2 of 3, 3 of 4;
before, all of it in the best).  A flat objective with ``noise > 0`` is refused: its normalised
scale (0 worst gait, 1 best) does not exist, and the noise would rate it worst or best at random.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from gaitpref.feedback import Rating
from gaitpref.simulate.users import objective_on_grid
from gaitpref.space import FloatArray, Space


@dataclass
class OrdinalRater:
    """Rates actions ``1..K`` (``K = len(quantiles) + 1``) from ``objective`` on ``space``;
    a utility on a boundary (ties) by the rule in this module's docstring."""

    space: Space
    objective: FloatArray
    quantiles: Sequence[float]
    rng: np.random.Generator
    noise: float = 0.0  # on the normalised objective (0 worst gait, 1 best)
    minimize: bool = False
    boundaries: FloatArray = field(init=False, repr=False)
    utility: FloatArray = field(init=False, repr=False)
    _sorted: FloatArray = field(init=False, repr=False)
    _q: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        q = np.asarray(self.quantiles, dtype=np.float64)
        if q.ndim != 1 or q.size < 1 or np.any((q <= 0) | (q >= 1)) or np.any(np.diff(q) <= 0):
            raise ValueError(f"quantiles must increase strictly inside (0, 1), got {q.tolist()}")
        if not (np.isfinite(self.noise) and self.noise >= 0):
            raise ValueError(f"noise must be a finite number >= 0, got {self.noise!r}")
        grid = objective_on_grid(self.space, self.objective)
        utility = -grid if self.minimize else grid
        lo, hi = float(utility.min()), float(utility.max())
        if hi == lo and self.noise > 0:
            raise ValueError(
                f"objective: the same at every gait ({lo!r}), so it has no normalised scale "
                f"(0 worst gait, 1 best) for noise {self.noise!r} to blur, and the noise would "
                "rate every gait worst or best at random; give noise = 0 (a flat objective is "
                "then rated in one middle category) or an objective that varies"
            )
        self.utility = (utility - lo) / (hi - lo if hi > lo else 1.0)
        self.boundaries = np.quantile(self.utility, q)
        self._sorted = np.sort(self.utility)
        self._q = q

    @property
    def categories(self) -> int:
        return int(self.boundaries.size) + 1

    def category(self, seen: float) -> int:
        """The category (``1`` worst to ``K``) of the normalised utility ``seen``, noiseless:
        above the boundaries below it; on a boundary, by the middle of the block of gaits
        whose utility is ``seen`` (the module's docstring)."""
        below = int(np.searchsorted(self.boundaries, seen, side="left"))  # boundaries < seen
        on = int(np.searchsorted(self.boundaries, seen, side="right")) - below
        if not on:
            return 1 + below
        first = int(np.searchsorted(self._sorted, seen, side="left"))  # ranks of the block
        last = int(np.searchsorted(self._sorted, seen, side="right")) - 1
        if last < first:  # no gait has this utility (a noisy value): up, as before
            return 1 + below + on
        span = max(self._sorted.size - 1, 1)
        middle = (first + last) / (2 * span)  # np.quantile's position of the block's middle
        return 1 + below + int(np.count_nonzero(self._q[below : below + on] <= middle))

    def true_categories(self) -> NDArray[np.intp]:
        """Every gait's category without noise (what ``rate`` gives with ``noise = 0``)."""
        return np.array([self.category(float(u)) for u in self.utility], dtype=np.intp)

    def rate(self, action: int) -> int:
        """The rating of ``action``: ``1`` (worst) to ``K``."""
        seen = float(self.utility[action])
        if self.noise > 0:
            seen += self.noise * float(self.rng.standard_normal())
        return self.category(seen)

    def rate_all(self, actions: ArrayLike) -> list[Rating]:
        """One rating per distinct action, in order."""
        out: list[Rating] = []
        for a in dict.fromkeys(int(x) for x in np.asarray(actions).reshape(-1)):
            out.append(Rating(a, self.rate(a)))
        return out


__all__ = ["OrdinalRater"]
