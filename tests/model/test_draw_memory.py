"""One joint draw holds two ``size x A`` arrays at its peak, and draws exactly as before.

A draw of ``size`` samples over ``A`` actions held four ``size x A`` arrays at once (traced with
tracemalloc): the normals ``z``, the jitter's normals ``z'``, their scaled copy and the samples;
a warm start's draw seven.  At the sampling budget (``SAMPLE_LIMIT_ELEMENTS``, 1 GiB) that was
4 GiB.  Now ``z`` is freed once the prior's root has been applied and ``z'`` is drawn and added
in blocks: two arrays (``SAMPLE_PEAK_ARRAYS``), three for a warm start.  The products themselves
are not split into blocks of samples: BLAS rounds a row of a product differently with another
number of rows, and a stored session must replay bit for bit; the tests below check that every
path gives exactly the values of the old formula.
"""

from __future__ import annotations

import dataclasses
import tracemalloc
from typing import Any

import numpy as np
import pytest

import gaitpref.model.kronecker as kronecker
import gaitpref.model.population as population
from gaitpref import Feature, PointSet, PreferenceGP, Space, SquaredExponential
from gaitpref.model import PopulationModel, Probit
from gaitpref.model.engines import DenseEngine, PointEngine, ScalableEngine
from gaitpref.model.kronecker import SAMPLE_PEAK_ARRAYS, KroneckerPriorSampler

BLOCK = 1 << 14  # the blocks' share of the peak is then negligible beside the 32 MiB draw


def _grid(*shape: int) -> Space:
    return Space([Feature.linspace(f"f{i}", 0.0, 1.0, n) for i, n in enumerate(shape)])


def _peak(post: Any, size: int, points: int, **kw: bool) -> float:
    """Peak traced memory of one ``sample`` (of a posterior, or a mixture of them) in ``size x
    points`` float64 arrays."""
    sample = post.sample
    sample(np.random.default_rng(0), 1, **kw)  # cached means, crosses and factors first
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        sample(np.random.default_rng(1), size, **kw)
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    return peak / (size * points * 8)


