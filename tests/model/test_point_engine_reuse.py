"""The point engine's reuse of kernel blocks (issue 13's speed work) computes the very same floats
as the kernel from coordinates: results must replay bit for bit, so equality here is exact."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import Feature, Space, SquaredExponential
from gaitpref.model.engines import PointEngine
from gaitpref.pointset import PointSet

KERNEL = SquaredExponential((0.3, 0.5, 0.7, 0.4), 1.7, 1e-6)


def _points(rng: np.random.Generator, n: int) -> PointSet:
    domain = Space([Feature.interval(f"x{k}", 0.0, 1.0) for k in range(4)])
    return PointSet(domain, rng.random((n, 4)))


def test_cross_after_the_prior_matrix_is_the_kernels_bit_for_bit() -> None:
    space = _points(np.random.default_rng(0), 40)
    visited = np.sort(np.random.default_rng(1).choice(40, 25, replace=False))
    engine = PointEngine(space, KERNEL)
    _ = engine.root_t  # the prior matrix now exists: cross is taken from it
    got = engine.cross(visited)
    want = KERNEL.cross(space, visited)
    assert np.array_equal(got.rows(np.arange(40)), want)
    assert got.rows(np.arange(40)).flags["C_CONTIGUOUS"]  # the same order for BLAS


@pytest.mark.parametrize("jitter", [0.0, 1e-6])
def test_a_line_engine_started_from_the_tables_matrix_is_bit_for_bit(jitter: float) -> None:
    kernel = SquaredExponential(KERNEL.lengthscale, KERNEL.variance, jitter)
    rng = np.random.default_rng(2)
    table = _points(rng, 30)
    base = PointEngine(table, kernel)
    base.cross(np.arange(30))  # every table point visited: its K is kept
    extended, _ = table.extended(rng.random((12, 4)))
    reused = PointEngine(extended, kernel, base).plain
    fresh = PointEngine(extended, kernel).plain
    assert np.array_equal(reused, fresh)
    plain = SquaredExponential(kernel.lengthscale, kernel.variance)
    assert np.array_equal(fresh, plain.cross(extended, np.arange(42)))


def test_a_base_that_is_not_a_prefix_is_not_used() -> None:
    rng = np.random.default_rng(3)
    table = _points(rng, 20)
    base = PointEngine(table, KERNEL)
    base.cross(np.arange(20))
    other = _points(rng, 25)
    plain = SquaredExponential(KERNEL.lengthscale, KERNEL.variance)
    assert np.array_equal(PointEngine(other, KERNEL, base).plain, plain.cross(other, np.arange(25)))


def test_an_extended_set_finds_its_rows_as_a_fresh_one_does() -> None:
    rng = np.random.default_rng(4)
    table = _points(rng, 10)
    new = np.vstack([rng.random((3, 4)), table.points[2], rng.random((1, 4))])
    extended, ids = table.extended(new)
    fresh = PointSet(table.domain, extended.points)
    for row in np.vstack([extended.points, new]):
        assert extended.find(row) == fresh.find(row)
    assert ids[3] == 2
    assert extended.find(rng.random(4)) is None
