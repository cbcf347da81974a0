"""The cross-covariance ``K_{:,V}`` between every action and the visited ones, three ways.

Everything the posterior computes over all ``A`` actions goes through ``K_{:,V}`` (``A x m``):
the mean ``K_{:,V} alpha``, the pathwise correction ``K_{:,V} beta`` of samples and the rows of
``P = L^-1 K_{V,:}`` for the variance (``posterior.py``).  A :class:`CrossCovariance` offers
exactly those three uses, so the posterior never needs to know how (or whether) the matrix is
stored:

- :class:`DenseCross`: the ``A x m`` matrix itself (small grids: one BLAS call per use);
- :class:`~gaitpref.model.kronecker.KhatriRaoCross`: the grid's Kronecker structure, nothing
  ``A x m`` stored (``kronecker.py``);
- :class:`RowBlockCross`: explicit row blocks from the kernel, for grids whose structure does
  not fit the Khatri-Rao tables (one enormous feature), still within a fixed memory budget.

Notation: ``A`` actions, ``m`` visited, ``s`` right-hand sides (samples).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Protocol

import numpy as np

from gaitpref.model.kernels import SquaredExponential
from gaitpref.space import FloatArray, IntArray, Space


class CrossCovariance(Protocol):
    """``K_{:,V}`` for one visited set ``V``."""

    visited: IntArray

    def add_product(self, out: FloatArray, coef: FloatArray) -> None:
        """``out += (K_{:,V} coef)^T`` in place (``out``: ``s x A``, ``coef``: ``m x s``)."""

    def rows(self, rows: IntArray) -> FloatArray:
        """``K[rows, V]``."""

    def blocks(self) -> Iterator[tuple[int, FloatArray]]:
        """``(start, K[start:start + len(block), V])`` covering the grid in order."""


class DenseCross:
    """``K_{:,V}`` held as one ``A x m`` matrix."""

    def __init__(
        self,
        space: Space,
        kernel: SquaredExponential,
        visited: IntArray,
        matrix: FloatArray | None = None,
    ) -> None:
        """``matrix``, when given, is ``K_{:,V}`` already computed (the same floats as
        ``kernel.cross(space, visited)``)."""
        self.visited = visited
        self.matrix = kernel.cross(space, visited) if matrix is None else matrix
        self.matrix.setflags(write=False)

    def add_product(self, out: FloatArray, coef: FloatArray) -> None:
        out += (self.matrix @ coef).T

    def rows(self, rows: IntArray) -> FloatArray:
        return self.matrix[np.asarray(rows, dtype=np.intp)]

    def blocks(self) -> Iterator[tuple[int, FloatArray]]:
        yield 0, self.matrix


class RowBlockCross:
    """``K_{:,V}`` computed ``rows_per_block`` rows at a time from the kernel, never stored."""

    def __init__(
        self, space: Space, kernel: SquaredExponential, visited: IntArray, block_elements: int
    ) -> None:
        self.space = space
        self.kernel = kernel
        self.visited = visited
        self.rows_per_block = max(1, block_elements // max(visited.shape[0], 1))

    def add_product(self, out: FloatArray, coef: FloatArray) -> None:
        for start, block in self.blocks():
            out[:, start : start + block.shape[0]] += (block @ coef).T

    def rows(self, rows: IntArray) -> FloatArray:
        return self.kernel.cross(self.space, self.visited, rows=rows)

    def blocks(self) -> Iterator[tuple[int, FloatArray]]:
        size = len(self.space)
        for start in range(0, size, self.rows_per_block):
            stop = min(size, start + self.rows_per_block)
            yield start, self.rows(np.arange(start, stop))
