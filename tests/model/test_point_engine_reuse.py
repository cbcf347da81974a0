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


@pytest.mark.parametrize("jitter", [0.0, 1e-6])
def test_a_grown_tables_cross_and_prior_block_are_the_kernels_bit_for_bit(jitter: float) -> None:
    kernel = SquaredExponential(KERNEL.lengthscale, KERNEL.variance, jitter)
    rng = np.random.default_rng(5)
    table = _points(rng, 30)
    base = PointEngine(table, kernel)
    base.offer_square(kernel.cross(table, np.arange(30), rows=np.arange(30)))  # a fit's K_VV
    once, _ = table.extended(rng.random((1, 4)), share=True)
    twice, _ = once.extended(rng.random((2, 4)), share=True)
    middle = PointEngine(once, kernel, base)  # holds no K: the next engine reads base's
    engine = PointEngine(twice, kernel, middle)
    old = np.sort(rng.choice(30, 20, replace=False))
    got = engine.cross(old).rows(np.arange(33))
    assert np.array_equal(got, kernel.cross(twice, old)) and got.flags["C_CONTIGUOUS"]
    visited = np.concatenate([old, [31, 32]])
    block = engine.prior_block(visited)
    assert block is not None and block.flags["C_CONTIGUOUS"]
    assert np.array_equal(block, kernel.cross(twice, visited, rows=visited))
    every = engine.prior_block(np.arange(33))
    assert every is not None
    assert np.array_equal(every, kernel.cross(twice, np.arange(33), rows=np.arange(33)))
    assert np.array_equal(engine.cross(np.arange(33)).rows(np.arange(33)), every)
    plain = SquaredExponential(kernel.lengthscale, kernel.variance)
    assert np.array_equal(engine.plain, plain.cross(twice, np.arange(33)))
    assert PointEngine(twice, kernel).prior_block(visited) is None  # no base: nothing computed


def test_a_posteriors_kernel_column_and_visited_rows_are_the_kernels_bit_for_bit() -> None:
    from gaitpref.model.gp import PreferenceGP

    rng = np.random.default_rng(6)
    space = _points(rng, 25)
    gp = PreferenceGP(space, KERNEL, 0.05)
    post = gp.posterior([0, 3, 5, 7], [1, 4, 6, 9])
    _ = post.mean  # the cross is computed: columns and rows are read from it
    for action in (0, 2, 9, 24):
        want = KERNEL.cross(space, np.array([action]))[:, 0]
        assert np.array_equal(post.kernel_column(action), want)
    rows = np.array([2, 0, 24, 9])
    assert np.array_equal(post.visited_cross(rows), KERNEL.cross(space, post.visited, rows=rows))


def test_snapping_rows_at_once_is_snapping_value_by_value() -> None:
    from gaitpref.loop.lines import _snapped

    domain = Space(
        [
            Feature.interval("a", -1.0, 2.0),
            Feature.linspace("b", 0.0, 1.0, 5),
            Feature.interval("c", 0.0, 1.0),
            Feature("d", (0.0, 0.25, 1.0)),
        ]
    )
    rng = np.random.default_rng(7)
    raw = rng.uniform(-2.0, 3.0, (200, 4))
    raw[:5] = [[-1.0, 0.125, 0.0, 0.625], [2.0, 1.0, -0.0, 0.0], [-0.0, -0.0, 1.0, 2.0],
               [3.0, 0.5, 1.5, -1.0], [-5.0, 0.375, 0.5, 0.625]]  # fmt: skip
    want = np.array([[f.snap(x) for f, x in zip(domain.features, row, strict=True)] for row in raw])
    got = _snapped(domain, raw)
    assert np.array_equal(got, want)
    assert np.array_equal(np.signbit(got), np.signbit(want))  # -0.0 kept where snap keeps it
    raw[3, 2] = np.nan
    with pytest.raises(ValueError, match="'c'"):
        _snapped(domain, raw)
