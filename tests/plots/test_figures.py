"""Figures say what they show (issue 15, item 13): legends and colour bars for every mark, trial
numbers readable and not stacked, the same +-2 sd band everywhere, no clipped learning curve."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure

from gaitpref import Session
from gaitpref.config import parse_config
from gaitpref.plots import BAND_LABEL, BAND_SD, HIGHEST_LABEL, RECOMMENDED_LABEL
from gaitpref.plots.posterior import PosteriorPicture, posterior_picture, render
from gaitpref.plots.session import render_session, session_picture, trial_numbers
from gaitpref.space import FloatArray
from gaitpref.storage import MemoryStorage
from tests.sessions.unsafekit import unsafe_config


def _session(config: str, answers: int) -> Session:
    s = Session.create(MemoryStorage(), config, "S01", seed=4)
    for _ in range(answers):
        q = s.next_query()
        other = q.buffer[0] if q.buffer else q.actions[-1]
        pair = [(q.actions[0], other, "first")] if q.actions[0] != other else []
        s.answer(q.id, pair, [])
    return s


def _legend_texts(fig: Figure) -> set[str]:
    legends = [ax.get_legend() for ax in fig.axes]
    return {t.get_text() for legend in legends if legend for t in legend.texts}


def _colour_bar_labels(fig: Figure) -> list[str]:
    return [ax.get_ylabel() for ax in fig.axes if ax.get_label() == "<colorbar>"]


@pytest.fixture(scope="module")
def one_d() -> Session:
    return _session("exo-1d-step-length", 6)


@pytest.fixture(scope="module")
def two_d() -> Session:
    return _session("exo-2d-length-duration", 12)


def test_the_1d_figures_share_the_2_sd_band(one_d: Session) -> None:
    post = one_d.posterior()
    mean, std = np.asarray(post.mean), np.asarray(post.std)
    for fig in (
        render(posterior_picture(post, [t.action for t in one_d.trials()], samples=0)),
        render_session(session_picture(one_d, samples=0)),
    ):
        band = next(c for c in fig.axes[0].collections if isinstance(c, PolyCollection))
        ys = np.asarray(band.get_paths()[0].vertices)[:, 1]
        assert np.isclose(ys.max(), (mean + BAND_SD * std).max())
        assert np.isclose(ys.min(), (mean - BAND_SD * std).min())
        assert BAND_LABEL in _legend_texts(fig)
        plt.close(fig)
    assert BAND_SD == 2.0


def test_the_posterior_figure_names_its_marks(two_d: Session) -> None:
    post = two_d.posterior()
    trials = [t.action for t in two_d.trials()]
    objective = np.linspace(0.0, 1.0, len(post.mean))
    fig = render(posterior_picture(post, trials, objective, samples=0))
    legend = _legend_texts(fig)
    assert {"best posterior mean", "true best", "trials (shade: order)"} <= legend
    assert "trial" in _colour_bar_labels(fig)
    assert {"true objective", "posterior mean"} <= set(_colour_bar_labels(fig))
    plt.close(fig)


def test_repeated_gaits_get_one_readable_label(two_d: Session) -> None:
    from dataclasses import replace

    tried = np.array([5, 5, 9, 5, 12], dtype=np.intp)  # gait 5 tried three times
    pic = replace(session_picture(two_d, samples=0), trials=tried, excluded=np.zeros(5, dtype=bool))
    labels = trial_numbers(pic)
    assert labels == {5: "1, 2, 4", 9: "3", 12: "5"}  # one label per gait tried
    fig = render_session(pic)
    texts = [t for t in fig.axes[0].texts]
    assert len(texts) == len(labels)
    assert all(t.get_color() == "k" and t.get_path_effects() for t in texts)  # not white on yellow
    assert RECOMMENDED_LABEL in _legend_texts(fig)
    plt.close(fig)


CONFIG_2D = """
name = "best-2d"
[space.step_length]
min = 0.08
max = 0.18
num = 6
[space.step_duration]
min = 0.8
max = 1.2
num = 5
[model]
lengthscale = { step_length = 0.03, step_duration = 0.15 }
signal_variance = 0.005
noise = 0.02
jitter = 0.0
fit = "fixed"
[cospar]
seed = 1
strategy = "self-sparring"
[safety]
unsafe_radius = 0.1
"""


def _marks(fig: Figure) -> dict[str, np.ndarray]:
    """The heat map's marks by legend label: their (x, y) offsets."""
    return {
        str(c.get_label()): np.asarray(c.get_offsets())
        for c in fig.axes[0].collections
        if not str(c.get_label()).startswith("_")
    }


