"""One-dimensional subspaces through the current best point: LineBO / LineCoSpar lines.

LineBO (Kirschner et al., ICML 2019, Algorithm 1) restricts each acquisition to a line
``{x_best + t v}`` through the current best point, with a random direction ``v`` (or a
coordinate direction, CoordinateLineBO); LineCoSpar (Tucker et al., IROS 2020, Section III-B)
does the same for preference feedback and discretises the line into a fixed number of points.
Here directions live in range-normalised coordinates ``u_f = (x_f - min_f) / (max_f - min_f)``
so no feature dominates by its units; the line is clipped to the box ``[0, 1]^d`` and
discretised into ``points`` equally spaced values of ``t`` (plus ``t = 0``, the best point
itself).  Each feature is then snapped (:meth:`gaitpref.space.Feature.snap`): a discrete
feature to its nearest grid value, a continuous one only clipped.  A direction that leaves the
box at once both ways from an origin on its boundary is folded into it (:func:`entering`;
``LineSettings.boundary = "fold"``, the default since config defaults 0.11; ``"clip"`` keeps
such a line to its origin, as every line was drawn before).

Directions: ``"random"`` (uniform on the sphere), ``"coordinate"`` (one feature chosen at
random) or ``"coactive"`` (from the last executed point towards the point the user's coactive
suggestions point to, else random).  The suggestions are the last answer's that the model keeps
(``LineSettings.coactive = "kept"``, the default since config defaults 0.12): those of a trial
excluded since no longer steer the line; ``"recorded"`` takes every suggestion recorded with the
answer, excluded or not, as every line was drawn before (``loop/line.py``).

``lines`` > 1 draws a *star* of lines through the same origin: the first with the direction
rule, the others random directions, the query chosen among all their points (a union of
one-dimensional subspaces, as LineBO's Algorithm 1 allows any low-dimensional subspace; the
posterior on it is the same restriction of the full model).  One line is LineCoSpar's rule.

``cloud`` > 0 adds that many points around the origin to the query's candidates (a *cloud*):
Gaussian steps in normalised coordinates with standard deviations :data:`CLOUD_SCALES` (the
points split evenly among them), clipped to the box and snapped, drawn from the line's seed
after the star's directions.  Lines through the best point reach far along few directions; the
cloud looks a short way in many (a screen on issue 13's 12-D random-GP cells,
``docs/results/continuous/notes.md``).

Every line takes its own seed, drawn from the loop's generator, so the log can name it.  When
every point of a line is excluded (avoided, near a gait flagged unsafe, in the region of
avoidance) the loop draws another, at most :data:`LINE_DRAWS` lines per query in all
(:func:`redraw_rule`, ``loop/line.py``).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Literal, get_args

import numpy as np

from gaitpref.checks import is_count
from gaitpref.space import FloatArray, Space

Direction = Literal["random", "coordinate", "coactive"]
DIRECTIONS: tuple[Direction, ...] = get_args(Direction)
Boundary = Literal["fold", "clip"]
BOUNDARIES: tuple[Boundary, ...] = get_args(Boundary)
#: which of the last answer's coactive suggestions give the ``"coactive"`` direction: those the
#: model keeps (an excluded trial's taken out), or every one recorded (before defaults 0.12)
CoactiveSource = Literal["kept", "recorded"]
COACTIVE_SOURCES: tuple[CoactiveSource, ...] = get_args(CoactiveSource)

#: the most lines one query draws (:func:`redraw_rule`): while every point of the lines drawn is
#: excluded, four with the configured rule through the best point (the first with the coactive
#: direction, the others without it, which would give the same line again), four random
#: directions through it (a coordinate rule has one line per feature; from a best point on the
#: box's boundary a line covers only the half of its directions that enter the box), then four
#: random directions through random points (the best point may sit where every line is excluded)
LINE_DRAWS = 12
#: the most lines one query's star holds (``LineSettings.lines``)
MAX_LINES = 64
#: the most points a query's lines hold together (``lines x points``): the posterior over the
#: table and the star is a dense matrix over them (one line of 4096 points, as before stars)
MAX_STAR_POINTS = 4096
#: the standard deviations of a cloud's steps around the origin (normalised coordinates)
CLOUD_SCALES = (0.05, 0.1, 0.2)


@dataclass(frozen=True)
class LineSettings:
    """How the line path draws its subspaces: points per line and the direction rule."""

    points: int = 50
    direction: Direction = "random"
    lines: int = 1
    cloud: int = 0
    boundary: Boundary = "fold"
    coactive: CoactiveSource = "kept"

    def __post_init__(self) -> None:
        if self.coactive not in COACTIVE_SOURCES:
            raise ValueError(
                "line coactive source must be one of "
                f"{', '.join(COACTIVE_SOURCES)}; got {self.coactive!r}"
            )
        if self.boundary not in BOUNDARIES:
            raise ValueError(
                f"line boundary must be one of {', '.join(BOUNDARIES)}; got {self.boundary!r}"
            )
        if not is_count(self.cloud) or not 0 <= self.cloud <= MAX_STAR_POINTS:
            raise ValueError(
                f"a query's cloud holds 0 to {MAX_STAR_POINTS} points, got cloud = {self.cloud!r}"
            )
        object.__setattr__(self, "cloud", int(self.cloud))
        if not is_count(self.points) or self.points < 2:
            raise ValueError(f"a line needs at least 2 points, got points = {self.points!r}")
        if not is_count(self.lines) or not 1 <= self.lines <= MAX_LINES:
            raise ValueError(
                f"lines per query must be an integer from 1 to {MAX_LINES}, got {self.lines!r}"
            )
        object.__setattr__(self, "points", int(self.points))  # a NumPy integer as an int
        object.__setattr__(self, "lines", int(self.lines))
        total = self.lines * self.points + self.cloud
        if total > MAX_STAR_POINTS:
            cloud = f" and a cloud of {self.cloud}" if self.cloud else ""
            raise ValueError(
                f"{self.lines} lines of {self.points} points{cloud} are {total} points a query, "
                f"more than {MAX_STAR_POINTS}: fewer lines or fewer points"
                + (" or cloud points" if self.cloud else "")
            )
        if self.direction not in DIRECTIONS:
            raise ValueError(
                f"line direction must be one of {', '.join(DIRECTIONS)}; got {self.direction!r}"
            )


@dataclass(frozen=True)
class Line:
    """One drawn subspace: its seed, origin and unit direction (normalised coordinates) and
    its points in the features' units (``k x d``, distinct; in order of ``t``, line by line).
    A star of lines (``LineSettings.lines`` > 1) has the other lines' directions in
    ``others``, its points those of every line, the first line's first."""

    seed: int
    origin: tuple[float, ...]
    direction: tuple[float, ...]
    points: FloatArray = field(repr=False)
    others: tuple[tuple[float, ...], ...] = ()

    def to_json(self) -> dict[str, object]:
        out: dict[str, object] = {
            "seed": self.seed,
            "origin": list(self.origin),
            "direction": list(self.direction),
            "points": self.points.tolist(),
        }
        if self.others:
            out["others"] = [list(v) for v in self.others]
        return out


