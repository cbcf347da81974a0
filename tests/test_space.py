from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gaitpref import MOVES, CoSpar, Feature, PreferenceGP, Space, SquaredExponential, load_config
from gaitpref.space import MAX_GRID_FEATURES, MAX_LINSPACE_VALUES, POINTS_LIMIT_ACTIONS


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
    point: Any = space.point(a)  # an array of the values: taken as the sequence it is
    assert space.index(point) == a
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
        ({"name": "x", "values": "abc"}, "'x': values must be numbers"),
        ({"name": "x", "values": [0, 1], "coactive": (0.1, 0.2, 0.3)}, "coactive must be two"),
        ({"name": "x", "values": [0, 1], "coactive": "ab"}, "coactive must be two"),
        ({"name": "x", "values": [0, 1], "words": "ab"}, "words must be two"),
        ({"name": "x", "values": [0, 1], "unit": None}, "unit must be a string"),  # was 'None'
        # a span of inf: the loop failed later with "a prior's median must be positive"
        ({"name": "x", "values": [-1.7e308, 1.7e308]}, "range of the values must be finite"),
        # read by NumPy as numbers before: "123" as 123.0, bools as 0 and 1, a table row by row
        ({"name": "x", "values": "123"}, "'x': values must be numbers, got '123'"),
        ({"name": "x", "values": ["0.1", "0.2"]}, "values must be numbers"),
        ({"name": "x", "values": [False, True]}, "values must be numbers"),
        (
            {"name": "x", "values": [[0, 1], [2, 3]]},
            r"values must be a 1-D sequence, got shape \(2, 2\)",
        ),
        ({"name": "x", "values": [[0, 1], [2]]}, "values must be numbers"),
        # "no" is truthy: the feature was continuous
        ({"name": "x", "values": [0, 1], "continuous": "no"}, "continuous must be True or False"),
        ({"name": "x", "values": [0, 1], "continuous": 1}, "continuous must be True or False"),
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


def test_a_point_is_every_feature_once_and_a_number(small_space: Space) -> None:
    names = small_space.names
    point = small_space.point(3)
    # NaN matched the first grid value before
    with pytest.raises(ValueError, match="= nan is not a value"):
        small_space.index([np.nan, *point[1:]])
    # a key the space does not have (a typo beside the right names) was ignored
    named = dict(zip(names, point.tolist(), strict=True))
    with pytest.raises(KeyError, match=r"unknown features \['typo'\]"):
        small_space.index({**named, "typo": 1.0})
    assert small_space.index(named) == 3
    # atol=NaN matched any point to its nearest grid point
    off = [float(point[0]) + 0.5, *point[1:].tolist()]
    for atol in (np.nan, -1.0, np.inf, "0.1"):
        with pytest.raises(ValueError, match="atol must be a finite number >= 0"):
            small_space.index(off, atol=atol)  # type: ignore[arg-type]


def test_feature_moves_take_an_index_in_range() -> None:
    f = Feature("x", [0.0, 1.0, 2.0, 3.0, 4.0], coactive=(0.25, 0.5))
    assert f.move(4, "-small") == 3
    # -1 read the last value before (and moved from it)
    for bad in (-1, 5, 1.0, True):
        with pytest.raises(IndexError, match=r"value index must be an integer in 0\.\.4"):
            f.move(bad, "-small")  # type: ignore[arg-type]
    four: Any = np.int64(4)  # a NumPy integer is an index too
    assert f.move(four, "-small") == 3
    with pytest.raises(ValueError, match="a value must be a number, got nan"):
        f.snap(np.nan)  # it gave the first value


def test_coactive_move_names_a_bad_feature(small_space: Space) -> None:
    for bad in (True, 1.5):
        with pytest.raises(TypeError, match="feature must be a name or a number"):
            small_space.coactive_move(0, bad, "+big")  # type: ignore[arg-type]
    with pytest.raises(IndexError, match="feature number -1 out of range"):
        small_space.coactive_move(0, -1, "+big")
    one: Any = np.int64(1)
    assert small_space.coactive_move(0, one, "+big") == small_space.coactive_move(
        0, small_space.names[1], "+big"
    )


