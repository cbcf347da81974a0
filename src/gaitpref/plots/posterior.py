"""Figures of a posterior over a 1-D or 2-D gait grid, as in the paper's Figs. 2, 3, 5 and 6.

The data of a picture is computed first (:class:`PosteriorPicture`, plain arrays), then rendered
with matplotlib (Agg backend, no screen needed):

- 1-D: posterior mean +- 2 standard deviations (:data:`gaitpref.plots.BAND_SD`, the band of
  every figure), a few joint posterior samples, the trials coloured by order (colour bar); a
  session's figure (``recommended`` given: the console's) stars the recommended gait on the mean
  and circles the highest over every gait when that is another (:func:`gaitpref.plots.mark_best`);
- 2-D: a heat map of the posterior mean (colour bar) with the trials in chronological order
  (shaded by order, their own colour bar), the best posterior mean starred and, when the true
  objective is known, its best marked with an X; a legend names the marks.  A session's figure
  (``recommended`` given: the console's) stars the recommended gait instead and circles the
  highest over every gait when that is another (:func:`gaitpref.plots.mark_best`).

With ``safety`` (ROIAL's region of avoidance and the operator's unsafe flags,
:mod:`gaitpref.plots.safety`), both kinds shade the avoided gaits (``Safety.avoided``, the loop's
own rule) and mark each gait flagged unsafe with the radius around it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from gaitpref.model.posterior import Posterior
from gaitpref.model.threads import one_blas_thread
from gaitpref.plots import BAND_LABEL, BAND_SD, mark_best, plain
from gaitpref.plots.safety import SafetyShading, draw_1d, draw_2d
from gaitpref.space import FloatArray, IntArray, Space


@dataclass(frozen=True)
class PosteriorPicture:
    """What a posterior figure shows, as arrays."""

    space: Space
    mean: FloatArray
    std: FloatArray
    samples: FloatArray  # k x A
    trials: IntArray  # executed actions in order
    objective: FloatArray | None  # true objective (flat), if known
    title: str
    safety: SafetyShading | None = None  # region of avoidance and unsafe flags, if any
    recommending: bool = False  # a session's: star ``recommended``, not the argmax
    recommended: int | None = None  # Session.recommended(): None when no gait may be proposed


def posterior_picture(
    posterior: Posterior,
    trials: Sequence[int] | IntArray = (),
    objective: FloatArray | None = None,
    *,
    samples: int = 3,
    rng: np.random.Generator | None = None,
    title: str = "",
    safety: SafetyShading | None = None,
    recommending: bool = False,
    recommended: int | None = None,
) -> PosteriorPicture:
    """Collect what to draw (``samples`` joint posterior samples, drawn with ``rng``;
    ``safety``: what :func:`gaitpref.plots.safety.safety_shading` computed, to shade).
    ``recommending``: a session's figure, which stars ``recommended`` (its
    ``Session.recommended()``) rather than the argmax over every gait."""
    if posterior.space.ndim > 2:
        raise ValueError("posterior figures are drawn for 1-D and 2-D spaces only")
    gen = rng if rng is not None else np.random.default_rng(0)
    with one_blas_thread():  # as the session figure (plots/session.py): the same floats
        draws = posterior.sample(gen, samples) if samples else np.zeros((0, len(posterior.space)))
        std = np.asarray(posterior.std).copy()
    return PosteriorPicture(
        space=posterior.space,
        mean=np.asarray(posterior.mean).copy(),
        std=std,
        samples=draws,
        trials=np.asarray(trials, dtype=np.intp),
        objective=None if objective is None else np.asarray(objective, dtype=float).reshape(-1),
        title=title,
        safety=safety,
        recommending=recommending,
        recommended=recommended,
    )


def _axis_label(space: Space, k: int) -> str:
    f = space.features[k]
    return plain(f"{f.name} [{f.unit}]" if f.unit else f.name)


def _draw_1d(pic: PosteriorPicture, fig: Figure) -> None:
    x = pic.space.features[0].array
    ax = fig.add_subplot(1, 1, 1)
    half = BAND_SD * pic.std
    ax.fill_between(x, pic.mean - half, pic.mean + half, alpha=0.25, label=BAND_LABEL)
    ax.plot(x, pic.mean, lw=2, label="posterior mean")
    for k, s in enumerate(pic.samples):
        ax.plot(x, s, lw=0.8, ls="--", label="posterior samples" if k == 0 else None)
    if pic.trials.size:
        dots = ax.scatter(
            x[pic.trials],
            pic.mean[pic.trials],
            c=np.arange(1, pic.trials.size + 1),
            cmap="viridis",
            zorder=3,
            s=20,
            label="trials (colour: order)",
        )
        fig.colorbar(dots, ax=ax, fraction=0.046, label="trial")
    if pic.objective is not None:
        ax2 = ax.twinx()
        ax2.plot(x, pic.objective, color="k", lw=1, alpha=0.6)
        ax2.set_ylabel("true objective")
    if pic.safety is not None:
        draw_1d(ax, x, pic.mean, pic.safety)
    if pic.recommending:
        mark_best(ax, pic.space.points, pic.mean, pic.recommended)
    ax.set_xlabel(_axis_label(pic.space, 0))
    ax.set_ylabel("utility")
    ax.legend(loc="best", fontsize=8)


#: the gap between the posterior mean's colour bar and its axes when the trials' colour bar is
#: carved out of that gap's left (next to the axes): room for the trials' ticks and label, which
#: overlapped the posterior mean's bar at matplotlib's default 0.05
TRIALS_BAR_ROOM = 0.15


def _heat(
    ax: Axes, pic: PosteriorPicture, values: FloatArray, title: str, pad: float = 0.05
) -> None:
    fx, fy = pic.space.features
    grid = values.reshape(pic.space.shape)
    mesh = ax.pcolormesh(fy.array, fx.array, grid, shading="nearest", cmap="viridis")
    plt.colorbar(mesh, ax=ax, fraction=0.046, pad=pad, label=title)
    ax.set_xlabel(_axis_label(pic.space, 1))
    ax.set_ylabel(_axis_label(pic.space, 0))
    ax.set_title(title)


def _draw_2d(pic: PosteriorPicture, fig: Figure) -> None:
    panels = 2 if pic.objective is not None else 1
    axes = fig.subplots(1, panels, squeeze=False)[0]
    if pic.objective is not None:
        _heat(axes[0], pic, pic.objective, "true objective")
    ax = axes[-1]
    _heat(ax, pic, pic.mean, "posterior mean", TRIALS_BAR_ROOM if pic.trials.size else 0.05)
    if pic.trials.size:
        pts = pic.space.points[pic.trials]
        ax.plot(pts[:, 1], pts[:, 0], color="w", lw=0.6, alpha=0.6)
        dots = ax.scatter(
            pts[:, 1],
            pts[:, 0],
            c=np.arange(1, pic.trials.size + 1),
            cmap="Greys",
            edgecolors="k",
            linewidths=0.5,
            s=18,
            zorder=3,
            label="trials (shade: order)",
        )
        fig.colorbar(dots, ax=ax, fraction=0.046, label="trial")
    if pic.recommending:
        mark_best(ax, pic.space.points, pic.mean, pic.recommended)
    else:
        best = pic.space.points[int(np.argmax(pic.mean))]
        ax.scatter(
            [best[1]], [best[0]], marker="*", s=160, c="red", edgecolors="k", zorder=4,
            label="best posterior mean",
        )  # fmt: skip
    if pic.objective is not None:
        true_best = pic.space.points[int(np.argmax(pic.objective))]
        for a in axes:
            a.scatter([true_best[1]], [true_best[0]], marker="x", s=80, c="k", zorder=4,
                      label="true best")  # fmt: skip
    proxies = draw_2d(ax, pic.space, pic.safety) if pic.safety is not None else []
    handles, _ = ax.get_legend_handles_labels()
    ax.legend(handles=[*handles, *proxies], loc="upper left", fontsize=7, framealpha=0.85)


def render(pic: PosteriorPicture) -> Figure:
    """A matplotlib figure of the picture."""
    wide = pic.space.ndim == 2 and pic.objective is not None
    fig = plt.figure(figsize=(11, 4.5) if wide else (6.5, 4.5))
    if pic.space.ndim == 1:
        _draw_1d(pic, fig)
    else:
        _draw_2d(pic, fig)
    if pic.title:
        fig.suptitle(plain(pic.title))
    fig.tight_layout()
    return fig


def save_posterior_figure(pic: PosteriorPicture, path: str | Path) -> Path:
    """Render ``pic`` to ``path`` (PNG or anything matplotlib writes); returns the path."""
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig = render(pic)
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out
