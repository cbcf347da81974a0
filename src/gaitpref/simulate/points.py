"""Simulated experiments against an objective over points (grid or line path, issue 13).

The user compares the points of a query by a :data:`~gaitpref.simulate.continuous.PointObjective`
(noiseless, or with probit noise ``noise`` on the utility difference, as
:class:`~gaitpref.simulate.users.SimulatedUser`); the coactive helper is the paper's
gradient-threshold rule on the objective's gradient (central differences in range-normalised
coordinates), its thresholds the 50th and 75th percentiles of ``|gradient|`` per feature over
random points of the box (where the paper takes them over the grid).  The same code runs a
full-grid :class:`~gaitpref.loop.cospar.CoSpar` and a
:class:`~gaitpref.loop.line.LineCoSpar`: both name actions by index into ``loop.space``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.special import ndtr

from gaitpref.feedback import Comparison, Suggestion
from gaitpref.limits import MAX_TRIALS
from gaitpref.loop.cospar import CoSpar, Query
from gaitpref.pointset import PointSet
from gaitpref.simulate.continuous import PointObjective
from gaitpref.simulate.users import check_user_noise, query_pairs
from gaitpref.space import FloatArray, Move, Space


@dataclass
class PointUser:
    """Answers queries by ``objective`` at the actions' points (higher is better)."""

    objective: PointObjective
    rng: np.random.Generator
    noise: float = 0.0

    def __post_init__(self) -> None:
        check_user_noise(self.noise)

    def answer(self, query: Query, space: Space) -> list[Comparison]:
        """Every executed action against every other member of the query, each pair once."""
        members = list(dict.fromkeys(query.members))
        value = dict(
            zip(members, np.asarray(self.objective(space.points_of(members))), strict=True)
        )
        out: list[Comparison] = []
        for i, j in query_pairs(query):
            diff = float(value[i] - value[j])
            if self.noise > 0:
                first = self.rng.random() < float(ndtr(diff / (np.sqrt(2.0) * self.noise)))
            else:
                first = diff > 0 or (diff == 0 and self.rng.random() < 0.5)
            out.append(Comparison(i, j, "first" if first else "second"))
        return out


@dataclass
class PointCoactive:
    """Gradient-threshold coactive suggestions from ``objective`` over ``domain``."""

    objective: PointObjective
    domain: Space
    seed: int = 0
    samples: int = 512
    thresholds: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        rng = np.random.default_rng(self.seed)
        lo, span = self._box()
        pts = lo + rng.uniform(size=(self.samples, self.domain.ndim)) * span
        grads = self.gradient(pts)
        self.thresholds = np.percentile(np.abs(grads), [50, 75], axis=0)

    def _box(self) -> tuple[FloatArray, FloatArray]:
        lo = np.array([f.values[0] for f in self.domain.features])
        return lo, np.array([f.span for f in self.domain.features])

    def gradient(self, points: FloatArray, eps: float = 1e-3) -> FloatArray:
        """Central-difference gradients (per unit of each feature's range), ``m x d``."""
        lo, span = self._box()
        out = np.zeros(points.shape)
        for j in range(self.domain.ndim):
            if span[j] == 0:
                continue
            up, down = points.copy(), points.copy()
            up[:, j] = np.minimum(points[:, j] + eps * span[j], lo[j] + span[j])
            down[:, j] = np.maximum(points[:, j] - eps * span[j], lo[j])
            width = (up[:, j] - down[:, j]) / span[j]
            out[:, j] = (np.asarray(self.objective(up)) - np.asarray(self.objective(down))) / width
        return out

    def suggest_all(self, query: Query, space: Space) -> list[Suggestion]:
        """Suggestions for a query's executed actions (an action drawn twice gets one)."""
        out = []
        for a in dict.fromkeys(query.actions):
            g = self.gradient(space.points_of([a]))[0]
            k = int(np.argmax(np.abs(g)))
            if abs(g[k]) <= self.thresholds[0, k]:
                continue
            size = "big" if abs(g[k]) > self.thresholds[1, k] else "small"
            move: Move = f"{'+' if g[k] > 0 else '-'}{size}"  # type: ignore[assignment]
            name = self.domain.features[k].name
            if isinstance(space, PointSet):
                lands = space.move_target(a, name, move) is not None
            else:
                lands = space.coactive_move(a, name, move) is not None
            if lands:
                out.append(Suggestion(a, name, move))
        return out


@dataclass(frozen=True)
class PointsResult:
    """Per query the executed points and their objective; the final posterior's best point."""

    points: list[list[list[float]]]
    objective: list[list[float]]
    best_point: list[float]
    best_objective: float
    best_at: dict[int, float] = field(default_factory=dict)  # trials -> best point's objective

    @property
    def curve(self) -> FloatArray:
        """The objective of each trial (executed action), in order."""
        return np.array([v for q in self.objective for v in q])

    def to_json(self) -> dict[str, object]:
        return {
            "trials": int(self.curve.size),
            "points": self.points,
            "objective": self.objective,
            "best_point": self.best_point,
            "best_objective": self.best_objective,
            **({"best_objective_at": self.best_at} if self.best_at else {}),
        }


def run_points(
    loop: CoSpar,
    objective: PointObjective,
    user: PointUser,
    trials: int,
    coactive: PointCoactive | None = None,
    progress: Callable[[int], None] | None = None,
    checkpoints: tuple[int, ...] = (),
) -> PointsResult:
    """Run ``loop`` against ``user`` until ``trials`` actions have been executed (at most
    :data:`~gaitpref.limits.MAX_TRIALS`); with ``checkpoints``, also the objective of the
    posterior's best point after those trials."""
    if not 1 <= trials <= MAX_TRIALS:  # every trial runs: 10**12 ran until the memory was full
        raise ValueError(f"trials must be 1 to {MAX_TRIALS}, got {trials}")
    points: list[list[list[float]]] = []
    values: list[list[float]] = []
    best_at: dict[int, float] = {}
    done = 0
    while done < trials:
        query = loop.ask()
        answers = user.answer(query, loop.space)
        suggestions = [] if coactive is None else coactive.suggest_all(query, loop.space)
        loop.tell(query, answers, suggestions)
        executed = loop.space.points_of(query.actions)
        points.append(executed.tolist())
        values.append(np.asarray(objective(executed), dtype=np.float64).tolist())
        done += len(query.actions)
        for c in checkpoints:
            if done - len(query.actions) < c <= done:
                at = loop.space.points_of([loop.posterior.argmax])
                best_at[c] = float(np.asarray(objective(at))[0])
        if progress is not None:
            progress(min(done, trials))
    best = loop.space.points_of([loop.posterior.argmax])
    return PointsResult(
        points, values, best[0].tolist(), float(np.asarray(objective(best))[0]), best_at
    )


def random_curve(
    objective: PointObjective, domain: Space, trials: int, rng: np.random.Generator
) -> FloatArray:
    """The objective of ``trials`` points drawn uniformly from the box (random selection)."""
    lo = np.array([f.values[0] for f in domain.features])
    hi = np.array([f.values[-1] for f in domain.features])
    pts = lo + rng.uniform(size=(trials, domain.ndim)) * (hi - lo)
    snapped = np.array([[f.snap(v) for f, v in zip(domain.features, p, strict=True)] for p in pts])
    out: FloatArray = np.asarray(objective(snapped), dtype=np.float64)
    return out


__all__ = ["PointCoactive", "PointUser", "PointsResult", "random_curve", "run_points"]
