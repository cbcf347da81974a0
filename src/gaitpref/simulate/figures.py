"""Figures of the simulation studies (matplotlib, no pyplot state: safe in any process).

- :func:`plot_paper_2d`: one panel per Fig. 4 setting, our mean +- standard error beside the
  published curve, with the random-selection floor.
- :func:`plot_compass_gait`: the paper's Fig. 2 layout: the COT over step length, then the
  posterior utility (mean +- 2 standard deviations, 3 joint samples, the trials so far) after
  several iteration counts; a last panel with the learning curves of the sweep.

The data are computed elsewhere (``tables.Curves``, ``compass.Snapshot``); this module only draws.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from gaitpref.plots import BAND_LABEL, BAND_SD
from gaitpref.simulate.compass import Snapshot
from gaitpref.simulate.tables import Curves
from gaitpref.space import FloatArray

_OURS, _PUBLISHED, _FLOOR = "#1f5fa8", "#d0661d", "0.45"


def _band(ax: Axes, curves: Curves, name: str, color: str, label: str) -> None:
    t, m, se = curves.curve(name)
    ax.plot(t, m, color=color, lw=1.4, label=label)
    if np.all(np.isfinite(se)):
        ax.fill_between(t, m - se, m + se, color=color, alpha=0.25, lw=0)


def _floor_of(ax: Axes) -> float:
    """The lower y limit: 0.3 (the paper's), or lower so that no line or band is clipped."""
    lows = [float(np.nanmin(np.asarray(line.get_ydata()))) for line in ax.get_lines()]
    lows += [float(np.nanmin(np.asarray(c.get_paths()[0].vertices)[:, 1])) for c in ax.collections]
    low = min([0.3, *[v for v in lows if np.isfinite(v)]])
    return 0.3 if low >= 0.3 else float(np.floor((low - 0.02) * 10) / 10)


def plot_paper_2d(
    ours: Curves, published: Curves, path: str | Path, floor: str | None = "random"
) -> Path:
    """Our curves and the published ones overlaid, a panel per setting; saved to ``path``."""
    names = [s for s in ours.settings if s in published.settings]
    if not names:
        raise ValueError("no setting is in both our curves and the published ones")
    cols = min(3, len(names))
    rows = -(-len(names) // cols)
    fig = Figure(figsize=(4.2 * cols, 3.2 * rows), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, sharex=True, sharey=True, squeeze=False)).ravel()
    order = sorted(names, key=lambda n: (n.endswith("coactive"), n))
    for ax, name in zip(axes, order, strict=False):
        _band(ax, published, name, _PUBLISHED, "published (authors' 100 runs)")
        _band(ax, ours, name, _OURS, "gaitpref")
        if floor is not None and floor in ours.settings:
            t, m, _ = ours.curve(floor)
            ax.plot(t, m, color=_FLOOR, lw=1.0, ls="--", label="random selection")
        ax.set_title(name.replace("_", " ").replace("n", "n=", 1).replace(" b", ", b="))
        ax.set_xlim(0, int(ours.curve(name)[0].max()) + 1)
        ax.grid(alpha=0.3)
    axes[0].set_ylim(min(_floor_of(ax) for ax in axes[: len(order)]), 1.0)  # y is shared
    for ax in axes[len(order) :]:
        ax.set_visible(False)
    for ax in axes[::cols]:
        ax.set_ylabel("normalised objective")
    for ax in axes[-cols:]:
        ax.set_xlabel("trial")
    axes[0].legend(loc="lower right", fontsize=8)
    fig.suptitle("CoSpar on the paper's 2-D objectives: mean +- SE (Fig. 4)")
    path = Path(path)
    fig.savefig(path, dpi=130, bbox_inches="tight", pad_inches=0.1)
    return path


def plot_compass_gait(
    step_length: FloatArray,
    cot: FloatArray,
    snapshots: Sequence[Snapshot],
    path: str | Path,
    curves: Curves | None = None,
    cot_label: str = "COT (authors' polynomial)",
) -> Path:
    """COT, posterior snapshots and (optionally) the sweep's learning curves; saved to ``path``."""
    panels = 1 + len(snapshots) + (curves is not None)
    fig = Figure(figsize=(3.1 * panels, 3.0), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, panels)).ravel()
    x = np.asarray(step_length)
    axes[0].plot(x, cot, "k.-", lw=1.2)
    best = int(np.argmin(cot))
    axes[0].axvline(x[best], color="0.6", ls=":", lw=1)
    axes[0].set(title=cot_label, xlabel="step length (m)", ylabel="cost of transport")
    for ax, snap in zip(axes[1:], snapshots, strict=False):
        lo, hi = snap.mean - BAND_SD * snap.std, snap.mean + BAND_SD * snap.std
        ax.fill_between(x, lo, hi, color=_OURS, alpha=0.2, lw=0, label=BAND_LABEL)
        ax.plot(x, snap.mean, color=_OURS, lw=1.5, label="posterior mean")
        for k, s in enumerate(snap.samples):
            ax.plot(x, s, color="0.3", lw=0.8, ls="--", label="samples" if k == 0 else None)
        if snap.trials.size:
            ax.plot(
                x[snap.trials],
                snap.mean[snap.trials],
                "o",
                ms=3,
                color=_PUBLISHED,
                label="trials so far",
            )
        ax.axvline(x[best], color="0.6", ls=":", lw=1)
        ax.set(
            title=f"after {snap.iteration} iteration{'s' * (snap.iteration != 1)}",
            xlabel="step length (m)",
        )
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-2, 2))
    axes[1].set_ylabel("utility")
    axes[1].legend(fontsize=7, loc="lower center")
    if curves is not None:
        ax = axes[-1]
        for name, color in zip(curves.settings, (_OURS, _FLOOR, _PUBLISHED), strict=False):
            _band(ax, curves, name, color, name)
        ax.set(
            title="sweep: mean +- SE", xlabel="trial", ylabel="normalised objective (1 = min COT)"
        )
        ax.set_ylim(0.0, 1.02)
        ax.legend(fontsize=7, loc="lower right")
        ax.grid(alpha=0.3)
    path = Path(path)
    fig.savefig(path, dpi=130, bbox_inches="tight", pad_inches=0.1)
    return path
