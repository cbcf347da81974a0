"""The posterior figure shades the region of avoidance and marks unsafe flags (issue 12, item 3):
the shaded gaits are exactly those the loop keeps out of its queries, in 1-D and 2-D, each with
a legend entry."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.collections import PolyCollection, QuadMesh
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse

from gaitpref import Rating, Session
from gaitpref.config import parse_config
from gaitpref.loop.safety import near
from gaitpref.plots.posterior import posterior_picture, render
from gaitpref.plots.safety import AVOID_LABEL, FLAG_LABEL, NEAR_LABEL, safety_shading
from gaitpref.storage import MemoryStorage

SPACE_1D = """
[space.step_length]
min = 0.08
max = 0.18
num = 15
unit = "m"
"""
SPACE_2D = """
[space.step_length]
min = 0.08
max = 0.18
num = 8
unit = "m"
[space.step_duration]
min = 0.9
max = 1.4
num = 7
unit = "s"
"""
REST = """
[model]
lengthscale = {ls}
signal_variance = 0.005
noise = 0.02
[cospar]
seed = 2
[feedback.rating]
labels = ["very bad", "bad", "okay", "good"]
[safety]
avoid = ["very bad"]
lambda = {lam}
unsafe_radius = 0.15
"""


def _session(space: str, ls: str, lam: float, answers: int) -> Session:
    config = parse_config(f'name = "shaded"\n{space}{REST.format(ls=ls, lam=lam)}')
    s = Session.create(MemoryStorage(), config, "S01", seed=5)
    for k in range(answers):
        q = s.next_query()
        a = q.actions[0]
        given: list[object] = [Rating(a, "very bad" if k % 3 else "good")]
        if q.buffer and q.buffer[0] != a:
            given.append((a, q.buffer[0], "second" if k % 3 else "first"))
        s.answer(q.id, given)
    s.flag_unsafe(1, "stumbled")
    return s


@pytest.fixture(scope="module", params=["1d", "2d"])
def session(request: pytest.FixtureRequest) -> Session:
    if request.param == "1d":
        return _session(SPACE_1D, "0.03", 0.5, 9)
    return _session(SPACE_2D, "{ step_length = 0.03, step_duration = 0.15 }", 0.0, 12)


def _legend_texts(fig: Figure) -> set[str]:
    legends = [ax.get_legend() for ax in fig.axes]
    return {t.get_text() for legend in legends if legend for t in legend.texts}


def test_the_shaded_gaits_are_those_the_loop_avoids(session: Session) -> None:
    post, cfg = session.posterior(), session.config
    unsafe = [a for a, _ in session.unsafe_flags().values()]
    shade = safety_shading(post, cfg.safety, cfg.ordinal, unsafe)
    assert cfg.ordinal is not None
    t = cfg.safety.threshold(cfg.ordinal, post.kernel.variance)
    upper = np.asarray(post.mean) + cfg.safety.lam * np.asarray(post.std)
    assert np.array_equal(shade.avoid, upper < t)
    assert shade.avoid.any() and not shade.avoid.all()  # the ratings made a region to avoid
    assert np.array_equal(shade.near, near(post.space, unsafe, 0.15))
    assert shade.unsafe.tolist() == unsafe
    allowed = cfg.safety.allowed(post, cfg.ordinal, unsafe)
    assert allowed is not None
    assert np.array_equal(allowed, ~shade.avoid & ~shade.near)


def test_the_figure_shades_and_names_them(session: Session) -> None:
    post, cfg = session.posterior(), session.config
    unsafe = [a for a, _ in session.unsafe_flags().values()]
    shade = safety_shading(post, cfg.safety, cfg.ordinal, unsafe)
    fig = render(posterior_picture(post, [], samples=0, safety=shade))
    texts = _legend_texts(fig)
    assert {AVOID_LABEL, FLAG_LABEL, NEAR_LABEL} <= texts
    ax = fig.axes[0]
    if post.space.ndim == 1:
        bands = {c.get_label(): c for c in ax.collections if isinstance(c, PolyCollection)}
        # told apart without colour: each band hatched, one way and the other
        hatches = {bands[AVOID_LABEL].get_hatch(), bands[NEAR_LABEL].get_hatch()}
        assert None not in hatches and len(hatches) == 2
    else:
        ellipses = [p for p in ax.patches if isinstance(p, Ellipse)]
        assert len(ellipses) == len(unsafe)
        assert len([c for c in ax.collections if isinstance(c, QuadMesh)]) == 1  # the mean
        cover = [c for c in ax.collections if isinstance(c, PolyCollection)]
        assert [c.get_hatch() for c in cover] == ["//"]  # the avoided cells, hatched
        legend = ax.get_legend()
        assert legend is not None
        proxy = legend.legend_handles[[t.get_text() for t in legend.texts].index(AVOID_LABEL)]
        assert proxy is not None and proxy.get_hatch() == "//"
    plt.close(fig)


def test_without_safety_nothing_is_shaded(session: Session) -> None:
    fig = render(posterior_picture(session.posterior(), [], samples=0))
    assert not {AVOID_LABEL, FLAG_LABEL, NEAR_LABEL} & _legend_texts(fig)
    plt.close(fig)
