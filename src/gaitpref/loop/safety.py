"""The gaits a loop may propose: a region of avoidance and the operator's "unsafe" flags.

ROIAL (Li, Tucker et al., ICRA 2021): with ordinal ratings, the gaits expected to be rated in the
avoided (worst) categories form the *region of avoidance*; its complement, the *region of
interest*, is

    ROI = { a : mu_a + lambda * sd_a >= t_avoid }

where ``t_avoid`` is the threshold just above the avoided categories (``t_1`` when only the worst
is avoided) and ``lambda`` a confidence: a gait is avoided only when even its upper bound lies
below ``t_avoid``.  Besides, a trial the operator flagged "unsafe" removes its gait and every
gait within ``unsafe_radius`` of it (Euclidean, each feature scaled to ``[0, 1]`` by its range)
from every future query.  No strategy proposes outside :meth:`Safety.allowed`; when it is empty
the loop raises :class:`~gaitpref.errors.NoSafeGaitError` and proposes nothing.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gaitpref.model.ordinal import Ordinal
from gaitpref.model.posterior import Posterior
from gaitpref.space import Space

BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class Safety:
    """``avoid`` worst categories (0: no region of avoidance), its confidence ``lam`` and the
    radius around gaits flagged unsafe (a fraction of each feature's range)."""

    avoid: int = 0
    lam: float = 1.0
    unsafe_radius: float = 0.0

    def __post_init__(self) -> None:
        if isinstance(self.avoid, bool) or not isinstance(self.avoid, int) or self.avoid < 0:
            raise ValueError(f"avoid must be a number of categories >= 0, got {self.avoid!r}")
        if not (np.isfinite(self.lam) and self.lam >= 0):
            raise ValueError(f"lambda must be a finite number >= 0, got {self.lam!r}")
        if not (np.isfinite(self.unsafe_radius) and 0 <= self.unsafe_radius <= 1):
            raise ValueError(f"unsafe_radius must be in [0, 1], got {self.unsafe_radius!r}")

    def threshold(self, ordinal: Ordinal, signal_variance: float) -> float:
        """``t_avoid``: the threshold above the avoided categories."""
        if not 0 < self.avoid < ordinal.size:
            raise ValueError(
                f"avoiding {self.avoid} of {ordinal.size} categories leaves nothing to propose"
            )
        return ordinal.thresholds_for(signal_variance)[self.avoid - 1]

    def allowed(
        self, posterior: Posterior, ordinal: Ordinal | None, unsafe: Collection[int]
    ) -> BoolArray | None:
        """Which actions may be proposed (None: every one, nothing is restricted)."""
        if self.avoid == 0 and not unsafe:
            return None
        mask = np.ones(len(posterior.space), dtype=bool)
        if self.avoid:
            if ordinal is None:
                raise ValueError("a region of avoidance needs the loop's rating scale")
            t = self.threshold(ordinal, posterior.kernel.variance)
            upper = np.asarray(posterior.mean) + self.lam * np.asarray(posterior.std)
            mask &= upper >= t
        if unsafe:
            mask &= ~near(posterior.space, unsafe, self.unsafe_radius)
        return mask


def near(space: Space, centres: Collection[int], radius: float) -> BoolArray:
    """Actions within ``radius`` (features scaled to ``[0, 1]``) of any of ``centres``."""
    points = space.points
    lo, hi = points.min(axis=0), points.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    scaled = (points - lo) / span
    out = np.zeros(len(space), dtype=bool)
    for c in centres:
        d2 = np.sum((scaled - scaled[int(c)]) ** 2, axis=1)
        out |= d2 <= radius**2 * (1 + 1e-12)
        out[int(c)] = True
    return out


__all__ = ["BoolArray", "Safety", "near"]