def _spans(space: Space) -> tuple[FloatArray, FloatArray]:
    lo = np.array([f.values[0] for f in space.features])
    span = np.array([f.span for f in space.features])
    return lo, span


def random_point(space: Space, rng: np.random.Generator) -> FloatArray:
    """A point drawn uniformly from the box, snapped to the features' grids."""
    lo, span = _spans(space)
    u = rng.uniform(size=space.ndim)
    return np.array([f.snap(v) for f, v in zip(space.features, lo + u * span, strict=True)])


def direction(
    space: Space, rule: Direction, rng: np.random.Generator, towards: FloatArray | None = None
) -> FloatArray:
    """A unit direction in normalised coordinates (zero on single-valued features).

    ``towards`` (normalised coordinates) is the coactive direction; it is used by ``"coactive"``
    when it is given and not zero.
    """
    _, span = _spans(space)
    free = span > 0
    if not free.any():
        raise ValueError("every feature has a single value: there is no line to draw")
    if rule == "coactive" and towards is not None and np.any(towards[free] != 0):
        v = np.where(free, towards, 0.0)
    elif rule == "coordinate":
        v = np.zeros(space.ndim)
        v[int(rng.choice(np.flatnonzero(free)))] = 1.0
    else:
        v = np.where(free, rng.standard_normal(space.ndim), 0.0)
    out: FloatArray = v / np.linalg.norm(v)
    return out


