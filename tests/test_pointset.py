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
