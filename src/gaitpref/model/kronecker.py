"""Kronecker structure of the product kernel on a grid: prior samples and ``K_{:,V}`` products.

``docs/model.md``, "Posterior over all actions" (joint samples) and "Large grids": on a Cartesian
grid the prior covariance is ``K = s^2 (K_1 (x) ... (x) K_d) + jitter I``, so nothing ``A x A``
(or ``A x m``) is ever needed.

- Prior samples: ``f0 = s (S_1 (x) ... (x) S_d) z + sqrt(jitter) z'`` with ``S_f S_f^T = K_f``,
  applied axis by axis in ``O(A sum n_f)`` per sample.
- Cross-covariance: column ``j`` of ``K_{:,V}`` is ``s^2 (k_1[:, v_j1] (x) ... (x) k_d[:, v_jd])``
  plus ``jitter`` at row ``v_j``, so ``K_{:,V}`` is a column-wise Khatri-Rao product.  Splitting
  the features into a prefix (``P`` combinations) and a suffix (``C`` combinations, ``A = P C``),
  the rows of prefix ``p`` are ``T * c_p`` with the suffix table ``T`` (``C x m``) and the
  prefix row ``c_p`` (length ``m``).  Hence ``K_{:,V} B`` for an ``m x s`` matrix ``B`` is one
  matrix product ``(c_p B_t)_{(p,t)} @ T^T`` per block of prefixes, ``2 A m s`` flops through
  BLAS and only ``(P + C) m`` numbers stored; explicit row blocks ``K[rows, V]`` for the variance
  are built block by block within a fixed memory budget.

Notation: ``A`` grid points, ``d`` features with ``n_f`` values, ``m`` visited actions ``V``,
``s`` columns (samples); ``P`` prefix and ``C`` suffix combinations of the split.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence

import numpy as np

from gaitpref.model.kernels import SquaredExponential
from gaitpref.space import FloatArray, IntArray, Space

#: Elements (float64) that one block of temporary work may hold: 4 Mi elements = 32 MiB.
BLOCK_ELEMENTS = 1 << 22
#: The most values one joint draw of ``size`` samples over ``A`` points (``size x A``) may
#: hold: 2**27 float64, 1 GiB, the bound ``Posterior.covariance()`` has on its ``A x A`` matrix.
#: It admits the largest query (``n = 64`` samples) on the largest grid (10**6 gaits) twice
#: over; a strategy's settings may ask for more (plausible-eubo's ``samples``, gated-eubo's
#: ``gates``), so a new session checks its config's largest draw against it
#: (``config/draws.py``); beyond it, draw the samples in batches.  The numerics check every draw.
SAMPLE_LIMIT_ELEMENTS = 1 << 27
#: What one draw holds at its peak, in ``size x A`` arrays (measured with tracemalloc,
#: ``tests/model/test_draw_memory.py``): two, the normals and the first axis's product while
#: the prior's root is applied, then each axis's input and output.  The products are not split
#: into blocks of samples: BLAS rounds a row of a matrix product differently with another
#: number of rows (measured: 1e-15 on a 17 x 300 grid), and stored sessions must replay bit for
#: bit.  The jitter's normals are drawn and added :data:`BLOCK_ELEMENTS` at a time.  So a draw
#: at the budget peaks near 2 GiB (before: four arrays, the normals, the jitter's normals, their
#: scaled copy and the samples).  ``Posterior.sample(..., nugget=False)`` keeps the jitter's
#: part (one more), and a warm start's draw (``population.py``) its shared part (one more).
SAMPLE_PEAK_ARRAYS = 2


def check_sample_budget(size: int, points: int) -> None:
    """ValueError naming ``size``, ``points`` and the budget when ``size x points`` samples
    would pass :data:`SAMPLE_LIMIT_ELEMENTS` values (checked before anything is drawn)."""
    if size * points > SAMPLE_LIMIT_ELEMENTS:
        raise ValueError(
            f"size = {size} samples over {points} points would be {size * points:,} values, "
            f"more than the sampling budget of {SAMPLE_LIMIT_ELEMENTS:,} (1 GiB of float64): "
            f"draw at most {SAMPLE_LIMIT_ELEMENTS // points} samples at a time"
        )


class KroneckerPriorSampler:
    """Joint samples of ``N(0, K)`` over the whole grid through per-feature square roots.

    The square roots come from the eigendecomposition ``K_f = U diag(e) U^T``, ``S_f = U
    diag(sqrt(max(e, 0)))``, not from a Cholesky factor: a squared-exponential ``K_f`` on a fine
    grid is positive semi-definite only to rounding (its smallest eigenvalues are ``~1e-17``
    and some come out negative), where a Cholesky factorisation fails or needs a jitter that
    would change the distribution; clipping the rounding-level eigenvalues at zero changes
    ``S_f S_f^T`` by rounding only.  The grid jitter enters exactly, as an independent
    ``sqrt(jitter) z'`` term.
    """

    def __init__(self, space: Space, kernel: SquaredExponential) -> None:
        self.shape = space.shape
        self.size = len(space)
        self.scale = float(np.sqrt(kernel.variance))
        self.jitter_scale = float(np.sqrt(kernel.jitter))
        self.roots: list[FloatArray] = []
        for factor in kernel.factors(space):
            eigval, eigvec = np.linalg.eigh(factor)
            self.roots.append(eigvec * np.sqrt(np.clip(eigval, 0.0, None)))

    def draw(self, rng: np.random.Generator, size: int) -> tuple[FloatArray, FloatArray | None]:
        """The standard normals of ``size`` samples: ``z`` (``size x A``) and ``z'`` (or None);
        ValueError past :data:`SAMPLE_LIMIT_ELEMENTS`."""
        check_sample_budget(size, self.size)
        z = rng.standard_normal((size, self.size))
        z_jitter = rng.standard_normal((size, self.size)) if self.jitter_scale else None
        return z, z_jitter

    def transform(self, z: FloatArray, z_jitter: FloatArray | None) -> FloatArray:
        """``s (S_1 (x) ... (x) S_d) z + sqrt(jitter) z'`` for ``z`` of shape ``size x A``."""
        out = self._rooted(z)
        if z_jitter is not None:
            out += self.jitter_scale * z_jitter
        return out

    def _rooted(self, x: FloatArray) -> FloatArray:
        """``s (S_1 (x) ... (x) S_d) x``, axis by axis; an ``x`` its caller no longer holds is
        freed after the first axis (two ``size x A`` arrays at a time)."""
        size = x.shape[0]
        pre, post = size, self.size
        for root in self.roots:
            n = root.shape[0]
            post //= n
            if post == 1:
                x = x.reshape(pre, n) @ root.T
            else:
                x = np.matmul(root, x.reshape(pre, n, post))
            pre *= n
        out: FloatArray = x.reshape(size, self.size)
        out *= self.scale
        return out

    def parts(
        self, rng: np.random.Generator, size: int, *, jitter_part: bool = True
    ) -> tuple[FloatArray, FloatArray | None]:
        """``size x A`` joint prior samples and their jitter part ``sqrt(jitter) z'`` (None
        without jitter, or without ``jitter_part``): the generator used and the values exactly
        as :meth:`transform` of :meth:`draw`, at a peak of :data:`SAMPLE_PEAK_ARRAYS` arrays."""
        check_sample_budget(size, self.size)
        out = self._rooted(rng.standard_normal((size, self.size)))
        return add_jitter_draw(out, rng, self.jitter_scale, jitter_part)

    def sample(self, rng: np.random.Generator, size: int) -> FloatArray:
        """``size x A`` joint prior samples."""
        return self.parts(rng, size, jitter_part=False)[0]


