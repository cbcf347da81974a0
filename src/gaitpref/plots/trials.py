"""The posterior at the trials' points, for a space with no grid to draw (issue 13).

A continuous space (or one with more than two features) has no 1-D curve or 2-D heat map like the
paper's Figs. 2-6: its posterior lives on the points visited and the current line (LineCoSpar,
Tucker et al. 2020).  This figure says so and shows what there is: the posterior mean +- 2 sd
(:data:`gaitpref.plots.BAND_SD`) at each trial's point, in trial order, and the recommended
gait's posterior mean (the caller's ``Session.recommended``: the highest among the gaits that may
be proposed, the "best so far"), with its feature values in the caption; when the highest over
every gait is another (flagged unsafe, near one, or in the region of avoidance), its mean is a
dotted line, "highest mean (may not be proposed)", named in the caption too.  Data first
(:class:`TrialsPicture`), then rendered with matplotlib (Agg).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from gaitpref.model.posterior import Posterior
from gaitpref.plots import BAND_LABEL, BAND_SD, HIGHEST_LABEL, RECOMMENDED_LABEL, plain
from gaitpref.pointset import PointSet
from gaitpref.space import FloatArray, Space


@dataclass(frozen=True)
class TrialsPicture:
    """What the figure shows: the posterior at each trial's point, the recommended point's and,
    when another, the highest point's."""

    mean: FloatArray  # at the trials' points, in trial order
    std: FloatArray
    best_mean: float | None  # the recommended point's; None when there is none
    best: str  # the recommended point's feature values, as words
    why: str  # why no grid is drawn
    title: str
    highest_mean: float | None = None  # the highest over every point, when not the recommended
    highest: str = ""  # its feature values, as words


def on_a_grid(space: Space) -> bool:
    """Whether the paper's figures can draw ``space``: a full 1-D or 2-D grid."""
    return space.ndim <= 2 and not space.continuous and not isinstance(space, PointSet)


def trials_picture(
    posterior: Posterior, trials: Sequence[int], *, recommended: int | None, title: str = ""
) -> TrialsPicture:
    """The posterior at ``trials`` (actions of ``posterior.space``), at ``recommended`` (the
    session's recommended gait, ``Session.recommended()``: None while there is no point, the
    line path before a query, or when no gait may be proposed) and at its argmax when that is
    another gait."""
    space = posterior.space
    idx = np.asarray(trials, dtype=np.intp)
    mean = np.asarray(posterior.mean)
    why = (
        "continuous features: no grid to draw"
        if space.continuous
        else f"{space.ndim} features: no 1-D or 2-D grid to draw"
    )
    highest = int(np.argmax(mean)) if mean.size else None
    if recommended is not None:
        best = _words(space, recommended)
    elif highest is None:
        best = "none yet"
    else:
        best = "none may be proposed"
    other = highest is not None and highest != recommended
    return TrialsPicture(
        mean=mean[idx].copy(),
        std=np.sqrt(posterior.variance_at(idx)) if idx.size else np.zeros(0),
        best_mean=None if recommended is None else float(mean[recommended]),
        best=best,
        why=why,
        title=title,
        highest_mean=float(mean[highest]) if other and highest is not None else None,
        highest=_words(space, highest) if other and highest is not None else "",
    )


def _words(space: Space, action: int) -> str:
    return ", ".join(f"{n} {v:.3f}" for n, v in space.values_of(action).items())


def render_trials(pic: TrialsPicture) -> Figure:
    """A matplotlib figure of the picture."""
    fig = plt.figure(figsize=(6.5, 4.5))
    ax = fig.add_subplot(1, 1, 1)
    x = np.arange(1, pic.mean.size + 1)
    if x.size:
        ax.errorbar(x, pic.mean, yerr=BAND_SD * pic.std, fmt="o", ms=4, label=BAND_LABEL)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    if pic.best_mean is not None:
        ax.axhline(pic.best_mean, color="k", lw=1, ls="--", label=RECOMMENDED_LABEL)
    if pic.highest_mean is not None:
        ax.axhline(pic.highest_mean, color="r", lw=1, ls=":", label=HIGHEST_LABEL)
    ax.set_xlabel(f"trial ({pic.why}; the posterior at each trial's point)")
    ax.set_ylabel("utility")
    caption = f"recommended: {pic.best}"
    if pic.highest_mean is not None:
        caption += f"\nhighest mean (may not be proposed): {pic.highest}"
    ax.set_title(plain(caption), fontsize=9)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize=8)
    if pic.title:
        fig.suptitle(plain(pic.title))
    fig.tight_layout()
    return fig


__all__ = ["TrialsPicture", "on_a_grid", "render_trials", "trials_picture"]
