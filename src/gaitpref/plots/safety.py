"""The region of avoidance and the operator's unsafe flags, drawn over a posterior figure.

ROIAL (Li, Tucker et al., ICRA 2021): a gait is in the *region of avoidance* when the subject is
more likely than ``risk`` to rate it in an avoided category (or, with ROIAL's ``lambda``, when
even its upper bound ``mu_a + lambda sd_a`` lies below the threshold above the avoided
categories; ``gaitpref.loop.safety``), and a gait flagged "unsafe" removes itself and every
gait within ``unsafe_radius`` of it (each feature scaled to ``[0, 1]`` by its range).
:func:`safety_shading` computes both masks from a posterior (the same rule the loop uses to keep
gaits out of its queries); :func:`draw_1d` and :func:`draw_2d` shade them on a figure's axes,
with legend entries.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Ellipse, Patch
from numpy.typing import NDArray

from gaitpref.loop.safety import Safety, near
from gaitpref.model.ordinal import Ordinal
from gaitpref.model.posterior import Posterior
from gaitpref.space import FloatArray, IntArray, Space

BoolArray = NDArray[np.bool_]
AVOID_LABEL = "region of avoidance"
NEAR_LABEL = "within the unsafe radius"
FLAG_LABEL = "flagged unsafe"
AVOID_COLOUR = "0.45"
UNSAFE_COLOUR = "#b91c1c"
#: the shadings differ by pattern as well as by colour (a reader without colour vision, a
#: grey print): the region of avoidance hatched one way, the gaits near a flag the other
AVOID_HATCH = "//"
NEAR_HATCH = "\\\\"


@dataclass(frozen=True)
class SafetyShading:
    """What to shade: the avoided gaits, the flagged ones and the gaits near them."""

    avoid: BoolArray  # Safety.avoided (all False without a region of avoidance)
    threshold: float | None  # t_avoid on the utility scale (None: no region of avoidance)
    unsafe: IntArray  # flagged actions
    near: BoolArray  # within unsafe_radius of a flagged action (flagged ones included)
    radius: float  # the unsafe radius, as a fraction of each feature's range

    @property
    def empty(self) -> bool:
        return not self.avoid.any() and self.unsafe.size == 0 and self.threshold is None


def safety_shading(
    posterior: Posterior,
    safety: Safety,
    ordinal: Ordinal | None,
    unsafe: Collection[int] = (),
) -> SafetyShading:
    """The masks a posterior figure shades (the loop's own rule, ``Safety.allowed``)."""
    n = len(posterior.space)
    avoid = np.zeros(n, dtype=bool)
    threshold: float | None = None
    scale = posterior.ordinal if posterior.ordinal is not None else ordinal
    if safety.avoid and scale is not None:
        threshold = float(safety.threshold(scale, posterior.kernel.variance))
        avoid = safety.avoided(posterior, scale)
    flagged = np.asarray(sorted({int(a) for a in unsafe}), dtype=np.intp)
    close = (
        near(posterior.space, flagged.tolist(), safety.unsafe_radius)
        if flagged.size
        else np.zeros(n, dtype=bool)
    )
    return SafetyShading(avoid, threshold, flagged, close, safety.unsafe_radius)


def draw_1d(ax: Axes, x: FloatArray, mean: FloatArray, shade: SafetyShading) -> None:
    """Grey bands hatched ``//`` over the avoided gaits, red ones hatched ``\\`` near a flag, a
    red X on each flag."""
    band = ax.get_xaxis_transform()
    if shade.avoid.any():
        ax.fill_between(
            x, 0, 1, where=shade.avoid, transform=band, step="mid",
            facecolor=AVOID_COLOUR, edgecolor=AVOID_COLOUR, hatch=AVOID_HATCH, alpha=0.3, lw=0,
            label=AVOID_LABEL,
        )  # fmt: skip
    if shade.threshold is not None:
        ax.axhline(shade.threshold, color=AVOID_COLOUR, ls=":", lw=1, label="avoidance threshold")
    if shade.unsafe.size:
        ax.fill_between(
            x, 0, 1, where=shade.near, transform=band, step="mid",
            facecolor=UNSAFE_COLOUR, edgecolor=UNSAFE_COLOUR, hatch=NEAR_HATCH, alpha=0.2, lw=0,
            label=NEAR_LABEL,
        )  # fmt: skip
        ax.scatter(
            x[shade.unsafe], mean[shade.unsafe], marker="X", s=90, c=UNSAFE_COLOUR,
            edgecolors="k", zorder=5, label=FLAG_LABEL,
        )  # fmt: skip


def draw_2d(ax: Axes, space: Space, shade: SafetyShading) -> list[Patch]:
    """Hatched grey cells over the avoided gaits, a red X on each flag with a dashed ellipse of
    its radius; returns legend proxies for what was drawn (the scatter adds its own entry)."""
    fx, fy = space.features
    proxies: list[Patch] = []
    if shade.avoid.any():
        cover = np.ma.masked_where(~shade.avoid.reshape(space.shape), np.ones(space.shape))
        ax.pcolor(
            fy.array, fx.array, cover, shading="nearest", cmap="Greys", vmin=0, vmax=1.5,
            alpha=0.55, zorder=2, edgecolors="k", linewidths=0, hatch=AVOID_HATCH,
        )  # fmt: skip
        proxies.append(
            Patch(facecolor=AVOID_COLOUR, edgecolor="k", hatch=AVOID_HATCH, alpha=0.55,
                  label=AVOID_LABEL)
        )  # fmt: skip
    if shade.unsafe.size:
        pts = space.points[shade.unsafe]
        span = np.ptp(space.points, axis=0)
        if shade.radius > 0:
            for p in pts:
                ax.add_patch(
                    Ellipse(
                        (p[1], p[0]), 2 * shade.radius * span[1], 2 * shade.radius * span[0],
                        fill=False, ec=UNSAFE_COLOUR, ls="--", lw=1.5, zorder=5,
                    )
                )  # fmt: skip
            proxies.append(Patch(fill=False, ec=UNSAFE_COLOUR, ls="--", label=NEAR_LABEL))
        ax.scatter(
            pts[:, 1], pts[:, 0], marker="X", s=110, c=UNSAFE_COLOUR, edgecolors="k",
            zorder=6, label=FLAG_LABEL,
        )  # fmt: skip
    return proxies


__all__ = ["SafetyShading", "draw_1d", "draw_2d", "safety_shading"]
