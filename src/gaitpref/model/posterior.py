"""The Laplace posterior over all actions: mean, variance, covariance and joint samples.

From a :class:`~gaitpref.model.laplace.LaplaceMode` on the visited set ``V`` (``K_VV = L L^T``,
``I + L^T Lambda L = R R^T``), with ``P = L^-1 K_{V,:}``:

- mean        ``mu = K_{:,V} alpha``, ``alpha = K_VV^-1 f_hat_V``;
- covariance  ``Sigma = K - P^T P + (R^-1 P)^T (R^-1 P)``  (GPML eq. 3.24 in the visited subspace:
  the prior's conditional given ``f_V`` plus ``Sigma_VV = L (R R^T)^-1 L^T`` carried through it);
  the variance is its diagonal, ``k_aa - |P_a|^2 + |R^-1 P_a|^2``, computed block by block;
- samples (pathwise conditioning, Matheron's rule; Wilson et al. 2020): with a prior sample
  ``f0 ~ N(0, K)`` and ``w = L^-1 f0_V``,  ``f = f0 + K_{:,V} (alpha + L^-T (R^-T w - w))``, an
  exact draw from ``N(mu, Sigma)`` that costs ``O(A m)`` once ``f0`` is drawn.

Everything over all ``A`` actions goes through a
:class:`~gaitpref.model.cross.CrossCovariance` for ``K_{:,V}`` chosen by the model's engine
(``engines.py``): one ``A x m`` matrix on small grids, Kronecker tables and blocks of bounded
size on large ones.  Nothing ``A x A`` is built unless :meth:`Posterior.covariance` is called;
nothing ``A x m`` is built on the scalable path.

Notation: ``A`` actions, ``m`` visited, ``size`` samples; samples are ``size x A``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import cho_solve, solve_triangular
from scipy.special import ndtr

from gaitpref.checks import check_mask, is_noise
from gaitpref.model.cross import CrossCovariance, DenseCross
from gaitpref.model.engines import GridEngine, PointEngine
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.kronecker import KroneckerPriorSampler, check_sample_budget
from gaitpref.model.laplace import LaplaceMode
from gaitpref.model.ordinal import Ordinal, predictive_probabilities
from gaitpref.space import FloatArray, IntArray, Space

#: :meth:`Posterior.covariance` refuses grids whose ``A x A`` matrix would pass 1 GiB, and
#: :meth:`Posterior.covariance_at` as many actions.
COVARIANCE_LIMIT_ACTIONS = 11_585

__all__ = ["KroneckerPriorSampler", "Posterior", "random_argmax"]


def _readonly(a: FloatArray) -> FloatArray:
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Posterior:
    """Immutable Laplace posterior ``N(mean, Sigma)`` over every action of ``space``.

    ``fit`` is None for the prior (no data).  ``engine`` decides how ``A``-sized work is done
    (:attr:`sampler` names it); ``mean`` and ``variance`` are computed on first use and cached.
    """

    space: Space
    kernel: SquaredExponential
    fit: LaplaceMode | None
    engine: GridEngine
    noise: float | None = None  # the pairwise probit noise (preference_probability)
    ordinal: Ordinal | None = None  # the rating model (rating_probabilities)

    def __post_init__(self) -> None:
        noise = self.noise
        if noise is not None and not is_noise(noise):
            raise ValueError(
                f"preference noise must be None or positive with a finite square, got {noise!r}"
            )

    @property
    def visited(self) -> IntArray:
        return self.fit.visited if self.fit is not None else np.zeros(0, dtype=np.intp)

    @property
    def sampler(self) -> str:
        """The path in use: ``"dense"`` or ``"scalable"``."""
        return self.engine.name

    @cached_property
    def cross(self) -> CrossCovariance:
        """``K_{:,V}`` in the engine's representation."""
        return self.engine.cross(self.visited)

    @cached_property
    def _alpha(self) -> FloatArray:
        assert self.fit is not None
        return self.fit.alpha

    @cached_property
    def mean(self) -> FloatArray:
        """Posterior mean utility of every action (length ``A``)."""
        out = np.zeros((1, len(self.space)))
        if self.fit is not None:
            self.cross.add_product(out, self._alpha[:, None])
        return _readonly(out[0])

    def mean_at(self, actions: ArrayLike) -> FloatArray:
        """Posterior mean of the given actions only, ``O(len(actions) m)``."""
        idx = self.space.check_indices(actions)
        if self.fit is None:
            return np.zeros(idx.shape[0])
        out: FloatArray = self.cross.rows(idx) @ self._alpha
        return out

    def visited_cross(self, actions: ArrayLike) -> FloatArray:
        """``K[actions, V]``, the prior covariance of ``actions`` with the visited set, from the
        kernel (the strategies' covariances; ``population.py`` overrides it).  On a point set
        whose :attr:`cross` is already computed, its rows: the same floats as the kernel's
        (``PointEngine.cross``), without computing them again from the coordinates."""
        idx = np.asarray(actions, dtype=np.intp)
        cross = self._point_cross()
        if cross is not None and (idx.size == 0 or int(idx.min()) >= 0):
            return cross.rows(idx)
        out: FloatArray = self.kernel.cross(self.space, self.visited, rows=idx)
        return out

    def _point_cross(self) -> DenseCross | None:
        """:attr:`cross` on a point set once computed (``K_{:,V}``, each entry the kernel's
        floats: ``PointEngine.cross``), else None."""
        if not isinstance(self.engine, PointEngine) or "cross" not in self.__dict__:
            return None
        cross = self.cross
        return cross if isinstance(cross, DenseCross) else None

    def kernel_column(self, action: int) -> FloatArray:
        """``K[:, action]`` (a new array), from the kernel; on a point set whose :attr:`cross`
        is computed and has ``action`` among the visited, its column: the same floats."""
        cross = self._point_cross()
        visited = self.visited
        k = int(np.searchsorted(visited, action)) if cross is not None else visited.size
        if cross is not None and action >= 0 and k < visited.size and visited[k] == action:
            out: FloatArray = cross.matrix[:, k].copy()
            return out
        col = np.array([action], dtype=np.intp)
        column: FloatArray = self.kernel.cross(self.space, col)[:, 0].copy()
        return column

    @cached_property
    def variance(self) -> FloatArray:
        """Posterior marginal variance of every action (length ``A``), block by block."""
        var = self.kernel.diagonal(self.space)
        if self.fit is None:
            return _readonly(var)
        L, R = self.fit.chol_prior, self.fit.chol_hessian
        for start, block in self.cross.blocks():
            P = solve_triangular(L, block.T, lower=True, check_finite=False)
            Q = solve_triangular(R, P, lower=True, check_finite=False)
            stop = start + block.shape[0]
            var[start:stop] += np.einsum("ij,ij->j", Q, Q) - np.einsum("ij,ij->j", P, P)
        return _readonly(np.maximum(var, 0.0))

    @property
    def std(self) -> FloatArray:
        return np.sqrt(self.variance)

    def visited_solve(self, k_v: FloatArray) -> FloatArray:
        """``L^-T (p - (R R^T)^-1 p)`` with ``p = L^-1 k_v`` (columns of ``k_v``, ``m x c``):
        with ``K_{x,V}`` on the left it gives the data's correction to ``cov(f_x, f_y)`` for
        ``k_v = K_{V,y}`` (the module docstring's ``P^T P - Q^T Q`` for given columns)."""
        assert self.fit is not None
        L, R = self.fit.chol_prior, self.fit.chol_hessian
        p = solve_triangular(L, k_v, lower=True, check_finite=False)
        t = p - cho_solve((R, True), p, check_finite=False)
        out: FloatArray = solve_triangular(L, t, lower=True, trans="T", check_finite=False)
        return out

    def variance_at(self, actions: ArrayLike) -> FloatArray:
        """Posterior marginal variance of the given actions only, ``O(len(actions) m^2)``."""
        idx = self.space.check_indices(actions)
        var = np.asarray(self.kernel.diagonal(self.space), dtype=np.float64)[idx]
        if self.fit is None or idx.size == 0:
            return var
        P = solve_triangular(
            self.fit.chol_prior, self.cross.rows(idx).T, lower=True, check_finite=False
        )
        Q = solve_triangular(self.fit.chol_hessian, P, lower=True, check_finite=False)
        var += np.einsum("ij,ij->j", Q, Q) - np.einsum("ij,ij->j", P, P)
        out: FloatArray = np.maximum(var, 0.0)
        return out

    @cached_property
    def _variance_correction(self) -> FloatArray:
        """``C = M^T M - L^-T L^-1`` with ``M = R^-1 L^-1`` (``m x m``, ``O(m^3)`` once), so that
        the data's correction to a variance is one quadratic form, ``var_x = k_xx + k_x^T C k_x``
        with ``k_x = K[V, x]``: the same quantity as :meth:`variance_at`'s ``||Q||^2 - ||P||^2``."""
        assert self.fit is not None
        L, R = self.fit.chol_prior, self.fit.chol_hessian
        inv_l = solve_triangular(L, np.eye(L.shape[0]), lower=True, check_finite=False)
        m = solve_triangular(R, inv_l, lower=True, check_finite=False)
        out: FloatArray = m.T @ m - inv_l.T @ inv_l
        return out

    def variance_many(self, actions: ArrayLike) -> FloatArray:
        """As :meth:`variance_at`, for many actions at once: with more actions than visited ones
        the correction is :attr:`_variance_correction`'s quadratic form, one matrix product
        (``O(len(actions) m^2)`` still, but a product rather than two triangular solves: about
        3x faster at 57,750 actions and 300 visited); with fewer, :meth:`variance_at`.  The
        results agree to rounding (tested), not bit for bit."""
        idx = self.space.check_indices(actions)
        if self.fit is None or idx.size <= self.visited.size:
            return self.variance_at(idx)
        var = np.asarray(self.kernel.diagonal(self.space), dtype=np.float64)[idx]
        correction = self._variance_correction
        step = max(1, (1 << 22) // max(1, self.visited.size))  # bounded blocks of K[idx, V]
        for start in range(0, idx.size, step):
            k = self.cross.rows(idx[start : start + step])
            var[start : start + step] += np.einsum("ij,ij->i", k @ correction, k)
        out: FloatArray = np.maximum(var, 0.0)
        return out

    def covariance_at(self, actions: ArrayLike) -> FloatArray:
        """The posterior covariance among ``actions`` (``n x n``, ``O(n m^2)``); refuses more
        than :data:`COVARIANCE_LIMIT_ACTIONS` actions, as :meth:`covariance` does."""
        idx = self.space.check_indices(actions)
        if idx.size > COVARIANCE_LIMIT_ACTIONS:
            raise ValueError(
                f"covariance_at would build a {idx.size} x {idx.size} matrix "
                f"({idx.size**2 * 8 / 2**30:.1f} GiB; at most {COVARIANCE_LIMIT_ACTIONS} actions): "
                "use variance_at for the variances"
            )
        out: FloatArray = np.asarray(self.kernel.cross(self.space, idx, rows=idx), dtype=float)
        if self.fit is None:
            return out
        P = solve_triangular(self.fit.chol_prior, self.cross.rows(idx).T, lower=True)
        Q = solve_triangular(self.fit.chol_hessian, P, lower=True)
        result: FloatArray = out - P.T @ P + Q.T @ Q
        return result

    def preference_probability(self, a: int, b: int) -> float:
        """``P(a preferred to b)``: the probit with the noise and the posterior integrated out,
        ``Phi((mu_a - mu_b) / sqrt(2 sigma^2 + var_a + var_b - 2 cov_ab))``."""
        if self.noise is None:
            raise ValueError("this posterior was made without a preference noise")
        cov = self.covariance_at([self.space.check_index(a), self.space.check_index(b)])
        spread = 2.0 * self.noise**2 + cov[0, 0] + cov[1, 1] - 2.0 * cov[0, 1]
        mean = self.mean_at([a, b])
        return float(ndtr((mean[0] - mean[1]) / np.sqrt(max(spread, 1e-300))))

    def rating_probabilities(self, actions: ArrayLike) -> FloatArray:
        """``P(rating = k)`` for each of ``actions`` (``n x K``, ``model/ordinal.py``)."""
        if self.ordinal is None:
            raise ValueError("this posterior was made without an ordinal rating model")
        one = np.ndim(actions) == 0  # one action: a 1 x K table, as before
        idx = self.space.check_indices(np.reshape(actions, 1) if one else actions)
        var = np.diag(self.covariance_at(idx)) if idx.size <= 64 else self.variance[idx]
        thresholds = self.ordinal.thresholds_for(self.kernel.variance)
        return predictive_probabilities(self.ordinal, thresholds, self.mean_at(idx), var)

    def covariance(self) -> FloatArray:
        """The dense ``A x A`` posterior covariance (small grids: ``O(A^2 m)`` time).

        Raises ValueError above :data:`COVARIANCE_LIMIT_ACTIONS` actions (over 1 GiB).
        """
        size = len(self.space)
        if size > COVARIANCE_LIMIT_ACTIONS:
            raise ValueError(
                f"covariance() would build a {size} x {size} matrix "
                f"({size * size * 8 / 2**30:.1f} GiB); use variance, sample or argmax_samples"
            )
        K = self.kernel.dense(self.space)
        if self.fit is None:
            return K
        cross = np.concatenate([block for _, block in self.cross.blocks()])
        P = solve_triangular(self.fit.chol_prior, cross.T, lower=True, check_finite=False)
        Q = solve_triangular(self.fit.chol_hessian, P, lower=True, check_finite=False)
        out: FloatArray = K - P.T @ P + Q.T @ Q
        return out

    def sample(self, rng: np.random.Generator, size: int = 1, *, nugget: bool = True) -> FloatArray:
        """``size x A`` joint samples of the utilities over every action.

        ``nugget=False``: samples of the smooth part of the utility, without the kernel's
        jitter (the grid's independent per-gait term, ``kernels.py``), from the same draws:
        with ``f = g + e`` (``e`` the jitter's white noise), ``g = f - e - jitter C`` where
        ``C`` is the pathwise correction's coefficient on the visited columns (the jitter's share
        of ``K_{:,V}``).  The generator is used exactly as with the nugget.

        Memory: the ``size x A`` prior draw, into which the pathwise correction is added in
        place (and the jitter's draw without the nugget), plus the engine's bounded blocks; at
        its peak, while the prior's root is applied,
        :data:`~gaitpref.model.kronecker.SAMPLE_PEAK_ARRAYS` such arrays (one more without the
        nugget).  ``size x A`` may not pass
        :data:`~gaitpref.model.kronecker.SAMPLE_LIMIT_ELEMENTS` (1 GiB of float64): ValueError
        naming both, before anything is drawn.
        """
        size = check_sample_size(size, len(self.space))
        check_generator(rng)
        check_nugget(nugget)
        if self.fit is None or size == 0:
            f, e = self.engine.prior_parts(rng, size, jitter_part=not nugget)
            if not nugget and e is not None:
                f -= e
            return f
        f, f_visited, e = self._prior_draw(rng, size, jitter_part=not nugget)
        L, R = self.fit.chol_prior, self.fit.chol_hessian
        w = solve_triangular(L, f_visited.T, lower=True, check_finite=False)
        v = solve_triangular(R, w, lower=True, trans="T", check_finite=False) - w
        coef = solve_triangular(L, v, lower=True, trans="T", check_finite=False)
        coef += self._alpha[:, None]
        self.cross.add_product(f, coef)
        if not nugget and e is not None:
            f -= e
            columns, weight = self._jitter_columns()
            np.add.at(f.T, columns, -self.kernel.jitter * (coef * weight[:, None]))
        return f

    def _jitter_columns(self) -> tuple[IntArray, FloatArray]:
        """The grid action of each visited node and the weight of the jitter in its column of
        ``K_{:,V}`` (here the visited set is part of the grid: every weight is 1)."""
        return self.visited, np.ones(self.visited.shape[0])

    def _prior_draw(
        self, rng: np.random.Generator, size: int, *, jitter_part: bool = True
    ) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        """A joint prior draw over every action (``size x A``), the visited set (``size x
        m``) and the draw's jitter part over every action (None without jitter or
        ``jitter_part``); here the visited set is part of the grid (``model/population.py``
        overrides it)."""
        f, e = self.engine.prior_parts(rng, size, jitter_part=jitter_part)
        return f, f[:, self.visited], e

    def argmax_samples(
        self, rng: np.random.Generator, size: int, allowed: NDArray[np.bool_] | None = None
    ) -> IntArray:
        """The argmax of each of ``size`` joint samples, exact ties broken uniformly at random;
        with ``allowed``, the argmax over the allowed actions only.

        One pass over the samples as :meth:`sample` leaves them: no second ``size x A`` array.
        ``allowed`` is a boolean mask over every action with at least one true entry.
        """
        if len(self.space) == 0 and size:
            raise ValueError(_NO_ACTIONS)
        if allowed is not None:
            allowed = self._check_allowed(allowed)
        samples = self.sample(rng, size)
        if allowed is not None:
            samples[:, ~allowed] = -np.inf
        return np.array([random_argmax(s, rng) for s in samples], dtype=np.intp)

    def _check_allowed(self, allowed: object) -> NDArray[np.bool_]:
        """``allowed`` as a boolean mask over every action with an allowed one, else an error
        naming it (an all-false mask made every action equally likely: disallowed ones too)."""
        empty = "allowed allows no action: there is no argmax among none"
        return check_mask(allowed, len(self.space), empty=empty)

    @property
    def argmax(self) -> int:
        """The action with the highest posterior mean (lowest index among exact ties)."""
        if len(self.space) == 0:
            raise ValueError(_NO_ACTIONS)
        return int(np.argmax(self.mean))

    @property
    def log_evidence(self) -> float:
        """Laplace approximation of the data's log marginal likelihood (0 with no data)."""
        return self.fit.log_evidence if self.fit is not None else 0.0


#: What an argmax over no action says (a point set before its first point: the line path
#: before its first query).
_NO_ACTIONS = "the posterior has no actions yet (the line path's before its first query): no argmax"


def check_sample_size(size: object, points: int) -> int:
    """A number of samples over ``points`` points: an integer >= 0 (not a bool, not a float)
    within the sampling budget (:func:`~gaitpref.model.kronecker.check_sample_budget`)."""
    if isinstance(size, bool) or not isinstance(size, int | np.integer) or size < 0:
        raise ValueError(f"size (the number of samples) must be an integer >= 0, got {size!r}")
    check_sample_budget(int(size), points)
    return int(size)


def check_nugget(nugget: object) -> None:
    """``nugget`` is True or False (a string such as "False" was truthy: the jitter's part was
    kept, silently)."""
    if not isinstance(nugget, bool | np.bool_):
        raise TypeError(f"nugget must be True or False, got {nugget!r}")


def check_generator(rng: object) -> None:
    """Every random choice comes from an explicit generator (no seed, no global state)."""
    if not isinstance(rng, np.random.Generator):
        raise TypeError(
            f"rng must be a numpy.random.Generator (numpy.random.default_rng(seed)), got {rng!r}"
        )


def random_argmax(values: FloatArray, rng: np.random.Generator) -> int:
    """Index of the maximum of ``values``, exact ties broken uniformly at random with ``rng``."""
    best = np.flatnonzero(values == np.max(values))
    if best.size == 1:
        return int(best[0])
    return int(rng.choice(best))
