"""Figures of a gait library: COT over the grid and joint phase diagrams (the paper's Fig. 7).

The data are computed first (:func:`phase_diagram_data` runs the full hybrid model with
:func:`simulate_gait`; :func:`cot_panel_data` reads the library) and then rendered with
matplotlib's object API (no pyplot state, no display needed).

Notation: ``K`` simulation samples; each phase diagram is a pair of ``(K,)`` arrays.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from gaitpref.gaits.library import GaitLibrary
from gaitpref.gaits.simulate import simulate_gait
from gaitpref.space import FloatArray


def phase_diagram_data(library: GaitLibrary, index: int, steps: int = 6) -> dict[str, FloatArray]:
    """One physical leg's angle/velocity and hip angle/velocity over ``steps`` simulated steps."""
    gait = library.gait(index)
    result = simulate_gait(
        gait, library.params, steps=steps, arm_at=library.settings.clearance_start
    )
    return result.leg_trajectories()


def default_ids(library: GaitLibrary) -> list[str]:
    """Three feasible gaits to show: least COT, median COT and greatest COT."""
    cot = library.cot_grid().ravel()
    ok = np.flatnonzero(np.isfinite(cot))
    if ok.size == 0:
        return []
    order = ok[np.argsort(cot[ok])]
    picks = dict.fromkeys(int(i) for i in (order[0], order[order.size // 2], order[-1]))
    return [library.gait_id(i) for i in picks]


def _cot_panel(ax: Axes, library: GaitLibrary, marks: list[int]) -> None:
    grid = library.cot_grid()
    names = library.names
    lengths = np.asarray(library.axes[0][1])
    if "step_duration" in names:
        table = grid.reshape(grid.shape[0], grid.shape[1], -1)[:, :, 0]
        durations = np.asarray(library.axes[1][1])
        image = ax.pcolormesh(durations, lengths, table, shading="nearest", cmap="viridis")
        ax.figure.colorbar(image, ax=ax, label="mechanical COT")
        for k, i in enumerate(marks):
            point = library.parameters(i)
            ax.plot(point["step_duration"], point["step_length"], "o", mfc="none", mec=f"C{k}",
                    mew=2, ms=10)  # fmt: skip
        ax.set_xlabel("step duration [s]")
        ax.set_ylabel("step length [m]")
        ax.set_title("COT over the grid")
    else:
        cot = grid.reshape(grid.shape[0], -1)[:, 0]
        ax.plot(lengths, cot, "o-", color="k", ms=3)
        for k, i in enumerate(marks):
            row = int(np.unravel_index(i, library.shape)[0])
            ax.plot(lengths[row], cot[row], "o", ms=9, mfc="none", mec=f"C{k}", mew=2)
        ax.set_xlabel("step length [m]")
        ax.set_ylabel("mechanical COT")
        ax.set_title(f"COT at {library.speed:g} m/s")


def figure_target(path: str | Path) -> Path:
    """Where a figure asked for at ``path`` is written: ``path`` itself, or with ``.png`` added
    when it has no suffix; a folder or a format matplotlib does not write is refused (a
    ValueError), before anything is simulated."""
    out = Path(path)
    if out.is_dir():
        raise ValueError(f"figure {str(out)!r} is a folder: give a file name, e.g. fig.png")
    if not out.suffix:
        out = out.with_name(out.name + ".png")
    formats = Figure().canvas.get_supported_filetypes()
    if out.suffix[1:].lower() not in formats:
        raise ValueError(
            f"figure {str(out)!r}: matplotlib does not write {out.suffix!r} files "
            f"(it writes {', '.join(sorted(formats))})"
        )
    return out


def render_library_figure(
    library: GaitLibrary, ids: list[str], path: str | Path, steps: int = 6
) -> Path:
    """COT over the grid, then phase diagrams (leg and hip) of the gaits ``ids``; saves the
    figure (:func:`figure_target`: a PNG unless ``path`` names another format) and returns
    the path written."""
    out = figure_target(path)
    indices = [library.index_of_id(i) for i in ids]
    fig = Figure(figsize=(13.5, 4.0), layout="constrained")
    ax_cot, ax_leg, ax_hip = fig.subplots(1, 3)
    _cot_panel(ax_cot, library, indices)
    for k, index in enumerate(indices):
        data = phase_diagram_data(library, index, steps)
        label = library.gait_id(index)
        ax_leg.plot(data["leg"], data["leg_rate"], lw=1, color=f"C{k}", label=label)
        ax_hip.plot(data["hip"], data["hip_rate"], lw=1, color=f"C{k}", label=label)
    ax_leg.set_xlabel("leg angle from vertical [rad]")
    ax_leg.set_ylabel("leg angular velocity [rad/s]")
    ax_leg.set_title(f"leg phase diagram ({steps} steps, full model)")
    ax_hip.set_xlabel("hip angle [rad]")
    ax_hip.set_ylabel("hip angular velocity [rad/s]")
    ax_hip.set_title("hip phase diagram")
    if indices:
        ax_hip.legend(fontsize=8)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    return out
