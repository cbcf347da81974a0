"""A simulated subject who is noisy and sometimes indifferent, as real subjects are.

The ordered-probit subject (``model/likelihood.py``, :class:`~gaitpref.model.likelihood.
OrderedProbit`, is the model of the same behaviour): comparing actions ``i`` and ``j`` the
subject perceives ``y = f_i - f_j + e``, ``e ~ N(0, 2 noise^2)`` (each trial's utility is felt
with noise ``noise``), and answers

- "no preference" when ``|y| < band``;
- the action with the larger perceived utility otherwise.

With ``noise = 0`` and ``band = 0`` this is the paper's noiseless subject (exact ties broken at
random).  Objectives of the paper's synthetic benchmark are GP samples with variance 0.1 (sd
0.32); the study (``docs/results/learning``) uses ``noise = 0.05`` and ``band = 0.05`` on that
scale.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitpref.checks import is_number
from gaitpref.feedback import Outcome
from gaitpref.simulate.users import SimulatedUser


@dataclass
class IndifferentUser(SimulatedUser):
    """A :class:`SimulatedUser` with probit ``noise`` and an indifference ``band``."""

    band: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (is_number(self.band) and np.isfinite(self.band) and self.band >= 0):
            raise ValueError(f"band must be >= 0, got {self.band!r}")

    def compare(self, i: int, j: int) -> Outcome:
        """ "first", "second" or "none" for actions ``i`` and ``j`` (see the module docstring)."""
        perceived = float(self.utility[i] - self.utility[j])
        if self.noise > 0:
            perceived += float(np.sqrt(2.0) * self.noise * self.rng.standard_normal())
        if abs(perceived) < self.band:
            return "none"
        if perceived == 0:
            return "first" if self.rng.random() < 0.5 else "second"
        return "first" if perceived > 0 else "second"
