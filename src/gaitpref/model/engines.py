"""How a posterior reaches all ``A`` actions: the dense path or the scalable one.

Both paths draw the same exact samples from the Laplace posterior by pathwise conditioning
(``posterior.py``) and consume a generator identically, so with the same seed they propose the
same actions (up to floating-point rounding); they differ only in what they store:

- ``"dense"``: the prior's square root ``s (S_1 (x) ... (x) S_d)`` as one ``A x A`` matrix (built
  once per model) and ``K_{:,V}`` as one ``A x m`` matrix per posterior.  Fewest Python steps:
  fastest on small grids.
- ``"scalable"``: prior samples axis by axis through the per-feature roots and ``K_{:,V}`` through
  its Khatri-Rao tables (``kronecker.py``), in blocks of at most ``BLOCK_ELEMENTS`` floats:
  memory ``O(A s + (P + C) m)``, time ``O(A (sum n_f + m) s)`` per ask.
- ``"auto"``: dense up to :data:`DENSE_MAX_ACTIONS` actions, scalable above.  The threshold is
  the measured crossover of an ask on the project's 2-core machines
  (``benchmarks/bench_large.py``, ``benchmarks/results/large.md``): dense is faster by 10-30 us
  below about 90 actions, the two tie at 90-100, and scalable is 2-10x faster from 250 actions on
  (the dense path's ``A x A`` root makes its prior draw ``O(A^2)``).

Notation: ``A`` actions, ``m`` visited, ``s`` samples, ``n_f`` values of feature ``f``.
"""

from __future__ import annotations

from functools import cached_property
from typing import Literal, get_args

import numpy as np
from scipy.linalg import lapack

from gaitpref.model.cross import CrossCovariance, DenseCross, RowBlockCross
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.kronecker import (
    BLOCK_ELEMENTS,
    KhatriRaoCross,
    KroneckerPriorSampler,
    add_jitter_draw,
    check_sample_budget,
    khatri_rao_split,
)
from gaitpref.pointset import PointSet
from gaitpref.space import FloatArray, IntArray, Space

SamplerName = Literal["auto", "dense", "scalable"]
SAMPLERS: tuple[SamplerName, ...] = get_args(SamplerName)

#: ``sampler="auto"`` uses the dense path up to this many actions (measured crossover).
DENSE_MAX_ACTIONS = 100
#: The dense path refuses larger grids: its ``A x A`` prior root would pass 512 MiB.
DENSE_LIMIT_ACTIONS = 8192
#: A model on a grid refuses more actions than this: its posterior's mean, variance and samples
#: each hold one number per action (``loop/cospar.py``'s full-grid path has the same bound) ...
GRID_LIMIT_ACTIONS = 10_000_000
#: ... and a feature with more values than this: each fit builds the feature's ``n x n`` kernel
#: factor, which would pass 1 GiB (the bound ``Posterior.covariance()`` has; ``CoSpar``
#: allows 1,000 a feature).
FACTOR_LIMIT_VALUES = 11_585


def check_grid_size(space: Space) -> None:
    """ValueError naming the grid or the feature a model cannot hold (a point set, the line
    path's, has no grid: its size is its points')."""
    if isinstance(space, PointSet):
        return
    for f in space.features:
        if len(f.values) > FACTOR_LIMIT_VALUES:
            raise ValueError(
                f"feature {f.name!r} has {len(f.values):,} values; a model on a grid takes at most "
                f"{FACTOR_LIMIT_VALUES:,} a feature (its kernel factor is n x n, built at every "
                "fit): use fewer values, or the line path"
            )
    size = space.grid_size
    if size is not None and size > GRID_LIMIT_ACTIONS:
        raise ValueError(
            f"the grid has {size:,} actions; a model on a grid takes at most "
            f"{GRID_LIMIT_ACTIONS:,} (its mean, variance and samples hold one number per "
            "action): use the line path"
        )
    _ = space.index_shape  # a grid NumPy can index: ValueError naming its features otherwise


def resolve_sampler(sampler: str, size: int) -> Literal["dense", "scalable"]:
    """The path ``sampler`` means for a grid of ``size`` actions; ValueError if it cannot be."""
    if sampler not in SAMPLERS:
        raise ValueError(f"sampler must be one of {', '.join(SAMPLERS)}; got {sampler!r}")
    if sampler == "auto":
        return "dense" if size <= DENSE_MAX_ACTIONS else "scalable"
    if sampler == "dense" and size > DENSE_LIMIT_ACTIONS:
        raise ValueError(
            f'sampler="dense" needs an A x A matrix; this grid has {size} actions (the limit is '
            f'{DENSE_LIMIT_ACTIONS}): use sampler="scalable" or "auto"'
        )
    return "dense" if sampler == "dense" else "scalable"


