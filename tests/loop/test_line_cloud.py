"""A cloud of points around the best point besides the lines (``LineSettings.cloud``,
``[cospar] line_cloud``): drawn from the line's seed after the star, inside the box, near the
origin, leaving the lines themselves as they were; bounded with the lines' points."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import ConfigError
from gaitpref.config import parse_config
from gaitpref.loop.lines import CLOUD_SCALES, MAX_STAR_POINTS, LineSettings, draw_line
from gaitpref.space import Feature, Space
from tests.config.test_line_count import EXPLICIT, LINE

SPACE = Space(
    [Feature.interval("a", 0.0, 1.0), Feature.interval("b", -2.0, 2.0),
     Feature.linspace("c", 0.0, 1.0, 11), Feature.linspace("fixed", 3.0, 3.0, 1)]
)  # fmt: skip


def test_the_cloud_comes_after_the_star_and_lies_near_the_origin_inside_the_box() -> None:
    origin = np.array([0.9, 0.0, 0.5, 3.0])
    star = draw_line(SPACE, LineSettings(20, "random", 3), 7, origin)
    cloudy = draw_line(SPACE, LineSettings(20, "random", 3, 300), 7, origin)
    assert cloudy.direction == star.direction and cloudy.others == star.others
    n = star.points.shape[0]
    np.testing.assert_array_equal(cloudy.points[:n], star.points)  # the lines as they were
    cloud = cloudy.points[n:]
    assert 250 < cloud.shape[0] <= 300  # repeats on the discrete feature are dropped
    lo, hi = np.array([0.0, -2.0, 0.0, 3.0]), np.array([1.0, 2.0, 1.0, 3.0])
    assert np.all(cloud >= lo) and np.all(cloud <= hi)
    assert np.all(cloud[:, 3] == 3.0)  # a single-valued feature does not move
    assert set(np.round(cloud[:, 2], 12)) <= set(np.round(np.linspace(0, 1, 11), 12))
    steps = (cloud[:, :2] - origin[:2]) / np.array([1.0, 4.0])
    assert np.max(np.abs(steps)) < 5 * max(CLOUD_SCALES)  # near the origin, not across the box
    assert np.median(np.abs(steps)) < 0.2
    again = draw_line(SPACE, LineSettings(20, "random", 3, 300), 7, origin)
    np.testing.assert_array_equal(again.points, cloudy.points)  # the seed decides


def test_the_cloud_is_bounded_with_the_lines() -> None:
    LineSettings(50, "random", 4, MAX_STAR_POINTS - 200)
    with pytest.raises(ValueError, match="cloud"):
        LineSettings(50, "random", 4, MAX_STAR_POINTS - 199)
    with pytest.raises(ValueError, match="cloud"):
        LineSettings(50, "random", 1, -1)


def test_the_config_key_sets_the_cloud_and_names_itself_past_the_bound() -> None:
    assert parse_config(LINE + EXPLICIT).line.cloud == 0
    cfg = parse_config(LINE + EXPLICIT + "[cospar]\nline_cloud = 120\n")
    assert cfg.line.cloud == 120 and cfg.line.lines == 4
    with pytest.raises(ConfigError, match="line_cloud"):
        parse_config(LINE + EXPLICIT + "[cospar]\nline_cloud = 4000\n")
    with pytest.raises(ConfigError, match="line_cloud"):
        parse_config(LINE + EXPLICIT + "[cospar]\nline_cloud = -3\n")
