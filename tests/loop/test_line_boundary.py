"""Lines through a point on the box's boundary (``[cospar] line_boundary``, defaults 0.11).

A random direction through a point on the boundary of ``k`` features enters the box with
probability ``2 / 2^k``; otherwise the clipped line held its origin alone, and on a grid of a few
values per feature (whose extreme values are on the boundary) the loop proposed the buffered gait
again trial after trial.  ``fold`` turns such a direction into the box; every other line is drawn
as before, from the same random numbers.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gaitpref import Feature, Space
from gaitpref.config import parse_config
from gaitpref.loop.lines import LineSettings, draw_line, entering, line_points
from gaitpref.sessions.stored_config import config_of, library_meta
from tests.config.records import stored_record

D12 = Space([Feature.linspace(f"x{k}", 0.0, 1.0, 3) for k in range(12)])
BOX = Space(
    [Feature(f"c{k}", (-1.0, 2.0), continuous=True) for k in range(5)]
    + [Feature.linspace("g", 0.0, 1.0, 4)]
)


def _t_extent(space: Space, origin: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    lo = np.array([f.values[0] for f in space.features])
    span = np.array([f.span for f in space.features])
    u = (origin - lo) / span
    t_lo, t_hi = -np.inf, np.inf
    for uj, vj in zip(u, v, strict=True):
        if vj > 0:
            t_lo, t_hi = max(t_lo, -uj / vj), min(t_hi, (1 - uj) / vj)
        elif vj < 0:
            t_lo, t_hi = max(t_lo, (1 - uj) / vj), min(t_hi, -uj / vj)
    return t_lo, t_hi


def test_a_corner_line_held_its_origin_alone_and_now_crosses_the_grid() -> None:
    corner = np.array([0.0, 1.0] * 6)
    v = np.array([1.0, 1.0, -1.0, -1.0] * 3) / np.sqrt(12)  # out of the box both ways
    assert len(line_points(D12, corner, v, 50)) == 1  # clipped: the corner alone
    folded = entering(D12, corner, v)
    assert np.allclose(np.abs(folded), np.abs(v)) and np.isclose(np.linalg.norm(folded), 1.0)
    assert np.all(folded[0::2] > 0) and np.all(folded[1::2] < 0)  # into the box at each bound
    points = line_points(D12, corner, folded, 50)
    assert len(points) >= 3 and np.array_equal(points[0], corner)
    assert np.all((points >= 0.0) & (points <= 1.0))
    assert np.all(np.isin(points, [0.0, 0.5, 1.0]))  # snapped to the grid


def test_a_line_that_enters_the_box_is_drawn_as_before() -> None:
    rng = np.random.default_rng(5)
    for _ in range(200):
        origin = rng.choice([0.0, 0.5, 1.0], size=12)
        v = rng.standard_normal(12)
        v /= np.linalg.norm(v)
        t_lo, t_hi = _t_extent(D12, origin, v)
        if t_lo < 0 or t_hi > 0:
            assert entering(D12, origin, v) is v
    inner = np.full(12, 0.5)
    for seed in range(20):  # from inside the box fold and clip draw the same lines
        fold = draw_line(D12, LineSettings(lines=4, boundary="fold"), seed, inner)
        clip = draw_line(D12, LineSettings(lines=4, boundary="clip"), seed, inner)
        assert np.array_equal(fold.points, clip.points) and fold.direction == clip.direction


@settings(max_examples=200, deadline=None)
@given(
    u=st.lists(st.sampled_from([0.0, 1.0, 0.25, 0.5]), min_size=6, max_size=6),
    raw=st.lists(
        st.floats(-1.0, 1.0).filter(lambda x: x == 0 or abs(x) > 1e-6), min_size=6, max_size=6
    ),
)
def test_a_folded_line_always_reaches_into_the_box(u: list[float], raw: list[float]) -> None:
    lo = np.array([f.values[0] for f in BOX.features])
    span = np.array([f.span for f in BOX.features])
    origin = np.array([BOX.features[j].snap(lo[j] + u[j] * span[j]) for j in range(6)])
    v = np.array(raw)
    if np.linalg.norm(v) < 1e-3:
        v = np.ones(6)
    v = v / np.linalg.norm(v)
    w = entering(BOX, origin, v)
    t_lo, t_hi = _t_extent(BOX, origin, w)
    assert t_lo < 0 or t_hi > 0  # never the origin alone
    assert np.allclose(np.abs(w), np.abs(v))  # only signs change


@pytest.mark.parametrize("version", ["0.1", "0.8", "0.10"])
def test_sessions_recorded_before_0_11_replay_with_clipped_lines(version: str) -> None:
    text = "\n".join(
        ["[model]", "lengthscale = 0.4", "signal_variance = 1.0", "noise = 0.05", "jitter = 1e-6"]
        + [f"[space.x{k}]\nmin = 0.0\nmax = 1.0\nnum = 3" for k in range(12)]
        + ["[cospar]", 'subspace = "line"']
    )
    assert parse_config(text, defaults=version).line.boundary == "clip"
    assert config_of(stored_record(text, {"config_defaults": version})).line.boundary == "clip"
    assert config_of(stored_record(text, {})).line.boundary == "clip"  # no version: 0.1's
    new = parse_config(text)
    assert new.line.boundary == "fold" and new.relies_on_changed_defaults
    assert config_of(stored_record(text, library_meta(new))).line.boundary == "fold"
    given_ = parse_config(text + '\nline_boundary = "clip"')
    assert given_.line.boundary == "clip"


def test_line_settings_name_a_bad_boundary() -> None:
    with pytest.raises(ValueError, match="line boundary must be one of fold, clip; got 'wrap'"):
        LineSettings(boundary="wrap")  # type: ignore[arg-type]


def test_a_point_a_rounding_inside_the_boundary_is_on_it() -> None:
    """A line's end point lies a few roundings inside the box (``1 - 1e-16`` in normalised
    units), not on it: through it, a line leaving the box both ways held only points that snap
    to it, and the fold did not see it as on the boundary."""
    space = Space([Feature(f"c{k}", (0.0, 3.0), continuous=True) for k in range(4)])
    origin = np.array([3.0 * (1 - 2e-16), 0.0, 1.5, 1.5])
    v = np.array([1.0, 1.0, 0.3, -0.2])  # out of the box on c0 (by a rounding) for t > 0,
    v = v / np.linalg.norm(v)  # and on c1 for t < 0
    t_lo, t_hi = _t_extent(space, origin, v)
    assert -1e-12 < t_lo <= 0.0 <= t_hi < 1e-12  # a line a rounding long
    folded = entering(space, origin, v)
    assert folded[0] < 0 and folded[1] > 0
    points = line_points(space, origin, folded, 50)
    assert len(points) == 50 and np.ptp(points[:, 1]) > 0.5