def _highest_walked(config: str) -> tuple[Session, int]:
    """A session whose subject prefers the higher index, answered until the gait of the highest
    posterior mean is walked: the session and the number of the trial that walked it (flag it
    unsafe and the recommended gait is another)."""
    s = Session.create(MemoryStorage(), parse_config(config), "S01")
    walked: list[int] = []
    for _ in range(20):  # the subject prefers the higher index, until the argmax is walked
        q = s.next_query()
        a, b = q.actions[0], q.buffer[0] if q.buffer else q.actions[0]
        s.answer(q.id, [(a, b, "first" if a > b else "second")] if a != b else [])
        walked = [t.number for t in s.trials() if t.action == s.posterior().argmax]
        if walked:
            break
    assert walked
    return s, walked[-1]


def _drawn(fig: Figure) -> tuple[dict[str, np.ndarray], set[str]]:
    """The figure's marks (:func:`_marks`) and legend texts; the figure closed."""
    marks, texts = _marks(fig), _legend_texts(fig)
    plt.close(fig)
    return marks, texts


def _check_the_recommended_star(config: str, at: Callable[[FloatArray, int], list[float]]) -> None:
    """The session figure, then the console's posterior figure of a session of ``config``: the
    star on the recommended gait, no circle while it is the highest; once the highest is flagged
    unsafe, the circle on it.  ``at(mean, action)``: where a figure marks ``action``."""
    from gaitpref.console.figures import picture_of  # the console's figure beside "Best so far"

    s, walked = _highest_walked(config)
    pic = session_picture(s, samples=0)
    marks, _ = _drawn(render_session(pic))
    best = s.posterior().argmax
    assert pic.recommended == best and HIGHEST_LABEL not in marks
    assert np.allclose(marks[RECOMMENDED_LABEL], [at(pic.mean, best)])
    s.flag_unsafe(walked, "knee gave way")
    highest, rec = s.posterior().argmax, s.recommended()
    assert rec is not None and rec != highest
    pic = session_picture(s, samples=0)
    assert pic.recommended == rec
    marks, texts = _drawn(render_session(pic))
    assert {RECOMMENDED_LABEL, HIGHEST_LABEL} <= texts
    assert np.allclose(marks[RECOMMENDED_LABEL], [at(pic.mean, rec)])
    assert np.allclose(marks[HIGHEST_LABEL], [at(pic.mean, highest)])
    posterior = picture_of(s, "posterior")
    assert isinstance(posterior, PosteriorPicture) and posterior.recommended == rec
    marks, texts = _drawn(render(posterior))
    assert {RECOMMENDED_LABEL, HIGHEST_LABEL} <= texts
    assert np.allclose(marks[RECOMMENDED_LABEL], [at(posterior.mean, rec)])
    assert np.allclose(marks[HIGHEST_LABEL], [at(posterior.mean, highest)])
    assert "best posterior mean" not in marks


def test_the_session_figure_stars_the_recommended_gait_not_a_flagged_highest() -> None:
    point = parse_config(CONFIG_2D).space.points

    def at(mean: FloatArray, action: int) -> list[float]:
        return [point[action][1], point[action][0]]  # the heat map's x: the second feature

    _check_the_recommended_star(CONFIG_2D, at)


