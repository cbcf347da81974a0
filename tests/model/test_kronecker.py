"""Kronecker prior samples and the Khatri-Rao cross-covariance against dense matrices."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gaitpref.model import SquaredExponential
from gaitpref.model.cross import DenseCross, RowBlockCross
from gaitpref.model.engines import ScalableEngine
from gaitpref.model.kronecker import KhatriRaoCross, KroneckerPriorSampler, khatri_rao_split
from gaitpref.space import Feature, Space


def _grid(shape: tuple[int, ...]) -> Space:
    return Space([Feature.linspace(f"f{i}", 0.0, 1.0, n) for i, n in enumerate(shape)])


def test_prior_transform_is_the_kronecker_root_applied_to_z() -> None:
    space = _grid((4, 3, 5))
    kernel = SquaredExponential((0.3, 0.5, 0.2), 2.0, 1e-3)
    sampler = KroneckerPriorSampler(space, kernel)
    z = np.random.default_rng(0).standard_normal((3, len(space)))
    zj = np.random.default_rng(1).standard_normal((3, len(space)))
    root = np.kron(np.kron(sampler.roots[0], sampler.roots[1]), sampler.roots[2])
    expected = sampler.scale * z @ root.T + np.sqrt(kernel.jitter) * zj
    np.testing.assert_allclose(sampler.transform(z.copy(), zj), expected, rtol=0, atol=1e-12)
    # the root reproduces the prior covariance
    K = kernel.dense(space)
    np.testing.assert_allclose(
        sampler.scale**2 * root @ root.T + kernel.jitter * np.eye(len(space)), K, atol=1e-12
    )


def test_roots_survive_a_numerically_singular_factor() -> None:
    """A fine grid with a long lengthscale: Cholesky of K_f fails, the eigen root does not."""
    space = _grid((60,))
    kernel = SquaredExponential(1.0, 1.0, 0.0)
    (kf,) = kernel.factors(space)
    with pytest.raises(np.linalg.LinAlgError):
        np.linalg.cholesky(kf)
    (root,) = KroneckerPriorSampler(space, kernel).roots
    assert np.all(np.isfinite(root))
    np.testing.assert_allclose(root @ root.T, kf, atol=1e-12)


def test_split_is_balanced_and_respects_the_budget() -> None:
    assert khatri_rao_split((32, 32, 32, 32), 300) == 2  # P = C = 1024
    assert khatri_rao_split((11, 7, 6, 5, 5, 5), 300) == 3  # C = 125, P = 462
    assert khatri_rao_split((30, 30), 10, block_elements=300) == 1
    assert khatri_rao_split((30, 30), 11, block_elements=300) is None
    assert khatri_rao_split((1000,), 300) == 0  # one feature: the suffix is everything


@st.composite
def _problems(draw: st.DrawFn) -> tuple[Space, SquaredExponential, np.ndarray, int, int]:
    shape = tuple(draw(st.lists(st.integers(1, 5), min_size=1, max_size=4)))
    size = int(np.prod(shape))
    m = draw(st.integers(1, min(size, 12)))
    seed = draw(st.integers(0, 2**32 - 1))
    visited = np.sort(np.random.default_rng(seed).choice(size, m, replace=False)).astype(np.intp)
    jitter = draw(st.sampled_from([0.0, 1e-3]))
    kernel = SquaredExponential(tuple(0.2 + 0.1 * i for i in range(len(shape))), 1.7, jitter)
    return _grid(shape), kernel, visited, draw(st.integers(1, 3)), draw(st.integers(1, 400))


@settings(max_examples=60, deadline=None)
@given(_problems())
def test_scalable_cross_matches_the_dense_matrix(
    problem: tuple[Space, SquaredExponential, np.ndarray, int, int],
) -> None:
    space, kernel, visited, s, block_elements = problem
    dense = kernel.cross(space, visited)
    cross = ScalableEngine(space, kernel, block_elements).cross(visited)
    coef = np.random.default_rng(0).standard_normal((visited.size, s))
    out = np.ones((s, len(space)))
    cross.add_product(out, coef)
    np.testing.assert_allclose(out, 1.0 + (dense @ coef).T, rtol=1e-12, atol=1e-12)
    rows = np.arange(len(space))[::-1]
    np.testing.assert_allclose(cross.rows(rows), dense[rows], rtol=1e-13, atol=0)
    starts, blocks = zip(*cross.blocks(), strict=True)
    np.testing.assert_allclose(np.concatenate(blocks), dense, rtol=1e-13, atol=0)
    assert list(starts) == list(np.cumsum([0] + [b.shape[0] for b in blocks[:-1]]))


def test_scalable_engine_picks_khatri_rao_or_row_blocks() -> None:
    space = _grid((6, 5, 4))
    kernel = SquaredExponential(0.3, 1.0, 1e-4)
    visited = np.arange(0, 120, 7)
    assert isinstance(ScalableEngine(space, kernel).cross(visited), KhatriRaoCross)
    small = ScalableEngine(space, kernel, block_elements=visited.size * 10).cross(visited)
    assert isinstance(small, RowBlockCross)
    assert len(list(small.blocks())) == 12  # 10 rows per block


def test_khatri_rao_blocks_stay_within_the_budget() -> None:
    space = _grid((8, 8, 8))
    kernel = SquaredExponential(0.3, 1.0, 1e-4)
    visited = np.arange(0, 512, 5)
    budget = 64 * visited.size
    cross = ScalableEngine(space, kernel, budget).cross(visited)
    assert isinstance(cross, KhatriRaoCross)
    sizes = [b.size for _, b in cross.blocks()]
    assert len(sizes) > 1 and max(sizes) <= budget


def test_dense_cross_is_read_only() -> None:
    space = _grid((4, 4))
    cross = DenseCross(space, SquaredExponential(0.3, 1.0), np.array([1, 5]))
    with pytest.raises(ValueError):
        cross.matrix[0, 0] = 1.0


@pytest.mark.parametrize("shape", [(200,), (20, 15), (6, 5, 4)])
@pytest.mark.parametrize("kind", ["dense", "khatri-rao", "row-block"])
def test_the_cross_covariance_of_no_visited_gait_is_empty(
    shape: tuple[int, ...], kind: str
) -> None:
    """The prior's ``K_{:,V}`` (no gait visited yet) is ``A x 0``: its rows, blocks and products
    work and add nothing (a reshape to ``-1`` columns failed on 0 columns)."""
    space, kernel = _grid(shape), SquaredExponential(0.2, 1e-4, 1e-6)
    none = np.zeros(0, dtype=np.intp)
    cross: DenseCross | KhatriRaoCross | RowBlockCross
    if kind == "dense":
        cross = DenseCross(space, kernel, none)
    elif kind == "khatri-rao":
        cross = KhatriRaoCross(space, kernel, none, len(shape) // 2)
    else:
        cross = RowBlockCross(space, kernel, none, 64)
    assert cross.rows(np.arange(5)).shape == (5, 0)
    starts = [(start, block.shape) for start, block in cross.blocks()]
    assert sum(rows for _, (rows, _) in starts) == len(space)
    assert all(cols == 0 for _, (_, cols) in starts)
    out = np.ones((3, len(space)))
    cross.add_product(out, np.zeros((0, 3)))
    assert np.array_equal(out, np.ones((3, len(space))))
