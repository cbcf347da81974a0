"""The gaits a loop may propose: a region of avoidance and the operator's "unsafe" flags.

ROIAL (Li, Tucker et al., ICRA 2021): with ordinal ratings, the gaits expected to be rated in the
avoided (worst) categories form the *region of avoidance*.  Two rules, with ``t_avoid`` the
threshold just above the avoided categories (``t_1`` when only the worst is avoided), the
rating noise ``s`` and the posterior ``f_a ~ N(mu_a, sd_a^2)``:

- ``risk`` (the default): a gait is avoided when the subject is more likely than ``risk`` to
  rate it in an avoided category, the predictive probability of ``model/ordinal.py``

      P(rating_a <= avoid) = Phi((t_avoid - mu_a) / sqrt(s^2 + sd_a^2)) > risk;

  with the thresholds at the prior predictive's quantiles an unrated gait far from the data has
  ``avoid / K`` there, so ``risk`` must exceed it (the default is ``avoid / K + 0.1``): a gait
  is avoided once the ratings make an avoided rating likelier than before any data.
- ``lambda`` (ROIAL's upper bound, given in the config): the region of interest is

      ROI = { a : mu_a + lambda * sd_a >= t_avoid },

  a gait is avoided only when even its upper bound lies below ``t_avoid``: ``P(f_a < t_avoid) >
  Phi(lambda)``, 0.84 for ``lambda = 1``.  With the rating noise as large as the prior's sd (the
  default) a rating moves ``mu_a`` by well under one ``sd_a``, and this rule excludes almost no
  gait within 60 trials (``docs/results/ordinal/``).

With ``risk``, a cautious level (``cautious``, a share in (0, 1), 0.6 in a config since its
defaults version 0.4; SafeOpt's idea of expanding from gaits known to be safe, Sui et al., ICML
2015): with ``p_0`` the probability of an avoided rating at a gait with no data (posterior mean
0, the prior's variance), a gait is *known-safe* when

      P(rating_a <= avoid) <= min(cautious * p_0, risk),

the ratings near it having made an avoided rating at most ``cautious`` times as likely as with
no data (relative to ``p_0``, so that thresholds fitted from only good ratings, which lower every
gait's probability, do not make unexplored gaits known-safe).  While some gait the loop could
propose is known-safe, the loop proposes only known-safe gaits, and an unexplored gait (one the
``risk`` rule allows) only when it might be better than all of them: when its upper bound
``mu_a + explore * sd_a`` exceeds every known-safe gait's.  When no gait is known-safe the
``risk`` rule alone decides.  Gaits the operator declares safe (``start``, the device's nominal
gait: SafeOpt's safe seed) are known-safe from the start, before any rating, unless the ratings
make an avoided rating likelier than ``risk`` there (the ``risk`` rule avoids them); the loop
executes them first (``loop/cospar.py``).  Two settings narrow the exploring step (both off
by default): ``reach``, an unexplored gait only within ``reach`` lengthscales of a known-safe
gait the loop may propose; ``frontier``, only where the ratings have already made an avoided
rating less likely than before any data,

      P(rating_a <= avoid) <= frontier * p_0,

so the proposals grow from the known-safe gaits into gaits the ratings speak for (SafeOpt's
expansion set), never into gaits nothing is known about.  The upper bounds need the variance
of every unexplored gait that the bounds 0 and the prior's leave undecided, often most of them
(``Posterior.variance_many``: information gain's iteration on 57,750 gaits at 300 comparisons
0.47 s, against 0.16 s with ``risk`` alone; ``benchmarks/results/infogain.md``).

Both use the thresholds the posterior's rating scale carries (fitted by the evidence when the
config does not fix them), the ones its Laplace fit used.  Besides, a trial the operator
flagged "unsafe" removes its gait and every gait within ``unsafe_radius`` of it (Euclidean, each
feature scaled to ``[0, 1]`` by its range) from every future query.  No strategy proposes
outside :meth:`Safety.allowed`; when it is empty the loop raises
:class:`~gaitpref.errors.NoSafeGaitError` and proposes nothing (on the line path, when it is
empty on every line the ask draws, ``loop/line.py``).
"""

from __future__ import annotations

from collections.abc import Collection, Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gaitpref.checks import is_count, is_number
from gaitpref.model.ordinal import Ordinal, rating_probabilities
from gaitpref.model.posterior import Posterior
from gaitpref.space import FloatArray, Space

BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class Safety:
    """``avoid`` worst categories (0: no region of avoidance), its rule (``risk``: the largest
    probability of an avoided rating a proposed gait may have; None: ROIAL's upper bound with
    confidence ``lam``) and the radius around gaits flagged unsafe (a fraction of each feature's
    range)."""

    avoid: int = 0
    lam: float = 1.0
    unsafe_radius: float = 0.0
    risk: float | None = None
    cautious: float | None = None
    explore: float = 1.0
    #: gaits the operator declares safe (action indices): executed first, and known-safe for
    #: the cautious level until the ratings say otherwise
    start: tuple[int, ...] = ()
    #: with cautious: unexplored gaits only within ``reach`` lengthscales of a known-safe gait
    #: (None: anywhere)
    reach: float | None = None
    #: with cautious: unexplored gaits only where the ratings have made an avoided rating less
    #: likely than ``frontier`` times an unrated gait's (None: the ``risk`` rule's bound only)
    frontier: float | None = None

    def flag_effect(self, continuous: bool = False) -> str:
        """What an unsafe flag does, as the terminal and the CLI say it after one;
        ``continuous``: the space has a continuous feature, where without a radius a gait
        however close to the flagged one may be proposed (the line path proposed one a few
        hundredths of the ranges away at the next trial)."""
        if self.unsafe_radius == 0 and continuous:
            return (
                "its gait will not be proposed again, but gaits however close to it may be "
                "(unsafe_radius = 0; give [safety] unsafe_radius, a fraction of each feature's "
                "range, to keep them away too)"
            )
        if self.unsafe_radius == 0:
            return "its gait will not be proposed again"
        return (
            f"its gait and the gaits within unsafe_radius = {self.unsafe_radius:g} of it will "
            "not be proposed again"
        )

    def __post_init__(self) -> None:
        if not is_count(self.avoid) or self.avoid < 0:
            raise ValueError(f"avoid must be a number of categories >= 0, got {self.avoid!r}")
        object.__setattr__(self, "avoid", int(self.avoid))
        if not (is_number(self.lam) and np.isfinite(self.lam) and self.lam >= 0):
            raise ValueError(f"lambda must be a finite number >= 0, got {self.lam!r}")
        if not (
            is_number(self.unsafe_radius)
            and np.isfinite(self.unsafe_radius)
            and 0 <= self.unsafe_radius <= 1
        ):
            raise ValueError(f"unsafe_radius must be in [0, 1], got {self.unsafe_radius!r}")
        if self.risk is not None and not (
            is_number(self.risk) and np.isfinite(self.risk) and 0 < self.risk < 1
        ):
            raise ValueError(f"risk must be a probability in (0, 1), got {self.risk!r}")
        if self.cautious is not None:
            if self.risk is None:
                raise ValueError("cautious needs the risk rule (risk), not ROIAL's bound")
            if not (
                is_number(self.cautious) and np.isfinite(self.cautious) and 0 < self.cautious < 1
            ):
                raise ValueError(f"cautious must be a fraction in (0, 1), got {self.cautious!r}")
        if not (is_number(self.explore) and np.isfinite(self.explore) and self.explore >= 0):
            raise ValueError(f"explore must be a finite number >= 0, got {self.explore!r}")
        # read once (a generator was emptied by the check: no start gaits), and an iterable
        # (one index was "'int' object is not iterable")
        iterable = isinstance(self.start, Iterable) and not isinstance(self.start, str | bytes)
        start = tuple(self.start) if iterable else ()
        if not iterable or any(not is_count(a) or a < 0 for a in start):
            raise ValueError(f"start must hold action indices >= 0, got {self.start!r}")
        object.__setattr__(self, "start", tuple(int(a) for a in start))
        if self.reach is not None and not (
            is_number(self.reach) and np.isfinite(self.reach) and self.reach > 0
        ):
            raise ValueError(f"reach must be a number of lengthscales > 0, got {self.reach!r}")
        if self.frontier is not None and not (
            is_number(self.frontier) and np.isfinite(self.frontier) and 0 < self.frontier <= 1
        ):
            raise ValueError(f"frontier must be a share in (0, 1], got {self.frontier!r}")
        if (
            self.frontier is not None
            and self.cautious is not None
            and self.frontier <= self.cautious
        ):
            raise ValueError(
                f"frontier ({self.frontier!r}) must exceed cautious ({self.cautious!r}): a gait "
                "under frontier x an unrated gait's probability is known-safe already, so "
                "nothing would be left to explore"
            )
        if len(set(self.start)) != len(self.start):
            raise ValueError(f"start names a gait twice: {self.start!r}")

    def threshold(self, ordinal: Ordinal, signal_variance: float) -> float:
        """``t_avoid``: the threshold above the avoided categories."""
        if not 0 < self.avoid < ordinal.size:
            raise ValueError(
                f"avoiding {self.avoid} of {ordinal.size} categories leaves nothing to propose"
            )
        return ordinal.thresholds_for(signal_variance)[self.avoid - 1]

    def allowed(
        self,
        posterior: Posterior,
        ordinal: Ordinal | None,
        unsafe: Collection[int],
        within: BoolArray | None = None,
    ) -> BoolArray | None:
        """Which actions may be proposed (None: every one, nothing is restricted).

        ``within``: the actions the loop would propose from besides (a line's points, the
        actions not banned otherwise); the cautious level (``cautious``) applies when one of
        them, away from the unsafe flags, is known-safe.
        """
        if self.avoid == 0 and not unsafe:
            return None
        mask = np.ones(len(posterior.space), dtype=bool)
        if unsafe:
            mask &= ~near(posterior.space, unsafe, self.unsafe_radius)
        if self.avoid:
            mask &= ~self.avoided(posterior, ordinal, mask if within is None else mask & within)
        return mask

    def avoided(
        self, posterior: Posterior, ordinal: Ordinal | None, within: BoolArray | None = None
    ) -> BoolArray:
        """The region of avoidance (module docstring), with the posterior's rating scale (its
        fitted thresholds) or else ``ordinal``; with ``cautious``, while one of ``within``
        (default: every gait) is known-safe (by the ratings, or declared in ``start``), every
        gait neither known-safe nor possibly better than all the known-safe ones.

        Both rules are monotone in the posterior variance, which lies between 0 and the prior's:
        a gait decided alike at both ends needs no variance, and only the others' is computed
        (``O(A m)`` for the means plus ``O(a m^2)`` for ``a`` undecided gaits, not the whole
        grid's ``O(A m^2)``).
        """
        bounds = _Bounds(self, posterior, ordinal)
        if self.cautious is None or self.risk is None:
            return bounds.region(self.risk)
        known, risky = self._known(bounds)
        pool = np.flatnonzero(known if within is None else known & within)
        if not pool.size:
            return risky
        # an unexplored gait only when its upper bound beats every known-safe gait's
        mean, prior, var_of = bounds.mean, bounds.prior, bounds.var_of
        best = float(np.max(mean[pool] + self.explore * np.sqrt(var_of(pool))))
        better = ~risky & ~known & (mean > best)  # above it even with no variance left
        undecided = np.flatnonzero(
            ~risky & ~known & ~better & (mean + self.explore * np.sqrt(prior) > best)
        )
        if undecided.size:
            better[undecided] = mean[undecided] + self.explore * np.sqrt(var_of(undecided)) > best
        if self.reach is not None and better.any():
            better &= _within(posterior, pool, self.reach)
        if self.frontier is not None and better.any():  # where the ratings already speak for it
            ahead = np.flatnonzero(better)
            level = self.frontier * _unrated(bounds, self.avoid)
            better[ahead] = ~bounds.region_of(level, ahead)
        return ~(known | better)

    def known_safe(self, posterior: Posterior, ordinal: Ordinal | None) -> BoolArray | None:
        """The cautious level's known-safe gaits (None without the level): by the ratings, or
        declared in ``start`` and not avoided by the ``risk`` rule."""
        if self.cautious is None or self.risk is None:
            return None
        return self._known(_Bounds(self, posterior, ordinal))[0]

    def _known(self, bounds: _Bounds) -> tuple[BoolArray, BoolArray]:
        """The known-safe gaits and the ``risk`` rule's region (``cautious`` and ``risk`` set)."""
        assert self.cautious is not None and self.risk is not None
        if not bounds.mean.size:  # the line path before its first query: no gait yet
            return np.zeros(0, dtype=bool), np.zeros(0, dtype=bool)
        known = ~bounds.region(min(self.cautious * _unrated(bounds, self.avoid), self.risk))
        risky = bounds.region(self.risk)
        if self.start:  # declared safe: known-safe unless the ratings put them in the region
            declared = np.zeros(known.shape, dtype=bool)
            declared[list(self.start)] = True
            known |= declared & ~risky
        return known, risky

    def _rule(
        self,
        scale: Ordinal,
        v: float,
        t: float,
        mean: FloatArray,
        var: FloatArray,
        risk: float | None,
    ) -> BoolArray:
        """Avoided at posterior ``(mean, var)``: ROIAL's bound (``risk`` None), or the avoided
        ratings' chance above ``risk``."""
        if risk is None:
            out: BoolArray = mean + self.lam * np.sqrt(var) < t
            return out
        probs = rating_probabilities(scale, v, mean, var)
        return np.asarray(probs[:, : self.avoid].sum(axis=1) > risk)