def test_linspace_bounds_what_it_allocates() -> None:
    """``num = 10**12`` asked NumPy for 7 TiB (a MemoryError, or on a smaller count an
    allocation past the machine); a feature never needs more values than a model's grid."""
    for num in (0, MAX_LINSPACE_VALUES + 1, 10**12):
        with pytest.raises(ValueError, match=r"num must be an integer in 1\.\.10,000,000"):
            Feature.linspace("x", 0, 1, num)
    assert len(Feature.linspace("x", 0, 1, 1)) == 1


def test_a_feature_holds_at_most_the_linspace_bound() -> None:
    # values given directly had no bound: 10**8 of them became 10**8 Python floats (3 GB)
    many = np.broadcast_to(np.float64(0.0), (MAX_LINSPACE_VALUES + 1,))  # a view: no 80 MB
    with pytest.raises(ValueError, match=r"'x': at most 10,000,000 values, got 10,000,001"):
        Feature("x", many)


def test_space_and_linspace_arguments() -> None:
    with pytest.raises(TypeError, match=r"features\[0\] must be a Feature"):
        Space(["a"])  # type: ignore[list-item]
    for num in (2.5, True):
        with pytest.raises(ValueError, match=r"num must be an integer in 1\.\.10,000,000"):
            Feature.linspace("x", 0, 1, num)  # type: ignore[arg-type]
    three: Any = np.int64(3)
    assert len(Feature.linspace("x", 0, 1, three)) == 3
    # '2'..'10' compared as text ("max must exceed min"); None a TypeError
    with pytest.raises(ValueError, match="min and max must be numbers"):
        Feature.interval("x", "2", "10")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="min and max must be numbers"):
        Feature.linspace("x", None, 1, 3)  # type: ignore[arg-type]


def test_one_point_does_not_build_the_grid() -> None:
    # 40^5 = 102,400,000 actions: describe(7) built every point (7.8 GiB, 27 s) before
    space = Space([Feature.linspace(f"f{k}", 0, 1, 40) for k in range(5)])
    assert space.values_of(len(space) - 1) == dict.fromkeys(space.names, 1.0)
    assert space.describe(7).startswith("f0=0, f1=0")
    assert "points" not in vars(space)  # the cached grid was never made
    small = Space([Feature.linspace("a", 0, 1, 7), Feature("b", [0.1, 0.35, 2.0])])
    assert all(np.array_equal(small.point(i), small.points[i]) for i in range(len(small)))


def test_every_point_is_refused_past_the_bound_before_allocating() -> None:
    # 1000^4 actions: points and multi_index asked NumPy for 7.28 TiB (a MemoryError at best)
    space = Space([Feature.linspace(f"f{k}", 0, 1, 1000) for k in range(4)])
    for what in ("points", "multi_index"):
        with pytest.raises(
            ValueError,
            match=rf"{what} would hold every one of the grid's "
            r"1,000,000,000,000 actions \(1000 x 1000 x 1000 x 1000\)",
        ):
            getattr(space, what)
    assert space.point(len(space) - 1).tolist() == [1.0, 1.0, 1.0, 1.0]  # single actions read
    from gaitpref.model.engines import GRID_LIMIT_ACTIONS

    assert POINTS_LIMIT_ACTIONS == GRID_LIMIT_ACTIONS  # every grid a model takes enumerates
    at = Space([Feature.linspace("a", 0, 1, 10), Feature.linspace("b", 0, 1, 10**6)])
    assert len(at) == POINTS_LIMIT_ACTIONS
    with pytest.raises(ValueError, match="points would hold"):
        _ = Space([*at.features, Feature("c", [0.0, 1.0])]).points


def test_a_continuous_space_has_no_grid_points() -> None:
    # points was the grid of the continuous feature's two bounds, as if they were its values
    space = Space([Feature.interval("a", 0.0, 1.0), Feature("b", [1.0, 2.0, 3.0])])
    for what in ("points", "multi_index"):
        with pytest.raises(ValueError, match=r"continuous features \(a\) and no finite grid"):
            getattr(space, what)


@pytest.mark.parametrize("sizes", [[1], [3], [3, 4], [2, 1, 5], [4, 3, 2, 2]])
def test_points_are_every_point_in_flat_index_order(sizes: list[int]) -> None:
    space = Space([Feature.linspace(f"f{k}", 0, 1 + k, n) for k, n in enumerate(sizes)])
    grids = np.meshgrid(*(f.array for f in space.features), indexing="ij")
    assert np.array_equal(space.points, np.stack([g.ravel() for g in grids], axis=1))
    assert np.array_equal(space.points, space.points_of(list(range(len(space)))))
    assert np.array_equal(space.multi_index, np.argwhere(np.ones(space.shape, dtype=bool)))


