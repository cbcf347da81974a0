"""A point set (the line path's table) is bounded as a grid is: past 10,000,000 points its
constructor made a Python tuple of every row for its lookup table (over 1 GB at that size)."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import Feature, Space
from gaitpref.pointset import PointSet
from gaitpref.space import POINTS_LIMIT_ACTIONS


def test_a_point_set_holds_at_most_the_grid_bound() -> None:
    domain = Space([Feature.interval("a", 0.0, 1.0)])
    rows = np.broadcast_to(np.float64(0.5), (POINTS_LIMIT_ACTIONS + 1, 1))
    with pytest.raises(ValueError, match=r"at most 10,000,000 points \(a grid's bound\), got"):
        PointSet(domain, rows)
    table = PointSet(domain, [[0.2], [0.5]])
    assert len(table) == 2 and table.find([0.5]) == 1


def test_finding_a_point_of_the_wrong_length_says_so() -> None:
    # None ("not in the set") before, as for any point not there
    table = PointSet(Space([Feature.interval("a", 0.0, 1.0)]), [[0.2], [0.5]])
    with pytest.raises(ValueError, match="point has 2 coordinates, the point set's features 1"):
        table.find([0.5, 0.2])
    assert table.find([0.7]) is None and table.find(np.array([0.2])) == 0


def test_an_index_past_the_table_is_not_in_the_point_table_not_off_a_grid() -> None:
    """The line path has no grid: its indices are rows of the point table (they said 'off the
    grid (0..1)' as a grid's do, and 'it has no actions yet' for an empty table)."""
    domain = Space([Feature.interval("a", 0.0, 1.0)])
    table = PointSet(domain, [[0.2], [0.5]])
    with pytest.raises(
        IndexError, match=r"^action index 2 is not in the point table \(points 0\.\.1 so far\)$"
    ):
        table.check_index(2)
    with pytest.raises(
        IndexError, match=r"^actions\[1\] = -1 is not in the point table \(points 0\.\.1 so far\)$"
    ):
        table.check_indices([0, -1])
    with pytest.raises(IndexError, match=r"^second\[0\] = 2 is not in the point table"):
        table.check_indices(np.array([2]), "second")
    with pytest.raises(
        IndexError, match=r"^action index 0 is not in the point table \(it has no points yet\)$"
    ):
        PointSet(domain, np.zeros((0, 1))).point(0)
    grid = Space([Feature("a", (0.0, 1.0))])  # a grid says grid, as before
    with pytest.raises(IndexError, match=r"^action index 2 is off the grid \(0\.\.1\)$"):
        grid.check_index(2)