class _Bounds:
    """The posterior's mean, prior variance and lazily computed variances for one region."""

    def __init__(self, safety: Safety, posterior: Posterior, ordinal: Ordinal | None) -> None:
        scale = posterior.ordinal if posterior.ordinal is not None else ordinal
        if scale is None:
            raise ValueError("a region of avoidance needs the loop's rating scale")
        self.safety = safety
        self.posterior = posterior
        self.scale: Ordinal = scale
        self.v = posterior.kernel.variance
        self.t = safety.threshold(scale, self.v)
        self.mean: FloatArray = np.asarray(posterior.mean)
        self.prior: FloatArray = np.asarray(
            posterior.kernel.diagonal(posterior.space), dtype=np.float64
        )
        self.known_var = np.full(self.mean.shape, np.nan)  # posterior variances, computed once

    def var_of(self, actions: NDArray[np.intp]) -> FloatArray:
        todo = np.unique(actions[np.isnan(self.known_var[actions])])
        if todo.size:
            self.known_var[todo] = self.posterior.variance_many(todo)
        out: FloatArray = self.known_var[actions]
        return out

    def region(self, level: float | None) -> BoolArray:
        """The gaits the rule at ``level`` avoids (variances only of the undecided ones)."""
        return self.region_of(level, np.arange(self.mean.size))

    def region_of(self, level: float | None, actions: NDArray[np.intp]) -> BoolArray:
        """Whether the rule at ``level`` avoids each of ``actions`` (variances only of the
        undecided ones)."""
        rule, scale, v, t = self.safety._rule, self.scale, self.v, self.t
        mean, prior = self.mean[actions], self.prior[actions]
        out = rule(scale, v, t, mean, np.zeros_like(mean), level)
        undecided = np.flatnonzero(out != rule(scale, v, t, mean, prior, level))
        if undecided.size:
            out[undecided] = rule(
                scale, v, t, mean[undecided], self.var_of(actions[undecided]), level
            )
        return out