@pytest.mark.parametrize(
    ("values", "error", "message"),
    [
        # NumPy reads a bool among integers as 0 or 1: [True, 3] was the actions [1, 3]
        ([True, 3], TypeError, r"actions\[0\] = True is a bool, not a grid index"),
        ((2, np.True_), TypeError, r"actions\[1\] = np.True_ is a bool"),
        # an unsigned index past 2**63 was named as a negative one (-9223372036854775803)
        (np.array([2**63 + 5], dtype=np.uint64), IndexError, r"= 9223372036854775813 is off"),
        (np.array([2**64 - 1], dtype=np.uint64), IndexError, r"= 18446744073709551615 is off"),
        # an integer past 64 bits was "dtype object", with [3, 2**63] "dtype float64"
        ([2**70], IndexError, r"actions\[0\] = 1180591620717411303424 is off the grid \(0\.\.9\)"),
        ([3, 2**63], IndexError, r"actions\[1\] = 9223372036854775808 is off the grid"),
        ([3, -(2**70)], IndexError, r"actions\[1\] = -1180591620717411303424 is off"),
        ([1.0], TypeError, "must hold integer grid indices, got dtype float64"),
    ],
)
def test_indices_name_the_value_given(values: Any, error: type, message: str) -> None:
    space = Space([Feature.linspace("a", 0, 1, 10)])
    with pytest.raises(error, match=message):
        space.check_indices(values)


def test_indices_of_every_integer_kind() -> None:
    space = Space([Feature.linspace("a", 0, 1, 10)])
    # a list mixing NumPy integer types was read as floats ("got dtype float64")
    cases: list[tuple[Any, list[int]]] = [
        ([np.int8(3), 4, np.uint64(9)], [3, 4, 9]),
        ((0,), [0]),
        (np.array([9, 3], dtype=np.uint8), [9, 3]),
    ]
    for values, expected in cases:
        idx = space.check_indices(values)
        assert idx.dtype == np.intp and idx.tolist() == expected
    assert space.check_indices([]).dtype == np.intp and space.check_indices(()).shape == (0,)


def test_linspace_of_one_value_needs_min_at_most_max() -> None:
    # num = 1 with max < min was the value max, whatever min said
    with pytest.raises(ValueError, match=r"'a': max must exceed min, got 5\.0\.\.1\.0"):
        Feature.linspace("a", 5.0, 1.0, 1)
    assert Feature.linspace("a", 2.0, 2.0, 1).values == (2.0,)
    assert Feature("a", 0.5).values == (0.5,)  # one number is one value, as before
    flag: Any = np.True_
    assert Feature("a", np.array([1, 2], dtype=np.int8), continuous=flag).continuous is True


def test_a_grid_is_indexed_over_at_most_max_grid_features() -> None:
    # MAX_GRID_FEATURES + 2 features (all but one of one value): 2 actions, and every grid
    # operation failed in NumPy with "maximum supported dimension for an ndarray is currently
    # 64, found 66" (32 on NumPy 1)
    count = MAX_GRID_FEATURES + 1
    ones = [Feature(f"f{k}", [0.0]) for k in range(count)]
    at = Space([*ones[:-2], Feature("z", [0.0, 1.0], coactive=(0.5, 1.0))])
    assert len(at) == 2 and at.index([0.0] * (count - 2) + [1.0]) == 1
    assert at.coactive_move(0, "z", "+big") == 1 and at.points.shape == (2, count - 1)
    over = Space([*ones, Feature("z", [0.0, 1.0], coactive=(0.5, 1.0))])
    assert len(over) == 2 and over.grid_size == 2 and over.words.endswith("x 2")
    message = rf"the space has {count + 1} features; a grid's actions are indexed over at most"
    reads: list[Callable[[Space], object]] = [
        lambda s: s.point(1),
        lambda s: s.index([0.0] * count + [1.0]),
        lambda s: s.coactive_move(0, "z", "+big"),
        lambda s: s.points,
        lambda s: PreferenceGP(s, SquaredExponential(0.3, 1.0, 1e-6), 0.1),
        lambda s: CoSpar(s, SquaredExponential(0.3, 1.0, 1e-6), 0.1, seed=0),
    ]
    for read in reads:
        with pytest.raises(ValueError, match=message):
            read(over)
