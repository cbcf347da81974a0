"""The point engine's prior root (``engines.psd_root_t``, pivoted Cholesky) against the dense
reference: ``R^T R`` is the matrix to ~1e-10 relative, also when the matrix is semi-definite and
rank-deficient (a line's points close together), and draws through it have its covariance."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gaitpref import Feature, Space, SquaredExponential
from gaitpref.model.engines import PointEngine, psd_root_t
from gaitpref.pointset import PointSet


def _relative_error(root: np.ndarray, matrix: np.ndarray) -> float:
    return float(np.abs(root.T @ root - matrix).max() / np.abs(np.diagonal(matrix)).max())


@given(
    st.integers(1, 60),
    st.integers(1, 60),
    st.integers(0, 2**32 - 1),
    st.floats(1e-3, 1e3),
)
def test_the_root_reproduces_a_low_rank_matrix(n: int, rank: int, seed: int, scale: float) -> None:
    rng = np.random.default_rng(seed)
    factor = scale * rng.standard_normal((n, min(rank, n)))
    matrix = factor @ factor.T
    root = psd_root_t(matrix)
    assert root.shape == (n, n)
    assert _relative_error(root, matrix) < 1e-10


@given(
    st.integers(2, 12),
    st.integers(1, 60),
    st.integers(0, 2**32 - 1),
    st.floats(1e-9, 1e-2),
)
def test_the_root_reproduces_a_kernel_matrix_of_a_table_and_a_tight_line(
    d: int, table: int, seed: int, span: float
) -> None:
    """The line path's case: a table of scattered points and 50 points along a short segment
    (numerically rank-deficient, jitter-free)."""
    rng = np.random.default_rng(seed)
    start, direction = rng.random(d), rng.standard_normal(d)
    line = start + span * np.linspace(0.0, 1.0, 50)[:, None] * direction
    points = np.vstack([rng.random((table, d)), line])
    domain = Space([Feature.interval(f"x{k}", -10.0, 10.0) for k in range(d)])
    space = PointSet(domain, points)
    kernel = SquaredExponential(0.3, 1.7)
    matrix = kernel.cross(space, np.arange(len(space)))
    root = psd_root_t(matrix)
    assert _relative_error(root, matrix) < 1e-10
    assert np.linalg.matrix_rank(root) < len(space)  # the case is rank-deficient


def test_draws_through_the_engine_have_the_prior_covariance() -> None:
    rng = np.random.default_rng(5)
    domain = Space([Feature.interval(f"x{k}", 0.0, 1.0) for k in range(3)])
    near = 0.5 + 1e-6 * rng.standard_normal((4, 3))  # four nearly equal points: rank-deficient
    space = PointSet(domain, np.vstack([rng.random((6, 3)), near]))
    kernel = SquaredExponential(0.4, 1.3)  # no jitter: the draw is the root's alone
    engine = PointEngine(space, kernel)
    draws = engine.prior_samples(np.random.default_rng(6), 200_000)
    covariance = draws.T @ draws / draws.shape[0]
    np.testing.assert_allclose(covariance, engine.plain, atol=0.03)  # ~7 standard errors


def test_an_empty_and_a_zero_matrix_have_zero_roots() -> None:
    assert psd_root_t(np.zeros((0, 0))).shape == (0, 0)
    assert np.array_equal(psd_root_t(np.zeros((3, 3))), np.zeros((3, 3)))


@pytest.mark.parametrize(
    ("matrix", "message"),
    [
        (np.diag([1.0, -1.0]), "not positive semi-definite"),
        (np.array([[1.0, np.nan], [np.nan, 1.0]]), "not finite"),
        (np.ones((2, 3)), "must be square"),
    ],
)
def test_a_matrix_that_has_no_root_is_named(matrix: np.ndarray, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        psd_root_t(matrix)