def _unrated(bounds: _Bounds, avoid: int) -> float:
    """``p_0``: the probability of an avoided rating at a gait with no data (mean 0, the prior's
    variance), on the posterior's rating scale."""
    probs = rating_probabilities(bounds.scale, bounds.v, np.zeros(1), bounds.prior[:1])
    return float(probs[0, :avoid].sum())


def _within(posterior: Posterior, centres: NDArray[np.intp], reach: float) -> BoolArray:
    """Gaits within ``reach`` lengthscales (Euclidean, each feature in its lengthscale) of one
    of ``centres``."""
    points = posterior.space.points
    scaled = points / np.asarray(posterior.kernel.lengthscales(points.shape[1]))
    out = np.zeros(len(points), dtype=bool)
    per_chunk = max(1, 2**21 // (len(points) * points.shape[1]))  # ~16 MB of differences
    for chunk in np.array_split(centres, -(-centres.size // per_chunk)):
        d2 = np.sum((scaled[:, None, :] - scaled[None, chunk, :]) ** 2, axis=2)
        out |= np.min(d2, axis=1) <= reach**2
    return out


def default_risk(avoid: int, categories: int) -> float:
    """``avoid / K + 0.1``: avoided once an avoided rating is 0.1 likelier than before any data."""
    return avoid / categories + 0.1


def near(space: Space, centres: Collection[int], radius: float) -> BoolArray:
    """Actions within ``radius`` (each feature scaled to ``[0, 1]`` by its range) of ``centres``.

    The scale is the features' declared ranges, not the spread of the points present: on a point
    set (a line and the visited points) the radius means the same as on the full grid.
    """
    scaled = _scaled(space, space.points)
    out = np.zeros(len(space), dtype=bool)
    for c in centres:
        d2 = np.sum((scaled - scaled[int(c)]) ** 2, axis=1)
        out |= d2 <= radius**2 * (1 + 1e-12)
        out[int(c)] = True
    return out


def near_point(
    space: Space, centres: Collection[int], point: NDArray[np.float64], radius: float
) -> bool:
    """Whether ``point`` (feature values, maybe no longer a row of ``space``) lies within
    ``radius`` of one of ``centres``, scaled as by :func:`near`."""
    if not centres:
        return False
    d2 = np.sum(
        (_scaled(space, space.points[sorted(centres)]) - _scaled(space, point)) ** 2, axis=-1
    )
    return bool(np.any(d2 <= radius**2 * (1 + 1e-12)))


def _scaled(space: Space, points: NDArray[np.float64]) -> NDArray[np.float64]:
    """``points`` with each feature scaled to ``[0, 1]`` by its declared range."""
    lo = np.array([f.values[0] for f in space.features], dtype=np.float64)
    span = np.array([f.span for f in space.features], dtype=np.float64)
    out: NDArray[np.float64] = (points - lo) / np.where(span > 0, span, 1.0)
    return out


__all__ = ["BoolArray", "Safety", "default_risk", "near", "near_point"]