@pytest.fixture
def small_blocks(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(kronecker, "BLOCK_ELEMENTS", BLOCK)


@pytest.mark.usefixtures("small_blocks")
@pytest.mark.parametrize("fitted", [False, True])
@pytest.mark.parametrize("nugget", [True, False])
def test_a_scalable_draw_peaks_at_two_arrays(fitted: bool, nugget: bool) -> None:
    """4.0 arrays before (3.0 without jitter)."""
    space = _grid(100, 100)
    kernel = SquaredExponential(0.3, 1.0, 1e-3)
    gp = PreferenceGP(space, kernel, 0.1, sampler="scalable")
    post = gp.posterior([1, 5, 9], [2, 7, 30]) if fitted else gp.prior()
    post = dataclasses.replace(post, engine=ScalableEngine(space, kernel, BLOCK))
    assert SAMPLE_PEAK_ARRAYS == 2
    assert _peak(post, 400, len(space), nugget=nugget) <= SAMPLE_PEAK_ARRAYS + 0.1


@pytest.mark.usefixtures("small_blocks")
def test_the_dense_and_point_paths_peak_at_two_arrays() -> None:
    """4.0 arrays each before (with jitter)."""
    kernel = SquaredExponential(0.3, 1.0, 1e-3)
    dense = PreferenceGP(_grid(40, 50), kernel, 0.1, sampler="dense").posterior([1, 5], [2, 7])
    assert _peak(dense, 2000, 2000) <= SAMPLE_PEAK_ARRAYS + 0.1
    domain = Space([Feature.interval("x", 0.0, 1.0), Feature.interval("y", 0.0, 1.0)])
    points = PointSet(domain, np.random.default_rng(1).random((1000, 2)))
    line = PreferenceGP(points, kernel, 0.1).posterior([0, 1], [2, 3])
    assert _peak(line, 2000, 1000) <= SAMPLE_PEAK_ARRAYS + 0.1


@pytest.mark.usefixtures("small_blocks")
def test_a_warm_start_draw_peaks_at_three_arrays() -> None:
    """Its own and shared parts and one product: 7.0 arrays before."""
    space = _grid(100, 100)
    model = PopulationModel(space, SquaredExponential(0.3, 1.0, 1e-3), 0.5, 0.1)
    n = len(space)
    post = model.posterior(np.array([0, n + 3]), np.array([4, n + 9]), Probit(np.full(2, 0.1)), 0)
    assert _peak(post, 400, n) <= SAMPLE_PEAK_ARRAYS + 1.1


# -- the same values as before, bit for bit ---------------------------------------------------
SHAPES = [(4, 3, 5), (17, 300), (3, 101), (300,), (30, 40)]


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("jitter", [0.0, 1e-3])
def test_the_kronecker_draw_is_the_old_formula_bit_for_bit(
    shape: tuple[int, ...], jitter: float, small_blocks: None
) -> None:
    """``transform(*draw(rng, size))`` is the formula every earlier release drew with (the
    jitter's normals in blocks of BLOCK values here: many blocks)."""
    sampler = KroneckerPriorSampler(_grid(*shape), SquaredExponential(0.2, 1.3, jitter))
    for size in (1, 7, 64):
        z, zj = sampler.draw(np.random.default_rng(size), size)
        before = sampler.transform(z, zj)
        for keep in (True, False):
            rng = np.random.default_rng(size)
            after, part = sampler.parts(rng, size, jitter_part=keep)
            assert np.array_equal(after, before)
            if keep and jitter:
                assert zj is not None and part is not None
                assert np.array_equal(part, sampler.jitter_scale * zj)
            else:
                assert part is None
            assert (
                rng.standard_normal()
                == np.random.default_rng(size).standard_normal(
                    2 * size * sampler.size + 1 if jitter else size * sampler.size + 1
                )[-1]
            )  # the generator moved exactly as far
        assert np.array_equal(sampler.sample(np.random.default_rng(size), size), before)


@pytest.mark.usefixtures("small_blocks")
@pytest.mark.parametrize("jitter", [0.0, 1e-4])
def test_the_dense_and_point_engines_draw_the_old_formula_bit_for_bit(jitter: float) -> None:
    kernel = SquaredExponential(0.3, 1.0, jitter)
    domain = Space([Feature.interval("x", 0.0, 1.0), Feature.interval("y", 0.0, 1.0)])
    points = PointSet(domain, np.random.default_rng(1).random((60, 2)))
    for engine in (DenseEngine(_grid(7, 9), kernel), PointEngine(points, kernel)):
        n = len(engine.space)
        for size in (1, 5, 700):
            rng = np.random.default_rng(size)
            z = rng.standard_normal((size, n))
            zj = rng.standard_normal((size, n)) if jitter else None
            before = z @ engine.root_t
            part = None if zj is None else np.sqrt(jitter) * zj
            if part is not None:
                before += part
            for keep in (True, False):
                f, e = engine.prior_parts(np.random.default_rng(size), size, jitter_part=keep)
                assert np.array_equal(f, before)
                assert (e is None) == (part is None or not keep)
                if e is not None:
                    assert part is not None and np.array_equal(e, part)


@pytest.mark.parametrize("rho", [0.0, 0.5, 1.0])
@pytest.mark.parametrize("nugget", [True, False])
def test_a_warm_start_draws_the_old_formula_bit_for_bit(
    rho: float, nugget: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    space = _grid(12, 10)
    model = PopulationModel(space, SquaredExponential(0.3, 1.0, 1e-3), rho, 0.1)
    n = len(space)
    first, second = np.array([0, n + 3, 2 * n + 5]), np.array([4, n + 9, 2 * n + 1])
    post = model.posterior(first, second, Probit(np.full(3, 0.1)), 0)
    after = post.sample(np.random.default_rng(5), 6, nugget=nugget)

    def old(own: np.ndarray, shared: np.ndarray, mix: float) -> np.ndarray:
        out: np.ndarray = np.sqrt(1.0 - mix) * own + np.sqrt(mix) * shared
        return out

    monkeypatch.setattr(population, "_mixed", old)
    again = model.posterior(first, second, Probit(np.full(3, 0.1)), 0)
    assert np.array_equal(again.sample(np.random.default_rng(5), 6, nugget=nugget), after)
