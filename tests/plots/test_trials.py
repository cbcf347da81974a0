"""The posterior at the trials' points (``plots/trials.py``), for spaces with no grid to draw:
its numbers are the posterior's at those points, and the paper's figures keep 1-D/2-D grids."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.container import ErrorbarContainer

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.plots import HIGHEST_LABEL, RECOMMENDED_LABEL
from gaitpref.plots.trials import on_a_grid, render_trials, trials_picture
from gaitpref.storage import MemoryStorage
from tests.sessions.test_line_session import TEXT, _drive


def test_the_trials_picture_is_the_posterior_at_the_trials() -> None:
    s = Session.create(MemoryStorage(), parse_config(TEXT), "S01")
    _drive(s, 5)
    post = s.posterior()
    trials = [t.action for t in s.trials()]
    pic = trials_picture(post, trials, recommended=s.recommended(), title="t")
    assert not on_a_grid(post.space) and "continuous" in pic.why
    # dense reference: the posterior's own marginals at those rows
    assert np.allclose(pic.mean, np.asarray(post.mean)[trials])
    assert np.allclose(pic.std, np.asarray(post.std)[trials])
    best = int(np.argmax(post.mean))
    assert s.recommended() == best  # nothing flagged: the recommended gait is the highest
    assert pic.best_mean == float(np.max(post.mean)) and pic.highest_mean is None
    assert pic.best.startswith(f"step_length {post.space.values_of(best)['step_length']:.3f}")
    fig = render_trials(pic)
    try:
        (ax,) = fig.axes
        (bars,) = ax.containers
        assert isinstance(bars, ErrorbarContainer)
        assert np.size(bars.lines[0].get_xdata()) == 5
    finally:
        plt.close(fig)


def test_grids_of_one_or_two_features_keep_the_paper_figures() -> None:
    from gaitpref.config import load_config

    assert on_a_grid(load_config("exo-2d-length-duration").space)
    assert not on_a_grid(load_config("synthetic-6d").space)
    assert not on_a_grid(load_config("compass-continuous-3d").space)


def test_the_trials_figure_marks_the_recommended_gait_not_a_flagged_highest() -> None:
    s = Session.create(
        MemoryStorage(), parse_config(TEXT + "[safety]\nunsafe_radius = 0.3\n"), "S01"
    )
    _drive(s, 5)
    mean = np.asarray(s.posterior().mean)
    top = max(s.trials(), key=lambda t: mean[t.action])  # the best trial, flagged unsafe
    s.flag_unsafe(top.number, "knee gave way")
    post = s.posterior()
    highest, rec = post.argmax, s.recommended()
    assert rec is not None and rec != highest  # the highest may not be proposed
    pic = trials_picture(post, [t.action for t in s.trials()], recommended=rec)
    mean = np.asarray(post.mean)
    assert pic.best_mean == float(mean[rec]) and pic.highest_mean == float(mean[highest])
    assert pic.best.startswith(f"step_length {s.space.values_of(rec)['step_length']:.3f}")
    fig = render_trials(pic)
    try:
        (ax,) = fig.axes
        lines = {ln.get_label(): ln.get_ydata() for ln in ax.get_lines()}
        assert np.allclose(lines[RECOMMENDED_LABEL], mean[rec])
        assert np.allclose(lines[HIGHEST_LABEL], mean[highest])
        assert ax.get_title().startswith("recommended: ")
        assert "highest mean (may not be proposed)" in ax.get_title()
    finally:
        plt.close(fig)
