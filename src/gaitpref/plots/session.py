"""The figure of a session, as in the paper's Figs. 2 and 3 (one row per subject there).

- 1-D: the posterior mean +- 2 standard deviations (:data:`gaitpref.plots.BAND_SD`, as every
  figure) with a few joint samples and the trials, the recommended gait starred on the mean and
  the highest over every gait, when another, circled (as on the 2-D heat map below);
  beside it the trials in chronological order (trial number upwards) over a background that
  shows, row by row, the posterior mean after each trial ("the background depicting the posterior
  preference mean at each step length").
- 2-D: a heat map of the posterior mean with the trials numbered in order (one label per gait:
  ``"3, 7"`` when it was tried twice; dark numbers with a light outline, readable on every colour)
  and the recommended gait starred (``Session.recommended``: the highest posterior mean among
  the gaits that may be proposed, the "best so far" the operator is told to walk); when the
  highest over every gait is another (flagged unsafe, near one, or in the region of avoidance)
  it gets a hollow circle, "highest mean (may not be proposed)".  Neither is drawn while the
  posterior mean is flat (nothing learned yet).  A legend names the marks and the crosses.
- With a blind validation: the subject's ranking of gaits A/B/C against their posterior mean.
- With ``[safety] avoid`` or gaits flagged unsafe: the posterior (1-D) and the heat map (2-D)
  shade the region of avoidance and mark each flag with its radius, as the console's posterior
  figure does (:mod:`gaitpref.plots.safety`, whose helpers both call: :func:`session_shading`).

Excluded trials are drawn as crosses.  :func:`session_picture` collects plain arrays from a
session; :func:`render_session` draws them (matplotlib, Agg).

Notation: ``A`` actions, ``T`` trials in force, ``history`` is ``T x A``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patheffects import withStroke
from matplotlib.ticker import MaxNLocator

from gaitpref.model.threads import one_blas_thread
from gaitpref.plots import BAND_LABEL, BAND_SD, mark_best, plain
from gaitpref.plots.safety import SafetyShading, draw_1d, draw_2d, safety_shading
from gaitpref.plots.trials import on_a_grid, render_trials, trials_picture
from gaitpref.space import FloatArray, IntArray, Space

if TYPE_CHECKING:
    from gaitpref.model.posterior import Posterior
    from gaitpref.sessions.session import Session


@dataclass(frozen=True)
class SessionPicture:
    """What a session figure shows, as arrays."""

    space: Space
    mean: FloatArray
    std: FloatArray
    samples: FloatArray  # k x A
    trials: IntArray  # actions of the trials in force, in order
    excluded: np.ndarray  # bool per trial
    history: FloatArray  # T x A: posterior mean after each trial
    validation: tuple[tuple[str, int, int, float], ...]  # (label, action, subject rank, mean)
    title: str
    recommended: int | None = None  # Session.recommended(): None when no gait may be proposed
    safety: SafetyShading | None = None  # region of avoidance and unsafe flags, if any


def session_shading(session: Session, posterior: Posterior) -> SafetyShading | None:
    """What a session's figures shade over its ``posterior`` (the console's posterior figure,
    the session figure): its region of avoidance and its unsafe flags, by the loop's own rule;
    None when its config avoids nothing and no gait is flagged (nothing to shade, no legend
    entry)."""
    config = session.config
    unsafe = [action for action, _ in session.unsafe_flags().values()]
    if not (config.safety.avoid or unsafe):
        return None
    return safety_shading(posterior, config.safety, config.ordinal, unsafe)


def session_picture(session: Session, samples: int = 3, seed: int = 0) -> SessionPicture:
    """Collect a session's picture (``samples`` posterior draws with generator ``seed``), on
    one BLAS thread as ask, tell and the confidence (``model/threads.py``)."""
    with one_blas_thread():
        return _session_picture(session, samples, seed)


def _session_picture(session: Session, samples: int, seed: int) -> SessionPicture:
    post = session.posterior()
    space = session.config.space
    if space.ndim > 2:
        raise ValueError("session figures are drawn for 1-D and 2-D spaces only")
    trials = session.trials()
    rows = [p.mean for q, p in session.history() for _ in q.actions]
    history = np.array(rows) if rows else np.zeros((0, len(space)))
    draws = post.sample(np.random.default_rng(seed), samples) if samples else np.zeros((0, 1))
    last = session.validations()[-1:] if session.validations() else []
    validation = tuple(
        (label, r.actions[label], r.ranking.index(label) + 1, r.posterior_mean[label])
        for r in last
        for label in sorted(r.actions)
    )
    return SessionPicture(
        space=space,
        mean=np.asarray(post.mean).copy(),
        std=np.asarray(post.std).copy(),
        samples=draws,
        trials=np.array([t.action for t in trials], dtype=np.intp),
        excluded=np.array([t.excluded is not None for t in trials], dtype=bool),
        history=history,
        validation=validation,
        title=f"session {session.id}: subject {session.subject}, {session.config.name}, "
        f"{len(trials)} trials",
        recommended=session.recommended(),
        safety=session_shading(session, post),
    )


def _label(space: Space, k: int) -> str:
    f = space.features[k]
    return plain(f"{f.name} [{f.unit}]" if f.unit else f.name)


def _posterior_1d(ax: Axes, pic: SessionPicture) -> None:
    x = pic.space.features[0].array
    half = BAND_SD * pic.std
    ax.fill_between(x, pic.mean - half, pic.mean + half, alpha=0.25, label=BAND_LABEL)
    ax.plot(x, pic.mean, lw=2, label="posterior mean")
    for k, s in enumerate(pic.samples):
        ax.plot(x, s, lw=0.7, ls="--", alpha=0.8, label="posterior samples" if k == 0 else None)
    kept = ~pic.excluded
    ax.scatter(x[pic.trials[kept]], pic.mean[pic.trials[kept]], c="k", s=14, zorder=3,
               label="trials")  # fmt: skip
    if pic.excluded.any():
        ax.scatter(x[pic.trials[~kept]], pic.mean[pic.trials[~kept]], marker="x", c="r", s=30,
                   zorder=3, label="excluded")  # fmt: skip
    if pic.safety is not None:
        draw_1d(ax, x, pic.mean, pic.safety)
    mark_best(ax, pic.space.points, pic.mean, pic.recommended)
    ax.set_xlabel(_label(pic.space, 0))
    ax.set_ylabel("utility")
    ax.legend(loc="best", fontsize=7)
    ax.set_title("posterior")


def _chronology_1d(ax: Axes, pic: SessionPicture) -> None:
    x = pic.space.features[0].array
    n = pic.trials.size
    if n:
        ax.pcolormesh(x, np.arange(1, n + 1), pic.history, shading="nearest", cmap="viridis")
        numbers = np.arange(1, n + 1)
        ax.plot(x[pic.trials], numbers, color="w", lw=0.8)
        ax.scatter(x[pic.trials][~pic.excluded], numbers[~pic.excluded], c="w", s=14, zorder=3)
        ax.scatter(x[pic.trials][pic.excluded], numbers[pic.excluded], marker="x", c="r", s=30,
                   zorder=3)  # fmt: skip
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel(_label(pic.space, 0))
    ax.set_ylabel("trial")
    ax.set_title("trials in order over the posterior mean")


def _heat_2d(ax: Axes, pic: SessionPicture) -> None:
    fx, fy = pic.space.features
    mesh = ax.pcolormesh(fy.array, fx.array, pic.mean.reshape(pic.space.shape), shading="nearest",
                         cmap="viridis")  # fmt: skip
    plt.colorbar(mesh, ax=ax, fraction=0.046, label="posterior mean")
    pts = pic.space.points[pic.trials]
    if pic.trials.size:
        ax.plot(pts[:, 1], pts[:, 0], color="w", lw=0.6, alpha=0.7)
        for action, numbers in trial_numbers(pic).items():
            p = pic.space.points[action]
            ax.annotate(numbers, (p[1], p[0]), color="k", fontsize=7, ha="center", va="center",
                        path_effects=[OUTLINE], zorder=5)  # fmt: skip
        if pic.excluded.any():
            bad = pts[pic.excluded]
            ax.scatter(bad[:, 1], bad[:, 0], marker="x", c="r", s=50, zorder=4,
                       label="excluded trial")  # fmt: skip
    mark_best(ax, pic.space.points, pic.mean, pic.recommended)
    proxies = draw_2d(ax, pic.space, pic.safety) if pic.safety is not None else []
    handles = [*ax.get_legend_handles_labels()[0], *proxies]
    if handles:  # nothing to name before a trial, a preference or a flag
        ax.legend(handles=handles, loc="upper left", fontsize=7, framealpha=0.85)
    ax.set_xlabel(_label(pic.space, 1))
    ax.set_ylabel(_label(pic.space, 0))
    ax.set_title("posterior mean and trials (numbered)")


#: dark trial numbers with a light outline: readable on the dark and the yellow end of viridis
OUTLINE = withStroke(linewidth=2.5, foreground="w")


def trial_numbers(pic: SessionPicture) -> dict[int, str]:
    """The label of each gait tried: its trial numbers in order (``"3, 7, 12"``), one per gait,
    so that repeated gaits do not print numbers on top of each other."""
    seen: dict[int, list[str]] = {}
    for k, action in enumerate(pic.trials, start=1):
        seen.setdefault(int(action), []).append(str(k))
    return {a: ", ".join(ks) for a, ks in seen.items()}


def _validation(ax: Axes, pic: SessionPicture) -> None:
    labels = [plain(v[0]) for v in pic.validation]
    ax.bar(labels, [v[3] for v in pic.validation], color="0.7")
    for k, v in enumerate(pic.validation):
        ax.annotate(f"rank {v[2]}", (k, v[3]), ha="center", va="bottom", fontsize=8)
    ax.set_ylabel("posterior mean")
    ax.set_title("blind ranking (1 = best)")


def render_session(pic: SessionPicture) -> Figure:
    """A matplotlib figure of the picture."""
    panels = (2 if pic.space.ndim == 1 else 1) + (1 if pic.validation else 0)
    fig = plt.figure(figsize=(4.6 * panels + 0.6, 4.3))
    axes = fig.subplots(1, panels, squeeze=False)[0]
    if pic.space.ndim == 1:
        _posterior_1d(axes[0], pic)
        _chronology_1d(axes[1], pic)
    else:
        _heat_2d(axes[0], pic)
    if pic.validation:
        _validation(axes[-1], pic)
    fig.suptitle(plain(pic.title), fontsize=10)
    fig.tight_layout()
    return fig


def save_session_figure(session: Session, path: str | Path) -> Path:
    """Draw ``session`` to ``path`` (PNG or anything matplotlib writes); returns the path
    written: ``path`` itself, or with ``.png`` added when it has no suffix (a folder is
    refused, never written beside).

    A space the paper's figures cannot draw (continuous, or more than two features) gets the
    posterior at the trials' points instead (``plots/trials.py``), as in the console."""
    out = Path(path)
    if out.is_dir():
        raise ValueError(f"figure {str(out)!r} is a folder: give a file name, e.g. fig.png")
    if not out.suffix:
        out = out.with_name(out.name + ".png")
    out.parent.mkdir(parents=True, exist_ok=True)
    post = session.posterior()
    if on_a_grid(post.space):
        fig = render_session(session_picture(session))
    else:
        trials = [t.action for t in session.trials()]
        title = f"session {session.id} ({session.subject}): posterior after {len(trials)} trials"
        with one_blas_thread():
            pic = trials_picture(post, trials, recommended=session.recommended(), title=title)
        fig = render_trials(pic)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