def add_jitter_draw(
    out: FloatArray, rng: np.random.Generator, scale: float, keep: bool
) -> tuple[FloatArray, FloatArray | None]:
    """``out += scale z'`` in place for standard normals ``z'`` of ``out``'s shape from ``rng``,
    and the part ``scale z'`` when ``keep`` (else None; None too when ``scale`` is 0, which
    draws nothing).  The same generator use, values and rounding as ``part = scale *
    rng.standard_normal(out.shape); out += part``; without ``keep`` the normals are drawn and
    added :data:`BLOCK_ELEMENTS` at a time (a generator's normals come in the same sequence
    however they are split into calls)."""
    if not scale:
        return out, None
    if keep:
        part: FloatArray = rng.standard_normal(out.shape)
        part *= scale
        out += part
        return out, part
    rows = max(1, BLOCK_ELEMENTS // max(1, out.shape[1]))
    for start in range(0, out.shape[0], rows):
        block = out[start : start + rows]
        normals = rng.standard_normal(block.shape)
        normals *= scale
        block += normals
    return out, None


def _khatri_rao(columns: Sequence[FloatArray], m: int) -> FloatArray:
    """Column-wise Khatri-Rao product (C order over the factors' rows); ``1 x m`` ones if none."""
    out = np.ones((1, m))
    for col in columns:
        out = (out[:, None, :] * col[None, :, :]).reshape(out.shape[0] * col.shape[0], m)
    return out


class KhatriRaoCross:
    """``K_{:,V}`` on a grid, never stored: products, row gathers and row blocks.

    ``split`` is the first suffix feature (:func:`khatri_rao_split`).  Temporaries stay below
    ``block_elements`` floats (plus one row block of ``s`` samples when ``C s`` exceeds it).
    """

    def __init__(
        self,
        space: Space,
        kernel: SquaredExponential,
        visited: IntArray,
        split: int,
        block_elements: int = BLOCK_ELEMENTS,
    ) -> None:
        self.size = len(space)
        self.shape = space.shape
        self.visited = visited
        self.variance = kernel.variance
        self.jitter = kernel.jitter
        m = visited.shape[0]
        self.m = m
        vis_mi = np.unravel_index(visited, space.shape)
        self.columns = [kf[:, vi] for kf, vi in zip(kernel.factors(space), vis_mi, strict=True)]
        self.block_elements = block_elements
        self.prefix = kernel.variance * _khatri_rao(self.columns[:split], m)  # P x m
        self.suffix_t = np.ascontiguousarray(_khatri_rao(self.columns[split:], m).T)  # m x C
        self.n_prefix, self.n_suffix = self.prefix.shape[0], self.suffix_t.shape[1]

    def add_product(self, out: FloatArray, coef: FloatArray) -> None:
        """``out += (K_{:,V} coef)^T`` in place; ``out`` is ``s x A``, ``coef`` is ``m x s``."""
        if not out.flags.c_contiguous:
            raise ValueError("add_product needs a C-contiguous output array")
        s = coef.shape[1]
        P, C = self.n_prefix, self.n_suffix
        view = out.reshape(s, P, C)
        step = max(1, self.block_elements // max(C * s, self.m * s, 1))
        coef_t = coef.T  # s x m
        for p0 in range(0, P, step):
            p1 = min(P, p0 + step)
            scaled = (self.prefix[p0:p1, None, :] * coef_t[None, :, :]).reshape(
                (p1 - p0) * s, self.m
            )
            block = scaled @ self.suffix_t  # (nb s) x C
            view[:, p0:p1, :] += block.reshape(p1 - p0, s, C).transpose(1, 0, 2)
        if self.jitter:
            out[:, self.visited] += self.jitter * coef_t

    def rows(self, rows: IntArray) -> FloatArray:
        """``K[rows, V]`` (``len(rows) x m``)."""
        rows = np.asarray(rows, dtype=np.intp)
        multi = np.unravel_index(rows, self.shape)
        out = self.variance * self.columns[0][multi[0]]
        for col, idx in zip(self.columns[1:], multi[1:], strict=True):
            out *= col[idx]
        if self.jitter:
            out += self.jitter * (rows[:, None] == self.visited[None, :])
        return out

    def blocks(self) -> Iterator[tuple[int, FloatArray]]:
        """``(start, K[start:start + len(block), V])`` over the whole grid, block by block."""
        P, C, m = self.n_prefix, self.n_suffix, self.m
        suffix = self.suffix_t.T  # C x m (a view)
        step = max(1, self.block_elements // max(C * m, 1))
        for p0 in range(0, P, step):
            p1 = min(P, p0 + step)
            block = (self.prefix[p0:p1, None, :] * suffix[None, :, :]).reshape((p1 - p0) * C, m)
            start = p0 * C
            if self.jitter:
                _add_jitter(block, start, self.visited, self.jitter)
            yield start, block


def _add_jitter(block: FloatArray, start: int, visited: IntArray, jitter: float) -> None:
    """``block[v - start, j] += jitter`` for the visited ``v = visited[j]`` inside the block."""
    stop = start + block.shape[0]
    j = np.flatnonzero((visited >= start) & (visited < stop))
    block[visited[j] - start, j] += jitter


def khatri_rao_split(
    shape: Sequence[int], m: int, block_elements: int = BLOCK_ELEMENTS
) -> int | None:
    """The first suffix feature of the most balanced split (``max(P, C)`` smallest) whose tables
    ``P x m`` and ``C x m`` both fit in ``block_elements``; None when no split fits."""
    best: tuple[int, int] | None = None
    total = math.prod(shape)
    for k in range(len(shape)):
        C = math.prod(shape[k:])
        largest = max(C, total // C)
        if largest * max(m, 1) <= block_elements and (best is None or largest < best[0]):
            best = (largest, k)
    return None if best is None else best[1]
