"""Figures: compute the picture's data first, then render it with matplotlib.

Text that comes from a user (a feature's name or unit, a config's name, a subject code, a
validation label) goes through :func:`plain` before matplotlib sees it: matplotlib reads text
between ``$`` signs as mathtext, so a unit ``$\\foo$`` made every figure of the session fail
and ``$x$`` was drawn as a formula.

A session's figures mark the gait the operator is told to walk (``Session.recommended``, the
"best so far": the highest posterior mean among the gaits that may be proposed) with a star; the
highest over every gait, when another (flagged unsafe, near one, or in the region of avoidance),
gets a hollow circle (:func:`mark_best`).  The caller passes the recommended gait in: plots never
read a session's rules.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from gaitpref.space import FloatArray

#: the legend's names of the recommended gait's mark and of the unrestricted highest's
RECOMMENDED_LABEL = "recommended (best so far)"
HIGHEST_LABEL = "highest mean (may not be proposed)"

#: the half-width of every posterior band, in standard deviations (mean +- 2 sd, as the paper)
BAND_SD = 2.0
#: how every figure names that band
BAND_LABEL = "mean ± 2 sd"


def plain(text: str) -> str:
    """``text`` as matplotlib draws it literally: every ``$`` escaped (no mathtext)."""
    return text.replace("$", r"\$")


def mark_best(ax: Axes, points: FloatArray, mean: FloatArray, recommended: int | None) -> None:
    """On a 1-D posterior curve (x: the feature, y: the posterior mean) or a 2-D heat map (x: the
    second feature, y: the first): the ``recommended`` gait starred (None: no gait may be
    proposed, no star) and, when another, the highest ``mean`` over every gait circled (hollow).
    Neither while the mean is flat: every gait as likely to be the best (the console's "No
    preference learned yet")."""
    from gaitpref.loop.stopping import preference_learned

    if not preference_learned(mean):
        return
    highest = int(np.argmax(mean))

    def at(action: int) -> tuple[float, float]:
        p = points[action]
        return (float(p[0]), float(mean[action])) if p.size == 1 else (float(p[1]), float(p[0]))

    if recommended is not None:
        x, y = at(recommended)
        ax.scatter([x], [y], marker="*", s=160, c="red", edgecolors="k", zorder=4,
                   label=RECOMMENDED_LABEL)  # fmt: skip
    if highest != recommended:
        x, y = at(highest)
        ax.scatter([x], [y], marker="o", s=160, facecolors="none", edgecolors="red",
                   linewidths=1.8, zorder=4, label=HIGHEST_LABEL)  # fmt: skip