def _t_range(u0: FloatArray, v: FloatArray) -> tuple[float, float]:
    """The ``t`` for which ``u0 + t v`` stays in the box ``[0, 1]^d``."""
    t_lo, t_hi = -np.inf, np.inf
    for u, vj in zip(u0, v, strict=True):
        if vj > 0:
            t_lo, t_hi = max(t_lo, -u / vj), min(t_hi, (1 - u) / vj)
        elif vj < 0:
            t_lo, t_hi = max(t_lo, (1 - u) / vj), min(t_hi, -u / vj)
    return float(t_lo), float(t_hi)


#: how near (range-normalised) a point is on the box's boundary, and how short a line through
#: it is no line, for :func:`entering`: a point a line ended at lies a few roundings inside the
#: box, not on it, and a line through it that leaves the box both ways is as short as those
ON_BOUNDARY = 1e-6


def entering(space: Space, origin: FloatArray, v: FloatArray) -> FloatArray:
    """``v``, unless the line ``origin + t v`` leaves the box at once both ways (the origin on
    the box's boundary, ``v`` pointing out of it on one feature for ``t > 0`` and on another for
    ``t < 0``): then ``v`` folded into the box, each component on a feature where the origin
    sits at its minimum made positive and at its maximum negative.

    From a point on the boundary of ``d`` features a random direction enters the box with
    probability ``2 / 2^d`` only; the line was then the origin alone, and the loop proposed the
    buffered gait again (a discrete feature's extreme values are on the boundary: on 12 features
    of 3 values, 18 of 30 trials repeated the trial before).  Folding keeps a random direction
    uniform among those that enter the box (the standard normal is symmetric in each sign).
    "On the boundary" and "at once" are within :data:`ON_BOUNDARY`: a line's end point lies a
    rounding inside the box, and a line through it that leaves the box both ways within a
    millionth of the range holds only points that snap to it (one in two did, before)."""
    lo, span = _spans(space)
    u0 = (origin - lo) / np.where(span > 0, span, 1.0)
    t_lo, t_hi = _t_range(u0, v)
    if t_lo < -ON_BOUNDARY or t_hi > ON_BOUNDARY:
        return v
    sign = np.where(u0 <= ON_BOUNDARY, 1.0, np.where(u0 >= 1.0 - ON_BOUNDARY, -1.0, np.sign(v)))
    out: FloatArray = np.where(span > 0, np.abs(v) * sign, 0.0)
    return out


def line_points(space: Space, origin: FloatArray, v: FloatArray, count: int) -> FloatArray:
    """``count`` points of the line ``origin + t v`` across the box, plus the origin, snapped;
    repeats (from snapping) removed, in order of ``t``."""
    lo, span = _spans(space)
    safe = np.where(span > 0, span, 1.0)
    u0 = (origin - lo) / safe
    t_lo, t_hi = _t_range(u0, v)
    ts = np.union1d(np.linspace(min(t_lo, 0.0), max(t_hi, 0.0), count), [0.0])
    raw = lo + (u0[None, :] + ts[:, None] * v[None, :]) * span
    snapped = _snapped(space, raw)
    snapped[ts == 0.0] = origin  # exactly the best point, not a rounding of it
    return _distinct(snapped)