def test_no_best_is_marked_before_a_preference_is_learned() -> None:
    s = Session.create(MemoryStorage(), parse_config(CONFIG_2D), "S01")
    fig = render_session(session_picture(s, samples=0))
    assert not {RECOMMENDED_LABEL, HIGHEST_LABEL} & set(_marks(fig))
    plt.close(fig)


def test_the_learning_curves_are_not_clipped(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from gaitpref.simulate.figures import plot_paper_2d
    from gaitpref.simulate.tables import Curves

    trials = np.arange(1, 21)
    low = np.linspace(0.12, 0.9, 20)  # starts far below the paper's 0.3

    def curves(shift: float) -> Curves:
        n = len(trials)
        return Curves(
            np.array(["n1_b1"] * n + ["random"] * n),
            np.concatenate([trials, trials]),
            np.concatenate([low + shift, np.full(n, 0.25)]),
            np.full(2 * n, 0.01),
        )

    captured: list[Figure] = []
    original = Figure.savefig

    def keep(self: Figure, *args: object, **kwargs: object) -> None:
        captured.append(self)
        original(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(Figure, "savefig", keep)
    plot_paper_2d(curves(0.0), curves(0.05), tmp_path / "curves.png")
    ax = captured[0].axes[0]
    assert ax.get_ylim()[0] <= 0.12 - 0.01  # the lowest band is inside the axes
    assert ax.get_ylim()[1] == 1.0


CONFIG_1D = unsafe_config("best-1d", 0.1, num=8)


def test_the_1d_figures_star_the_recommended_gait_not_a_flagged_highest() -> None:
    """As on the heat map: the star on the mean curve at the recommended gait, the hollow circle
    at the highest when another; the session figure's posterior panel and the console's."""
    x = parse_config(CONFIG_1D).space.points[:, 0]

    def at(mean: FloatArray, action: int) -> list[float]:
        return [x[action], mean[action]]  # on the mean curve

    _check_the_recommended_star(CONFIG_1D, at)


def test_no_best_is_marked_on_the_1d_figures_before_a_preference_is_learned() -> None:
    s = Session.create(MemoryStorage(), parse_config(CONFIG_1D), "S01")
    fig = render_session(session_picture(s, samples=0))
    assert not {RECOMMENDED_LABEL, HIGHEST_LABEL} & set(_marks(fig))
    plt.close(fig)
    from gaitpref.console.figures import picture_of

    posterior = picture_of(s, "posterior")
    assert isinstance(posterior, PosteriorPicture)
    fig = render(posterior)
    assert not {RECOMMENDED_LABEL, HIGHEST_LABEL} & set(_marks(fig))
    plt.close(fig)


def test_a_1d_posterior_figure_without_a_session_marks_no_best() -> None:
    """Simulation figures (no ``recommended``) draw the 1-D posterior as before: no star."""
    s = _session("exo-1d-step-length", 6)
    pic = posterior_picture(s.posterior(), [t.action for t in s.trials()], samples=0)
    fig = render(pic)
    assert not {RECOMMENDED_LABEL, HIGHEST_LABEL} & set(_marks(fig))
    plt.close(fig)


def test_the_trials_colour_bar_label_clears_the_posterior_means_bar(two_d: Session) -> None:
    """The trials' bar is carved out of the gap next to the axes; at matplotlib's default gap
    its label "trial" was drawn over the posterior mean's bar (the console's screenshot)."""
    post = two_d.posterior()
    fig = render(posterior_picture(post, [t.action for t in two_d.trials()], samples=0))
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    bars = {ax.get_ylabel(): ax for ax in fig.axes if ax.get_label() == "<colorbar>"}
    label = bars["trial"].yaxis.label.get_window_extent(renderer)
    ticks = bars["trial"].get_tightbbox(renderer)
    mean_bar = bars["posterior mean"].get_window_extent(renderer)
    assert label.x1 <= mean_bar.x0 and ticks is not None and ticks.x1 <= mean_bar.x0
    plt.close(fig)
