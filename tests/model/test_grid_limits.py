"""A model refuses, by name, a grid it cannot hold; a grid's size is counted exactly.

``len(Space)`` took NumPy's product of the feature sizes, which wraps past 2**63: 64 two-valued
features were 0 actions, so ``PreferenceGP`` chose the dense path ("auto": 0 <= 100 actions) and
its first use asked for a 32 GiB Kronecker root; 63 of them made ``len`` raise Python's
"__len__() should return >= 0".  ``khatri_rao_split`` divided by the wrapped product (0).
A ``PreferenceGP`` or ``PopulationModel`` took any grid, though every posterior reader over all
actions (mean, variance, samples) holds one number per action and every fit builds each
feature's ``n x n`` kernel factor: a feature of 10**5 values asked for 80 GB at the first fit.
Now they refuse past ``GRID_LIMIT_ACTIONS`` actions (``CoSpar``'s full-grid bound) or
``FACTOR_LIMIT_VALUES`` values a feature (a 1 GiB factor, ``covariance()``'s bound).
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from gaitpref import CoSpar, Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.model import PopulationModel
from gaitpref.model.engines import FACTOR_LIMIT_VALUES, GRID_LIMIT_ACTIONS
from gaitpref.model.kronecker import khatri_rao_split
from gaitpref.model.posterior import COVARIANCE_LIMIT_ACTIONS

KERNEL = SquaredExponential(0.3, 1.0, 1e-6)


def _binary(count: int) -> Space:
    return Space([Feature.linspace(f"f{k}", 0.0, 1.0, 2) for k in range(count)])


@pytest.mark.parametrize("count", [63, 64, 70])
def test_a_grid_past_what_len_can_count_says_so(count: int) -> None:
    space = _binary(count)
    assert space.grid_size == 2**count
    with pytest.raises(OverflowError, match=f"the grid has {2**count:,} actions"):
        len(space)
    assert len(_binary(62)) == 2**62 <= sys.maxsize  # exact below the limit


@pytest.mark.parametrize("count", [24, 64])
def test_models_refuse_a_grid_past_the_limit(count: int) -> None:
    space = _binary(count)  # 2**24 = 16,777,216 > 10**7
    for build in (
        lambda: PreferenceGP(space, KERNEL, 0.1),
        lambda: PopulationModel(space, KERNEL, 0.5, 0.1),
    ):
        with pytest.raises(ValueError, match=f"the grid has {2**count:,} actions; a model"):
            build()
    with pytest.raises(ValueError, match="the full-grid path holds at most"):
        CoSpar(space, KERNEL, 0.1, seed=0)  # the loop's own message, as before


def test_models_refuse_a_feature_whose_factor_passes_a_gib() -> None:
    assert FACTOR_LIMIT_VALUES == COVARIANCE_LIMIT_ACTIONS  # both: n x n float64 within 1 GiB
    wide = Space([Feature("x", np.arange(FACTOR_LIMIT_VALUES + 1, dtype=float))])
    with pytest.raises(ValueError, match=r"feature 'x' has 11,586 values; a model on a grid"):
        PreferenceGP(wide, KERNEL, 0.1)
    with pytest.raises(ValueError, match=r"feature 'x' has 11,586 values"):
        PopulationModel(wide, KERNEL, 0.5, 0.1)
    fits = Space([Feature("x", np.arange(FACTOR_LIMIT_VALUES, dtype=float))])
    assert PreferenceGP(fits, KERNEL, 0.1).sampler == "scalable"


def test_the_limits_hold_the_largest_grids_the_project_runs() -> None:
    assert GRID_LIMIT_ACTIONS == 10_000_000
    space = Space([Feature.linspace(c, 0.0, 1.0, 32) for c in "abcd"])  # 1,048,576 actions
    assert PreferenceGP(space, KERNEL, 0.1).sampler == "scalable"


def test_the_khatri_rao_split_counts_exactly() -> None:
    """The wrapped product was 0: ``total // C`` divided by zero."""
    assert khatri_rao_split((2,) * 64, 1) is None
    assert khatri_rao_split((32, 32, 32, 32), 10) == 2