class DenseEngine:
    """The dense path: ``A x A`` prior root, ``A x m`` cross-covariance."""

    name: Literal["dense", "scalable"] = "dense"

    def __init__(self, space: Space, kernel: SquaredExponential) -> None:
        self.space, self.kernel = space, kernel
        self.prior = KroneckerPriorSampler(space, kernel)
        root: FloatArray = np.ones((1, 1))
        for r in self.prior.roots:
            root = np.kron(root, r).astype(np.float64, copy=False)
        self.root_t = np.ascontiguousarray(self.prior.scale * root.T)  # so z @ root_t

    def prior_samples(self, rng: np.random.Generator, size: int) -> FloatArray:
        return self.prior_parts(rng, size, jitter_part=False)[0]

    def prior_parts(
        self, rng: np.random.Generator, size: int, *, jitter_part: bool = True
    ) -> tuple[FloatArray, FloatArray | None]:
        """Prior samples (as :meth:`prior_samples`, the same generator use and values) and
        their jitter part ``sqrt(jitter) z'`` (None without jitter or ``jitter_part``).  The
        generator draws ``z``, then ``z'``; ``z`` is freed after the product and ``z'`` drawn
        block by block unless kept (:data:`~gaitpref.model.kronecker.SAMPLE_PEAK_ARRAYS`)."""
        check_sample_budget(size, self.prior.size)
        out: FloatArray = rng.standard_normal((size, self.prior.size)) @ self.root_t
        return add_jitter_draw(out, rng, self.prior.jitter_scale, jitter_part)

    def cross(self, visited: IntArray) -> CrossCovariance:
        return DenseCross(self.space, self.kernel, visited)


class ScalableEngine:
    """The scalable path: Kronecker prior samples, blocked Khatri-Rao cross-covariance."""

    name: Literal["dense", "scalable"] = "scalable"

    def __init__(
        self, space: Space, kernel: SquaredExponential, block_elements: int = BLOCK_ELEMENTS
    ) -> None:
        self.space, self.kernel = space, kernel
        self.prior = KroneckerPriorSampler(space, kernel)
        self.block_elements = block_elements

    def prior_samples(self, rng: np.random.Generator, size: int) -> FloatArray:
        return self.prior.sample(rng, size)

    def prior_parts(
        self, rng: np.random.Generator, size: int, *, jitter_part: bool = True
    ) -> tuple[FloatArray, FloatArray | None]:
        """As :meth:`DenseEngine.prior_parts`."""
        return self.prior.parts(rng, size, jitter_part=jitter_part)

    def cross(self, visited: IntArray) -> CrossCovariance:
        split = khatri_rao_split(self.space.shape, visited.shape[0], self.block_elements)
        if split is None:
            return RowBlockCross(self.space, self.kernel, visited, self.block_elements)
        return KhatriRaoCross(self.space, self.kernel, visited, split, self.block_elements)


def psd_root_t(matrix: FloatArray) -> FloatArray:
    """``R`` (``n x n``) with ``R^T R = matrix`` for a symmetric positive semi-definite
    ``matrix``, possibly rank-deficient, by LAPACK's pivoted Cholesky ``dpstrf`` (Higham,
    *Accuracy and Stability of Numerical Algorithms*, 2002, Section 10.3).

    ``dpstrf`` gives a permutation ``p`` and a lower ``n x r`` factor ``L`` with
    ``matrix[p][:, p] = L L^T``, so ``R[:r, p] = L^T`` and the rows past the numerical rank ``r``
    are zero.  It stops when the largest diagonal entry of the remaining Schur complement is at
    most ``n u max_k matrix_kk`` (``u`` the unit roundoff, LAPACK's default tolerance); that
    complement is semi-definite, so no entry it leaves out exceeds that size: ``R^T R`` equals
    ``matrix`` to ``n u max_k matrix_kk`` plus rounding.  ``O(n r^2)`` time, about ten times
    faster than an eigendecomposition at a few hundred points.

    ``matrix`` must be semi-definite (a kernel's Gram matrix is).  ValueError if it is not square
    and finite, or if a diagonal entry of ``R^T R`` exceeds the matrix's by more than
    ``sqrt(u) max_k matrix_kk`` (a negative direction the factor left out; an indefinite
    remainder with a small diagonal would pass this check).
    """
    if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1]:
        raise ValueError(f"the prior covariance must be square, got shape {matrix.shape}")
    n = matrix.shape[0]
    root = np.zeros((n, n))
    if not n:
        return root
    if not np.all(np.isfinite(matrix)):
        raise ValueError(f"the prior covariance of the {n} points is not finite")
    factor, piv, rank, info = lapack.dpstrf(matrix, lower=1)
    if info < 0:  # an illegal argument: a wrapper bug, never the matrix
        raise ValueError(f"LAPACK dpstrf rejected argument {-info} of the prior covariance")
    root[:rank, piv - 1] = np.tril(factor[:, :rank]).T
    diagonal = np.diagonal(matrix)
    missed = diagonal - np.einsum("ij,ij->j", root, root)
    if missed.min() < -np.sqrt(np.finfo(float).eps) * diagonal.max():
        raise ValueError(
            f"the prior covariance of the {n} points is not positive semi-definite (a diagonal "
            f"entry of its pivoted Cholesky factor is off by {-missed.min():.3g})"
        )
    return root


