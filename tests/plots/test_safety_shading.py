"""The posterior figure shades the region of avoidance and marks unsafe flags (issue 12, item 3):
the shaded gaits are exactly those the loop keeps out of its queries, in 1-D and 2-D, each with
a legend entry; so does the paper-style session figure."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.collections import Collection, PolyCollection, QuadMesh
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse, Patch

from gaitpref import Rating, Session
from gaitpref.config import parse_config
from gaitpref.loop.safety import near
from gaitpref.plots.posterior import posterior_picture, render
from gaitpref.plots.safety import (
    AVOID_HATCH,
    AVOID_LABEL,
    FLAG_LABEL,
    NEAR_HATCH,
    NEAR_LABEL,
    safety_shading,
)
from gaitpref.plots.session import render_session, session_picture
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
        assert isinstance(proxy, Patch) and proxy.get_hatch() == "//"
    plt.close(fig)


def test_without_safety_nothing_is_shaded(session: Session) -> None:
    fig = render(posterior_picture(session.posterior(), [], samples=0))
    assert not {AVOID_LABEL, FLAG_LABEL, NEAR_LABEL} & _legend_texts(fig)
    plt.close(fig)


def _hatches(fig: Figure) -> set[str]:
    """Every hatch pattern drawn (the bands and cells; not the legend's proxies)."""
    drawn: list[Collection | Patch] = [c for ax in fig.axes for c in ax.collections]
    drawn += [p for ax in fig.axes for p in ax.patches]
    return {h for h in (d.get_hatch() for d in drawn) if h}


def _drawn(s: Session) -> tuple[set[str], int, int, set[str]]:
    """The session figure's hatches, flag marks, dashed ellipses and legend entries."""
    fig = render_session(session_picture(s, samples=0))
    marks = [c for ax in fig.axes for c in ax.collections if c.get_label() == FLAG_LABEL]
    ellipses = [p for ax in fig.axes for p in ax.patches if isinstance(p, Ellipse)]
    out = (_hatches(fig), len(marks), len(ellipses), _legend_texts(fig))
    plt.close(fig)
    return out


def test_the_session_figure_shades_and_marks_them_as_the_posterior_figure(
    session: Session,
) -> None:
    """The paper-style session figure shaded neither the region of avoidance nor the flags."""
    pic = session_picture(session, samples=0)
    fig = render_session(pic)
    assert {AVOID_LABEL, FLAG_LABEL, NEAR_LABEL} <= _legend_texts(fig)
    ax = fig.axes[0]  # the posterior (1-D) or the heat map (2-D)
    flagged = [a for a, _ in session.unsafe_flags().values()]
    marks = [c for c in ax.collections if c.get_label() == FLAG_LABEL]
    assert len(marks) == 1 and len(np.asarray(marks[0].get_offsets())) == len(flagged)
    if session.space.ndim == 1:
        assert _hatches(fig) == {AVOID_HATCH, NEAR_HATCH}
    else:
        assert _hatches(fig) == {AVOID_HATCH}
        assert len([p for p in ax.patches if isinstance(p, Ellipse)]) == len(flagged)
    # the same masks as the console's posterior figure (one helper: plots/safety.py)
    post, cfg = session.posterior(), session.config
    shade = safety_shading(post, cfg.safety, cfg.ordinal, flagged)
    assert pic.safety is not None
    assert np.array_equal(pic.safety.avoid, shade.avoid)
    assert np.array_equal(pic.safety.near, shade.near)
    plt.close(fig)


@pytest.mark.parametrize("space", [SPACE_1D, SPACE_2D], ids=["1d", "2d"])
def test_the_session_figure_marks_a_flag_while_it_stands_and_nothing_without_one(
    space: str,
) -> None:
    """No region of avoidance: no hatch and no mark until a trial is flagged, the flag's marks
    (its X; 1-D: its band hatched ``\\``, 2-D: its dashed ellipse) while it stands, and none
    again once it is withdrawn."""
    config = parse_config(
        f'name = "flags"\n{space}[model]\nlengthscale = 0.05\nsignal_variance = 0.005\n'
        "noise = 0.02\n[cospar]\nseed = 2\n[safety]\nunsafe_radius = 0.15\n"
    )
    s = Session.create(MemoryStorage(), config, "S01", seed=5)
    for _ in range(4):
        q = s.next_query()
        other = q.buffer[0] if q.buffer else q.actions[-1]
        s.answer(q.id, [(q.actions[0], other, "first")] if q.actions[0] != other else [])
    labels = {AVOID_LABEL, FLAG_LABEL, NEAR_LABEL}
    hatches, marks, ellipses, texts = _drawn(s)
    assert (hatches, marks, ellipses) == (set(), 0, 0) and not labels & texts
    assert session_picture(s, samples=0).safety is None
    s.flag_unsafe(2, "stumbled")
    hatches, marks, ellipses, texts = _drawn(s)
    assert marks == 1 and {FLAG_LABEL, NEAR_LABEL} <= texts and AVOID_LABEL not in texts
    one_d = s.space.ndim == 1
    assert (hatches, ellipses) == (({NEAR_HATCH}, 0) if one_d else (set(), 1))
    s.withdraw_unsafe(2)
    hatches, marks, ellipses, texts = _drawn(s)
    assert (hatches, marks, ellipses) == (set(), 0, 0) and not labels & texts
