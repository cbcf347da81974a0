"""Simulated users: answers from an objective over the grid, and the paper's coactive rule.

- :class:`SimulatedUser` prefers the action with the higher objective (lower with ``minimize``),
  breaks exact ties at random and, with ``noise > 0``, answers like a probit subject:
  ``P(i preferred) = Phi((f_i - f_j) / (sqrt(2) noise))``.  It compares every executed action with
  every other query member once (the paper's ``R``: ``n x (n + b)`` without repeated pairs, a gait
  not against itself), the pairs a session's operator is asked (:attr:`Query.compared`).
- :class:`GradientCoactive` is the paper's simulated coactive feedback (Section "Optimizing
  Synthetic Two-Dimensional Functions"; ``docs/results/large-6d/README.md``, "Setting"):
  the gradient by ``numpy.gradient`` over the grid (second-order central differences inside,
  first-order at the edges, in grid-index units); per feature, thresholds at the 50th and 75th
  percentiles of ``|gradient|``; on the feature with the largest ``|gradient|`` component, no
  feedback below its 50th percentile, the big move above its 75th, else the small move, in the
  direction of improvement.  Moves are the space's coactive fractions (see
  ``configs/synthetic-2d.toml``: 2 and 3 cells of 30, the paper's 5% and 10%).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy.special import ndtr

from gaitpref.checks import is_number
from gaitpref.feedback import Comparison, Outcome, Suggestion
from gaitpref.loop.cospar import Query
from gaitpref.space import FloatArray, Move, Space


def objective_on_grid(space: Space, objective: ArrayLike) -> FloatArray:
    """The objective as a flat array over the grid (shaped like the grid or already flat)."""
    arr = np.asarray(objective, dtype=np.float64)
    if arr.shape not in (space.shape, (len(space),)):
        flat = (len(space),)  # a 1-D grid's shape: it said 'needs (15,) or (15,)'
        needs = f"{space.shape}" if space.shape == flat else f"{space.shape} or {flat}"
        raise ValueError(f"objective has shape {arr.shape}; the grid needs {needs}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("objective values must be finite")
    return arr.reshape(-1).copy()


def check_user_noise(noise: float) -> float:
    """A simulated subject's probit noise: a finite number ``>= 0`` (0: noiseless), else a
    ValueError (checked before a sweep's runs, as well as by each user)."""
    if not (is_number(noise) and np.isfinite(noise) and noise >= 0):
        raise ValueError(f"noise must be a finite number >= 0, got {noise!r}")
    return float(noise)


@dataclass
class SimulatedUser:
    """Answers queries from ``objective`` (higher is better unless ``minimize``)."""

    space: Space
    objective: FloatArray
    rng: np.random.Generator
    minimize: bool = False
    noise: float = 0.0
    utility: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.objective = objective_on_grid(self.space, self.objective)
        self.utility = -self.objective if self.minimize else self.objective
        check_user_noise(self.noise)
        if not isinstance(self.rng, np.random.Generator):
            raise TypeError(
                f"rng must be a numpy.random.Generator (numpy.random.default_rng(seed)), "
                f"got {self.rng!r}"
            )

    def normalized(self, actions: ArrayLike) -> FloatArray:
        """``(f - worst) / (best - worst)`` of actions: 1 at the optimum, 0 at the worst."""
        lo, hi = float(self.utility.min()), float(self.utility.max())
        span = hi - lo if hi > lo else 1.0
        return (self.utility[self.space.check_indices(actions)] - lo) / span

    def compare(self, i: int, j: int) -> Outcome:
        """Which of ``i`` and ``j`` this user prefers."""
        diff = self.utility[self.space.check_index(i)] - self.utility[self.space.check_index(j)]
        if self.noise > 0:
            p_first = float(ndtr(diff / (np.sqrt(2.0) * self.noise)))
            return "first" if self.rng.random() < p_first else "second"
        if diff == 0:
            return "first" if self.rng.random() < 0.5 else "second"
        return "first" if diff > 0 else "second"

    def answer(self, query: Query) -> list[Comparison]:
        """Every executed action against every other member of the query, each pair once.

        A pair of grid actions is compared once even when an action appears twice in the query
        (``n >= 3`` can draw the same argmax twice): the loop accepts each pair once.
        """
        return [Comparison(i, j, self.compare(i, j)) for i, j in query_pairs(query)]


def query_pairs(query: Query) -> list[tuple[int, int]]:
    """The pairs a simulated user compares: those the query asks (:attr:`Query.compared`, the
    terminal's and the console's rule), every executed action against every other member, each
    pair of actions once (the loop accepts each pair once), a gait not against itself."""
    return list(query.compared)


@dataclass
class GradientCoactive:
    """The paper's gradient-threshold coactive feedback over ``objective``."""

    space: Space
    objective: FloatArray
    minimize: bool = False
    gradient: FloatArray = field(init=False, repr=False)
    thresholds: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        grid = objective_on_grid(self.space, self.objective).reshape(self.space.shape)
        if self.minimize:
            grid = -grid
        grads = np.gradient(grid) if grid.ndim > 1 else [np.gradient(grid)]
        if any(n < 2 for n in self.space.shape):
            raise ValueError("coactive gradients need at least 2 values per feature")
        self.gradient = np.stack([g.reshape(-1) for g in grads], axis=1)  # A x d
        self.thresholds = np.percentile(np.abs(self.gradient), [50, 75], axis=0)  # 2 x d

    def suggest_all(self, actions: Sequence[int]) -> list[Suggestion]:
        """Suggestions for a query's executed ``actions`` (an action drawn twice gets one)."""
        out = []
        for a in dict.fromkeys(actions):
            s = self.suggest(a)
            if s is not None:
                out.append(s)
        return out

    def suggest(self, action: int) -> Suggestion | None:
        """The suggestion for an executed ``action``, or None (none given, or it would clip)."""
        g = self.gradient[self.space.check_index(action)]
        k = int(np.argmax(np.abs(g)))
        mag = abs(g[k])
        if mag <= self.thresholds[0, k]:
            return None
        size = "big" if mag > self.thresholds[1, k] else "small"
        move: Move = f"{'+' if g[k] > 0 else '-'}{size}"  # type: ignore[assignment]
        name = self.space.features[k].name
        if self.space.coactive_move(action, name, move) is None:
            return None
        return Suggestion(action, name, move)