def _grown(known: FloatArray, kernel: SquaredExponential, space: PointSet) -> FloatArray:
    """``kernel``'s matrix over every point of ``space`` whose first block, over the first
    points, is ``known`` (taken as it is), with ``kernel``'s rows for the points past it and
    their transpose above (``(a - b)^2 = (b - a)^2``): each entry the kernel's floats."""
    size, start = len(space), known.shape[0]
    out = np.empty((size, size))
    out[:start, :start] = known
    if start < size:
        new = kernel.cross(space, np.arange(size), rows=np.arange(start, size))
        out[start:] = new
        out[:start, start:] = new[:, :start].T
    return out


class PointEngine:
    """The dense path on a :class:`~gaitpref.pointset.PointSet` (no grid, no Kronecker
    structure): the prior's square root from the pivoted Cholesky factor of the points'
    jitter-free covariance (:func:`psd_root_t`: exact for a semi-definite, rank-deficient
    matrix), the jitter as an independent term."""

    name: Literal["dense", "scalable"] = "dense"

    def __init__(
        self, space: PointSet, kernel: SquaredExponential, base: PointEngine | None = None
    ) -> None:
        """``base`` is an engine over the first points of ``space`` with the same kernel
        (a line's points appended to the table, the table grown by a query's points): ``K``
        over its points, when it holds it, is not computed again (:attr:`plain`,
        :meth:`cross`, :meth:`prior_block`).  A base that holds none but was made from one
        passes its own on (a table grown twice, by a query's point and then by its answer's
        suggestions)."""
        self.space, self.kernel = space, kernel
        self.jitter_scale = float(np.sqrt(kernel.jitter))
        if base is not None and base._square is None and base._base is not None:
            base = base._base
        self._base: PointEngine | None = base
        self._square: FloatArray | None = None  # K over every point, jitter included

    @cached_property
    def plain(self) -> FloatArray:
        """The jitter-free prior covariance of every point (computed once per engine).  Rows
        a base engine already has are taken from it: its ``K`` less the jitter is exactly this
        matrix (off the diagonal ``x + 0.0 = x``; on it ``s^2 exp(0) = s^2``), and the new
        block's transpose is exact (``(a - b)^2 = (b - a)^2``)."""
        plain = SquaredExponential(self.kernel.lengthscale, self.kernel.variance)
        size = len(self.space)
        known = self._known_block()
        self._base = None
        if known is None:
            return plain.cross(self.space, np.arange(size))
        out = _grown(known, plain, self.space)
        out[np.diag_indices(known.shape[0])] = self.kernel.variance
        return out

    def _known_block(self) -> FloatArray | None:
        """``K`` over the first points (jitter included): this engine's over all of them when
        it holds it, else the base engine's over all its points, when it has one and is a
        prefix."""
        if self._square is not None:
            return self._square
        base = self._base
        if base is None or base._square is None or base.kernel != self.kernel:
            return None
        start = len(base.space)
        if start > len(self.space) or not np.array_equal(
            base.space.points, self.space.points[:start]
        ):
            return None
        return base._square

    @cached_property
    def root_t(self) -> FloatArray:
        """The transposed square root of the jitter-free prior covariance (first draw only)."""
        return psd_root_t(self.plain)

    def prior_samples(self, rng: np.random.Generator, size: int) -> FloatArray:
        return self.prior_parts(rng, size, jitter_part=False)[0]

    def prior_parts(
        self, rng: np.random.Generator, size: int, *, jitter_part: bool = True
    ) -> tuple[FloatArray, FloatArray | None]:
        """As :meth:`DenseEngine.prior_parts`."""
        n = len(self.space)
        check_sample_budget(size, n)
        out: FloatArray = rng.standard_normal((size, n)) @ self.root_t
        return add_jitter_draw(out, rng, self.jitter_scale, jitter_part)

    def cross(self, visited: IntArray) -> CrossCovariance:
        """``K_{:,V}``; once :attr:`plain` is computed, its columns plus the jitter where a row
        is its column: each entry the same floating-point operations as the kernel's."""
        if "plain" not in self.__dict__:
            square = self._known_square()
            if square is None:
                return self._remember(DenseCross(self.space, self.kernel, visited))
            if _all_points(visited, len(self.space)):
                return DenseCross(self.space, self.kernel, visited, square)
            columns: FloatArray = np.take(square, visited, axis=1)  # C order, as the kernel's
            return DenseCross(self.space, self.kernel, visited, columns)
        matrix: FloatArray = np.take(self.plain, visited, axis=1)  # C order, as the kernel's
        if self.kernel.jitter:  # where a row is its column (the kernel adds 0.0 elsewhere: an
            # entry s^2 exp(.) >= +0.0, or NaN, plus +0.0 is itself)
            matrix[visited, np.arange(visited.shape[0])] += self.kernel.jitter
        return DenseCross(self.space, self.kernel, visited, matrix)

    def _known_square(self) -> FloatArray | None:
        """``K`` over every point (jitter included) when this engine holds it, or when a base
        engine holds it over the first points: then its block, and the kernel's rows for the
        points past them (their transpose the block above: ``(a - b)^2 = (b - a)^2`` and
        ``x + 0.0 = x`` off the diagonal), each entry the kernel's floats; kept.  None
        otherwise (nothing is computed)."""
        if self._square is not None:
            return self._square
        known = self._known_block()
        if known is None:
            return None
        out = _grown(known, self.kernel, self.space)
        out.setflags(write=False)
        self._square = out
        self._base = None
        return out

    def prior_block(self, visited: IntArray) -> FloatArray | None:
        """``K[V, V]`` (jitter included) from the ``K`` over every point this engine holds or
        has from its base (:meth:`_known_square`), the same floats as
        ``kernel.cross(space, V, rows=V)``, read-only; None when it has none."""
        square = self._known_square()
        if square is None:
            return None
        if _all_points(visited, len(self.space)):
            return square
        block: FloatArray = np.take(np.take(square, visited, axis=0), visited, axis=1)
        return block

    def offer_square(self, matrix: FloatArray) -> None:
        """Keep ``matrix`` as ``K`` over every point (jitter included) unless one is kept: a
        fit's ``K_VV`` when every point is visited (``kernel.cross(space, V, rows=V)`` with
        ``V`` all the points: the same floating-point operations as ``kernel.cross(space, V)``,
        so the same floats), read by :meth:`cross` and by a line's engine (:attr:`plain`)
        instead of computing it again.  Made read-only: the posterior's cross reads it."""
        if self._square is None and matrix.shape == (len(self.space), len(self.space)):
            matrix.setflags(write=False)
            self._square = matrix

    def _remember(self, cross: DenseCross) -> DenseCross:
        """Keep ``K`` over every point when ``cross`` is it (a line's engine starts there)."""
        if _all_points(cross.visited, len(self.space)):
            self._square = cross.matrix
        return cross


def _all_points(visited: IntArray, size: int) -> bool:
    """Whether ``visited`` is every point, ``0..size-1`` in order."""
    return visited.shape == (size,) and bool(np.array_equal(visited, np.arange(size)))


GridEngine = DenseEngine | ScalableEngine | PointEngine


def make_engine(space: Space, kernel: SquaredExponential, sampler: str = "auto") -> GridEngine:
    """The engine for ``sampler`` ("auto", "dense" or "scalable") on ``space``; a point set
    always takes :class:`PointEngine`."""
    if isinstance(space, PointSet):
        return PointEngine(space, kernel)
    if resolve_sampler(sampler, len(space)) == "dense":
        return DenseEngine(space, kernel)
    return ScalableEngine(space, kernel)