def cloud_points(
    space: Space, origin: FloatArray, count: int, rng: np.random.Generator
) -> FloatArray:
    """``count`` points around ``origin``: steps of :data:`CLOUD_SCALES` (normalised), clipped
    to the box and snapped; none on single-valued features."""
    lo, span = _spans(space)
    u0 = (origin - lo) / np.where(span > 0, span, 1.0)
    k = len(CLOUD_SCALES)
    sizes = [count // k + (j < count % k) for j in range(k)]
    steps = np.vstack(
        [
            rng.normal(0.0, scale, (n, space.ndim))
            for scale, n in zip(CLOUD_SCALES, sizes, strict=True)
        ]
    )
    raw = lo + np.clip(u0 + np.where(span > 0, steps, 0.0), 0.0, 1.0) * span
    return _snapped(space, raw).reshape(count, space.ndim)


def _snapped(space: Space, raw: FloatArray) -> FloatArray:
    """Each row of ``raw`` (``k x d``) snapped feature by feature as
    :meth:`~gaitpref.space.Feature.snap` does, the same floats: a continuous feature's column
    at once, ``min(max(x, lo), hi)`` as Python takes them (``lo`` only where it is greater,
    ``hi`` only where it is less), a discrete one's value by value.  A NaN goes to
    ``Feature.snap``, row by row, for its error."""
    if raw.ndim != 2 or raw.shape[0] == 0 or np.isnan(raw).any():
        return np.array(
            [[f.snap(x) for f, x in zip(space.features, row, strict=True)] for row in raw]
        )
    out: FloatArray = np.empty(raw.shape)
    for j, f in enumerate(space.features):
        x = raw[:, j]
        if f.continuous:
            low, high = f.values[0], f.values[-1]
            above = np.where(low > x, low, x)
            out[:, j] = np.where(high < above, high, above)
        else:
            out[:, j] = [f.snap(v) for v in x.tolist()]
    return out


def _distinct(rows: FloatArray) -> FloatArray:
    """``rows`` without repeats, each kept where it first appears."""
    _, first = np.unique(rows, axis=0, return_index=True)
    out: FloatArray = rows[np.sort(first)]
    return out


def draw_line(
    space: Space,
    settings: LineSettings,
    seed: int,
    origin: FloatArray | None,
    towards: FloatArray | None = None,
) -> Line:
    """The line of seed ``seed`` through ``origin`` (a random point when None); with
    ``settings.lines`` > 1, the star of that many lines through it (the others random
    directions, drawn after the first from the same seed); with ``settings.cloud``, that many
    points around it too (:func:`cloud_points`, drawn last)."""
    rng = np.random.default_rng(seed)
    start = random_point(space, rng) if origin is None else np.asarray(origin, dtype=np.float64)
    v = direction(space, settings.direction, rng, towards)
    others = [direction(space, "random", rng) for _ in range(settings.lines - 1)]
    if settings.boundary == "fold":  # no random numbers: the draws are as before
        v = entering(space, start, v)
        others = [entering(space, start, w) for w in others]
    points = line_points(space, start, v, settings.points)
    if others:
        rest = (line_points(space, start, w, settings.points) for w in others)
        points = _distinct(np.vstack([points, *rest]))
    if settings.cloud:
        points = _distinct(np.vstack([points, cloud_points(space, start, settings.cloud, rng)]))
    points.setflags(write=False)
    return Line(
        seed,
        tuple(start.tolist()),
        tuple(v.tolist()),
        points,
        tuple(tuple(w.tolist()) for w in others),
    )


def redraw_rule(settings: LineSettings, draw: int) -> tuple[LineSettings, bool]:
    """The rule of a query's ``draw``-th line (0: the first, the configured one; see
    :data:`LINE_DRAWS`), and whether it passes through the best point (else a random point)."""
    if draw < LINE_DRAWS // 3:
        return settings, True
    return replace(settings, direction="random"), draw < 2 * LINE_DRAWS // 3


def normalised(space: Space, delta: FloatArray) -> FloatArray:
    """A difference of points in normalised coordinates (per feature's range)."""
    _, span = _spans(space)
    out: FloatArray = np.where(span > 0, delta / np.where(span > 0, span, 1.0), 0.0)
    return out


__all__ = [
    "BOUNDARIES",
    "CLOUD_SCALES",
    "COACTIVE_SOURCES",
    "DIRECTIONS",
    "LINE_DRAWS",
    "MAX_LINES",
    "MAX_STAR_POINTS",
    "ON_BOUNDARY",
    "Boundary",
    "CoactiveSource",
    "Direction",
    "Line",
    "LineSettings",
    "cloud_points",
    "direction",
    "draw_line",
    "entering",
    "line_points",
    "normalised",
    "random_point",
    "redraw_rule",
]
