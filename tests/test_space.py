from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gaitpref import MOVES, Feature, Space, load_config


def test_grid_is_c_order_over_features_as_declared(small_space: Space) -> None:
    pts = small_space.points
    assert small_space.shape == (7, 5)
    assert len(small_space) == 35 and pts.shape == (35, 2)
    # the last feature varies fastest
    assert np.allclose(pts[:5, 0], 0.08) and np.allclose(pts[:5, 1], np.linspace(0.85, 1.15, 5))
    assert np.allclose(pts[5, :], [0.08 + 0.1 / 6, 0.85])
    i, j = 3, 2
    assert small_space.index([pts[5 * i + j, 0], pts[5 * i + j, 1]]) == 5 * i + j


@given(st.lists(st.integers(1, 6), min_size=1, max_size=4), st.data())
def test_index_point_round_trip(sizes: list[int], data: st.DataObject) -> None:
    space = Space([Feature.linspace(f"f{k}", 0.0, 1.0 + k, n) for k, n in enumerate(sizes)])
    a = data.draw(st.integers(0, len(space) - 1))
    assert space.index(space.point(a)) == a
    assert space.index(space.values_of(a)) == a
    assert np.array_equal(space.multi_index[a], np.unravel_index(a, space.shape))


def test_point_not_on_grid_is_an_error(small_space: Space) -> None:
    with pytest.raises(ValueError, match="not a grid value"):
        small_space.index([0.081, 0.85])
    with pytest.raises(IndexError, match="off the grid"):
        small_space.point(35)
    with pytest.raises(TypeError, match="integer"):
        small_space.check_index(1.0)


def test_coactive_moves_inside_and_at_the_edges() -> None:
    f = Feature.linspace("step_length", 0.08, 0.18, 15, unit="m", coactive=(0.1, 0.2))
    space = Space([f])
    # 10% of the range is 1.4 cells -> nearest is 1 cell; 20% is 2.8 cells -> 3 cells
    assert space.coactive_move(7, "step_length", "+small") == 8
    assert space.coactive_move(7, "step_length", "+big") == 10
    assert space.coactive_move(7, "step_length", "-small") == 6
    assert space.coactive_move(7, "step_length", "-big") == 4
    # clipped at the edges
    assert space.coactive_move(13, "step_length", "+big") == 14
    assert space.coactive_move(1, "step_length", "-big") == 0
    # a move that clips back to the same point carries no feedback
    assert space.coactive_move(14, "step_length", "+small") is None
    assert space.coactive_move(0, "step_length", "-big") is None


def test_coactive_moves_change_one_feature_only(small_space: Space) -> None:
    a = small_space.index([0.08 + 3 * 0.1 / 6, 1.0])
    b = small_space.coactive_move(a, "step_duration", "+big")
    assert b is not None
    assert small_space.point(b)[0] == small_space.point(a)[0]
    assert small_space.point(b)[1] > small_space.point(a)[1]
    with pytest.raises(ValueError, match="move must be one of"):
        small_space.coactive_move(a, "step_duration", "+huge")  # type: ignore[arg-type]
    with pytest.raises(KeyError, match="unknown feature"):
        small_space.coactive_move(a, "width", "+big")


def test_synthetic_config_moves_two_and_three_cells() -> None:
    space = load_config("synthetic-2d").space
    a = space.index([0.5 - 0.5 / 29, 0.5 - 0.5 / 29])  # cell (14, 14)
    assert space.coactive_move(a, "x", "+small") == a + 2 * 30
    assert space.coactive_move(a, "x", "+big") == a + 3 * 30
    assert space.coactive_move(a, "y", "-small") == a - 2
    assert space.coactive_move(a, "y", "-big") == a - 3


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"name": "x", "values": []}, "at least one value"),
        ({"name": "x", "values": [1, 1]}, "strictly increasing"),
        ({"name": "x", "values": [0, np.nan]}, "finite"),
        ({"name": "x y", "values": [0, 1]}, "identifier"),
        ({"name": "x", "values": [0, 1], "coactive": (0.3, 0.1)}, "coactive"),
    ],
)
def test_bad_features(kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Feature(**kwargs)  # type: ignore[arg-type]


def test_duplicate_feature_names_rejected() -> None:
    with pytest.raises(ValueError, match="unique"):
        Space([Feature("a", [0, 1]), Feature("a", [0, 1])])


def test_moves_constant() -> None:
    assert MOVES == ("+big", "+small", "-small", "-big")
