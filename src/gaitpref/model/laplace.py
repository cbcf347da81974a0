"""Laplace mode of the preference GP by Newton's method in the visited subspace.

Chu & Ghahramani (2005), Section 3; ``docs/model.md``, "Laplace mode".  The
negative log posterior ``S(f) = 1/2 f^T K^-1 f - sum_k log p_k(f_a - f_b)`` depends on ``f`` off
the ``m`` visited actions ``V`` only through the prior, so its mode is ``f_hat = K_{:,V} a`` and we
solve for ``f_V`` alone, in whitened coordinates ``f_V = L u`` (``K_VV = L L^T``):

    S(u) = 1/2 u^T u - sum_k log p_k(d_k),     d = G L u
    grad = u - L^T G^T g,                       Hess = I + H^T H,  H = diag(sqrt(c)) G L

(``G``: ``N x m`` signed incidence, ``g`` and ``c`` the likelihood's derivative and curvature).
Observations come in two shapes: on a *pair* of actions (``d_k = f_a - f_b``: preferences, ties,
coactive suggestions; row ``k`` of ``G`` is ``e_a - e_b``) and on a *single* action (``d_k = f_s``:
what ordinal ratings need; row ``k`` is ``e_s``).  Both enter ``S``, its gradient and ``H`` the
same way; with no single-action terms the arithmetic is the pair-only fit's, operation for
operation.
``Hess >= I``, so each Newton step is a well-conditioned Cholesky solve (GPML Algorithm 3.1 in
the comparison form, no ``W^-1``, no ``K^-1``).  A backtracking (Armijo) line search keeps every
step a descent step, and the loop stops when the gradient is below tolerance; otherwise it raises
:class:`ConvergenceError`.  It never returns the prior silently, and a Hessian that cannot be
factorised (curvature that overflows) is a :class:`ConvergenceError` too, never a raw
``LinAlgError``.

Notation: ``N`` observations, ``m`` visited actions, ``u`` and ``f_V`` length ``m``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any, NamedTuple

import numpy as np
from scipy.linalg import LinAlgError, cho_solve, cholesky, solve_triangular

from gaitpref.checks import is_count, is_number
from gaitpref.errors import ConvergenceError, PriorNotPositiveDefiniteError
from gaitpref.model import fit_memo
from gaitpref.model.likelihood import ActionLikelihood, PairLikelihood
from gaitpref.space import FloatArray, IntArray

#: The most distinct actions a fit is dense in: ``K_VV`` and the Hessian's factor are ``m x m``
#: (at this bound 800 MB each, and each Newton step ``O(m^3)``); a session's visited gaits are a
#: few hundred, but a simulated run of many trials on a large grid or the line path visits a new
#: gait nearly every trial, and one of ``MAX_TRIALS`` would have asked for tens of gigabytes.
MAX_VISITED = 10_000


def check_visited(m: int) -> None:
    """Refuse a fit over more than :data:`MAX_VISITED` distinct actions, before its ``m x m``
    prior covariance is built (``ValueError`` naming the count and the bound)."""
    if m > MAX_VISITED:
        raise ValueError(
            f"the answers involve {m:,} distinct gaits, more than the {MAX_VISITED:,} a posterior "
            f"is fitted over (dense in them: an {m:,} x {m:,} matrix of "
            f"{8 * m * m / 1e9:.1f} GB, and O(m^3) work for each answer); ask for fewer trials"
        )


@dataclass(frozen=True)
class Recipe:
    """What remakes a fit's two ``m x m`` factors from its mode, bit for bit: the prior
    covariance of the visited set (``prior``, a function that builds it as the fit's caller
    did), the observations' indices into it and their likelihoods.  ``O(N + m)`` to hold, where
    the factors take ``2 m^2`` numbers: a session keeps one fit per answer for undo.
    """

    prior: Callable[[], FloatArray]
    first: IntArray
    second: IntArray
    likelihood: PairLikelihood
    single: IntArray | None = None
    single_likelihood: ActionLikelihood | None = None

    def chol_prior(self) -> FloatArray:
        """``L`` with ``K_VV = L L^T``, as the fit factorised it."""
        return _factor_prior(self.prior())

    def factors(self, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``(L, R)`` at the whitened mode ``u``: the arithmetic of :func:`fit_laplace`'s last
        iteration, operation for operation (the same BLAS threads give the same bits)."""
        L = self.chol_prior()
        rows = _rows(L, self.first, self.second, self.single)
        _, _, c = _terms(L @ u, self.first, self.second, self.likelihood, self.single,
                         self.single_likelihood)  # fmt: skip
        return L, _hessian_factor(c, rows, 0, rows.shape[0])


@dataclass(frozen=True)
class LaplaceMode:
    """The Laplace fit on the visited set: everything the posterior needs, nothing over ``A``.

    ``factors`` is ``(L, R)``: ``K_VV = L L^T`` and ``I + H^T H = R R^T`` at the mode, two
    ``m x m`` lower factors.  A fit made with a :class:`Recipe` can drop them
    (:meth:`stripped`, what a session keeps for each answer's undo) and remake them, the same to
    the bit under the same BLAS threads, when they are read (:meth:`restored` keeps them).
    """

    visited: IntArray  # (m,) sorted grid indices
    whitened_mode: FloatArray  # (m,) u_hat, f_V = L u_hat
    iterations: int
    gradient_norm: float
    log_likelihood: float  # sum_k log p_k at the mode
    factors: tuple[FloatArray, FloatArray] | None = field(default=None, repr=False)
    recipe: Recipe | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.factors is None and self.recipe is None:
            raise ValueError("a Laplace fit needs its factors or a recipe to remake them")

    @property
    def chol_prior(self) -> FloatArray:
        """``L``, lower, ``K_VV = L L^T`` (remade when stripped: one ``m x m`` Cholesky)."""
        if self.factors is not None:
            return self.factors[0]
        assert self.recipe is not None
        return self.recipe.chol_prior()

    @property
    def chol_hessian(self) -> FloatArray:
        """``R``, lower, ``I + H^T H = R R^T`` at the mode (remade when stripped)."""
        return self._factors()[1]

    def _factors(self) -> tuple[FloatArray, FloatArray]:
        if self.factors is not None:
            return self.factors
        assert self.recipe is not None
        return self.recipe.factors(self.whitened_mode)

    @property
    def stripped(self) -> LaplaceMode:
        """The same fit without its factors, if it can remake them (else itself)."""
        return self if self.recipe is None else replace(self, factors=None)

    @property
    def restored(self) -> LaplaceMode:
        """The same fit holding its factors (remade once if stripped)."""
        return self if self.factors is not None else replace(self, factors=self._factors())

    @property
    def mode(self) -> FloatArray:
        """``f_hat`` on the visited actions."""
        return self.chol_prior @ self.whitened_mode

    @property
    def alpha(self) -> FloatArray:
        """``K_VV^-1 f_hat_V`` (so that the mean everywhere is ``K_{:,V} alpha``)."""
        out: FloatArray = solve_triangular(
            self.chol_prior, self.whitened_mode, lower=True, trans="T"
        )
        return out

    @property
    def log_evidence(self) -> float:
        """Laplace approximation of ``log p(D)``: ``sum log p - u^T u / 2 - log|I + H^T H| / 2``."""
        u = self.whitened_mode
        logdet = 2.0 * float(np.sum(np.log(np.diag(self.chol_hessian))))
        return self.log_likelihood - 0.5 * float(u @ u) - 0.5 * logdet


def _factor_prior(k_vv: FloatArray) -> FloatArray:
    try:
        factor: FloatArray = cholesky(k_vv, lower=True, check_finite=False)
        return factor
    except LinAlgError:
        raise PriorNotPositiveDefiniteError(
            f"the prior covariance of the {k_vv.shape[0]} visited actions is not positive "
            "definite; increase the kernel's jitter"
        ) from None


def _factor_hessian(hess: FloatArray, iteration: int, observations: int) -> FloatArray:
    """``R`` with ``I + H^T H = R R^T``; a named :class:`ConvergenceError` if it cannot be had.

    The Hessian is ``>= I`` in exact arithmetic; it fails only when the likelihood's curvature
    overflows or is not finite (a near-deterministic likelihood: tiny noise, huge signal).
    """
    try:
        if not np.all(np.isfinite(hess)):
            raise LinAlgError("the Hessian is not finite")
        factor: FloatArray = cholesky(hess, lower=True, check_finite=False)
        return factor
    except LinAlgError as exc:
        raise ConvergenceError(
            f"Laplace fit: the Hessian at Newton iteration {iteration} cannot be factorised "
            f"({exc}; {observations} observations over {hess.shape[0]} actions): the likelihood "
            "is nearly deterministic; use a larger noise or a smaller signal variance"
        ) from None


def _rows(L: FloatArray, first: IntArray, second: IntArray, single: IntArray | None) -> FloatArray:
    """``G L``: the pair rows ``L[a] - L[b]``, then the single rows ``L[s]``."""
    rows: FloatArray = L[first] - L[second]
    if single is not None:
        rows = np.vstack([rows, L[single]])
    return rows


def _terms(
    f: FloatArray,
    first: IntArray,
    second: IntArray,
    likelihood: PairLikelihood,
    single: IntArray | None,
    single_likelihood: ActionLikelihood | None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Every observation's ``(log p, g, c)`` at ``f_V``: the pairs', then the single actions'."""
    logp, g, c = likelihood.terms(f[first] - f[second])
    if single is not None and single_likelihood is not None:
        s_logp, s_g, s_c = single_likelihood.terms(f[single])
        logp, g, c = (np.concatenate(p) for p in ((logp, s_logp), (g, s_g), (c, s_c)))
    return logp, g, c


def _gradient(
    u: FloatArray,
    g: FloatArray,
    L: FloatArray,
    first: IntArray,
    second: IntArray,
    single: IntArray | None,
) -> FloatArray:
    """``u - L^T G^T g``: the objective's gradient in whitened coordinates."""
    m, n_pairs = u.shape[0], first.shape[0]
    g_pair = g[:n_pairs]
    grad_f = np.bincount(first, g_pair, m) - np.bincount(second, g_pair, m)
    if single is not None:
        grad_f = grad_f + np.bincount(single, g[n_pairs:], m)
    out: FloatArray = u - L.T @ grad_f
    return out


def _hessian_factor(
    c: FloatArray, rows: FloatArray, iteration: int, observations: int
) -> FloatArray:
    """``R`` with ``R R^T = I + H^T H``, ``H = diag(sqrt(c)) G L``."""
    H = np.sqrt(c)[:, None] * rows
    hess = H.T @ H
    hess[np.diag_indices_from(hess)] += 1.0
    return _factor_hessian(hess, iteration, observations)


_Objective = Callable[[FloatArray], tuple[float, FloatArray, FloatArray, FloatArray]]


class _Problem(NamedTuple):
    """What each iteration reads: the objective, ``L``, the rows ``G L`` and ``G``'s indices."""

    objective: _Objective
    L: FloatArray
    rows: FloatArray
    first: IntArray
    second: IntArray
    single: IntArray | None

    def gradient(self, u: FloatArray, g: FloatArray) -> FloatArray:
        return _gradient(u, g, self.L, self.first, self.second, self.single)


def _line_search(
    objective: _Objective, u: FloatArray, value: float, step: FloatArray, slope: float
) -> tuple[Any, float, Any, Any, Any]:
    """Backtracking with the Armijo condition; ``(None, ...)`` if no step decreases ``S``."""
    t = 1.0
    for _ in range(60):
        trial = u + t * step
        new_value, logp, g, c = objective(trial)
        if np.isfinite(new_value) and new_value <= value + 1e-4 * t * slope:
            return trial, new_value, logp, g, c
        t *= 0.5
    return None, value, None, None, None


def fit_laplace(
    k_vv: FloatArray,
    visited: IntArray,
    first: IntArray,
    second: IntArray,
    likelihood: PairLikelihood,
    init: FloatArray | None = None,
    *,
    single: IntArray | None = None,
    single_likelihood: ActionLikelihood | None = None,
    tol: float = 1e-11,
    max_iter: int = 100,
    prior: Callable[[], FloatArray] | None = None,
) -> LaplaceMode:
    """Newton's method for ``u_hat``; observations are ``d_k = f[first_k] - f[second_k]``.

    ``k_vv`` is the prior covariance of the grid actions ``visited``; ``first``/``second`` index
    into the visited set (``0..m-1``); ``init`` is a starting ``f_V`` (the previous posterior's
    mean there).  ``single`` (indices into the visited set) with ``single_likelihood`` adds
    observations of single utilities ``f[single_k]``.  ``prior``: a function that builds
    ``k_vv`` again, as the caller built it; with it the fit can drop its factors and remake
    them (:attr:`LaplaceMode.stripped`).
    """
    if (single is None) != (single_likelihood is None):
        raise ValueError("single and single_likelihood go together")
    if single is not None and single.size == 0:
        single = single_likelihood = None
    _check_problem(k_vv, visited, first, second, single, tol, max_iter)
    tol, max_iter = float(tol), int(max_iter)
    m = k_vv.shape[0]
    if init is not None and np.shape(init) != (m,):
        raise ValueError(
            f"init must hold one value per visited action ({m}), got shape {np.shape(init)}"
        )
    L = _factor_prior(k_vv)
    u = (
        np.zeros(m)
        if init is None
        else solve_triangular(L, np.asarray(init, dtype=np.float64), lower=True)
    )
    if not np.all(np.isfinite(u)):
        u = np.zeros(m)

    n_pairs = first.shape[0]
    # every observation, pairs and single actions, for the error messages
    n_obs = n_pairs + (0 if single is None else single.shape[0])
    rows = _rows(L, first, second, single)
    recipe = (
        None
        if prior is None
        else Recipe(prior, first, second, likelihood, single, single_likelihood)
    )

    def objective(u_: FloatArray) -> tuple[float, FloatArray, FloatArray, FloatArray]:
        logp, g, c = _terms(L @ u_, first, second, likelihood, single, single_likelihood)
        return 0.5 * float(u_ @ u_) - float(np.sum(logp)), logp, g, c

    memo = fit_memo.active() if m >= fit_memo.MEMO_FROM else None
    key = None
    if memo is not None:
        key = fit_memo.problem_key(
            k_vv, first, second, single, init, likelihood, single_likelihood,
            np.float64(tol), np.int64(max_iter),
        )  # fmt: skip
    problem = _Problem(objective, L, rows, first, second, single)
    if memo is not None:
        remembered = None if key is None else memo.get(key)
        if remembered is not None and remembered.mode.shape == (m,):
            checked = _at_remembered(remembered, problem, tol)
            if checked is not None:
                at, gnorm, R, logp = checked
                return LaplaceMode(visited, at, 1, gnorm, float(np.sum(logp)), (L, R), recipe)
    mode = _newton(u, problem, n_obs, tol, max_iter,
                   lambda it, u_, gnorm_, R, logp_: LaplaceMode(
                       visited, u_, it, gnorm_, float(np.sum(logp_)), (L, R), recipe))  # fmt: skip
    if memo is not None and key is not None:
        memo.put(key, fit_memo.Remembered(mode.whitened_mode, mode.gradient_norm))
    return mode


#: The most Newton iterations a fit may be given (``max_iter``): each is ``O(m^3)``, and a fit
#: converges in tens (100, the default, is already a failure's bound).
MAX_NEWTON_ITERATIONS = 10_000


def _check_problem(
    k_vv: FloatArray,
    visited: IntArray,
    first: IntArray,
    second: IntArray,
    single: IntArray | None,
    tol: float,
    max_iter: int,
) -> None:
    """ValueError naming what :func:`fit_laplace` cannot fit: a tolerance of inf (or 1 and
    more) accepted the start, the prior, as the mode at once; NaN or 0 never converged; a
    ``max_iter`` of 0 or less failed without an iteration, and one without bound could run
    without end; an index off the visited set was NumPy's IndexError."""
    if not (is_number(tol) and 0 < tol < 1):
        raise ValueError(f"tol must be a number in (0, 1), got {tol!r}")
    if not is_count(max_iter) or not 1 <= max_iter <= MAX_NEWTON_ITERATIONS:
        raise ValueError(
            f"max_iter must be an integer in 1..{MAX_NEWTON_ITERATIONS:,}, got {max_iter!r}"
        )
    m = visited.shape[0] if visited.ndim == 1 else -1
    if m < 0 or k_vv.shape != (m, m):
        raise ValueError(
            f"k_vv must be the {visited.shape} visited actions' square prior covariance, got "
            f"shape {k_vv.shape}"
        )
    if not np.all(np.isfinite(k_vv)):  # blamed on the likelihood's curvature before
        raise ValueError("k_vv, the visited actions' prior covariance, must be finite")
    if first.shape != second.shape:
        raise ValueError(f"first and second differ in shape: {first.shape} and {second.shape}")
    for name, idx in (("first", first), ("second", second), ("single", single)):
        if idx is None or idx.size == 0:
            continue
        if idx.ndim != 1 or not np.issubdtype(idx.dtype, np.integer):
            raise ValueError(
                f"{name} must be a 1-D array of indices into the visited set, got dtype "
                f"{idx.dtype} and shape {idx.shape}"
            )
        low, high = int(idx.min()), int(idx.max())
        if low < 0 or high >= m:
            raise ValueError(
                f"{name} holds {low if low < 0 else high}, not an index into the {m} visited "
                f"actions (0..{m - 1})"
            )


def _at_remembered(
    remembered: fit_memo.Remembered, problem: _Problem, tol: float
) -> tuple[FloatArray, float, FloatArray, FloatArray] | None:
    """The fit's last iteration at a remembered mode, ``(u, gnorm, R, logp)``: its numbers, if
    the gradient there passes :func:`_newton`'s test (or is the remembered norm exactly, within
    its rounding allowance); None otherwise, or if the entry's arithmetic fails (a damaged
    cache under a raising NumPy error state): the caller fits from its start."""
    at = remembered.mode.copy()
    try:
        _, logp, g, c = problem.objective(at)
        gnorm = float(np.max(np.abs(problem.gradient(at, g))))
        scale = max(1.0, float(np.max(np.abs(at))))
        if gnorm <= tol * scale or (
            gnorm == remembered.gradient_norm and gnorm <= 1e3 * tol * scale
        ):
            return at, gnorm, _hessian_factor(c, problem.rows, 1, problem.rows.shape[0]), logp
    except (ArithmeticError, ConvergenceError):
        return None
    return None


def _newton(
    u: FloatArray,
    problem: _Problem,
    n_obs: int,
    tol: float,
    max_iter: int,
    done: Callable[[int, FloatArray, float, FloatArray, FloatArray], LaplaceMode],
) -> LaplaceMode:
    """:func:`fit_laplace`'s Newton iterations from ``u``; ``done(iteration, u, gnorm, R, logp)``
    makes the result."""
    m = u.shape[0]
    objective, rows = problem.objective, problem.rows
    value, logp, g, c = objective(u)
    gnorm = last_full_step_gnorm = np.inf
    for iteration in range(1, max_iter + 1):
        grad = problem.gradient(u, g)
        gnorm = float(np.max(np.abs(grad))) if m else 0.0
        R = _hessian_factor(c, rows, iteration, n_obs)
        scale = max(1.0, float(np.max(np.abs(u)))) if m else 1.0
        if gnorm <= tol * scale:
            return done(iteration, u, gnorm, R, logp)
        step = -cho_solve((R, True), grad, check_finite=False)
        slope = float(grad @ step)
        # Once the predicted decrease is below the objective's rounding, a line search cannot
        # see progress: take the full Newton step while the gradient keeps shrinking.
        if -slope <= 64 * np.finfo(float).eps * max(1.0, abs(value)):
            if gnorm >= last_full_step_gnorm:
                if gnorm <= 1e3 * tol * scale:  # at the mode to rounding
                    return done(iteration, u, gnorm, R, logp)
                raise ConvergenceError(
                    f"Laplace fit stalled at Newton iteration {iteration} (gradient "
                    f"{gnorm:.3e}; {n_obs} observations over {m} actions)"
                )
            last_full_step_gnorm = gnorm
            trial = u + step
            new_value, new_logp, new_g, new_c = objective(trial)
        else:
            trial, new_value, new_logp, new_g, new_c = _line_search(
                objective, u, value, step, slope
            )
            if trial is None:
                raise ConvergenceError(
                    f"Laplace fit: line search failed at Newton iteration {iteration} "
                    f"(gradient {gnorm:.3e}, {n_obs} observations over {m} actions)"
                )
        u, value, logp, g, c = trial, new_value, new_logp, new_g, new_c
    raise ConvergenceError(
        f"Laplace fit did not converge in {max_iter} Newton iterations "
        f"(gradient {gnorm:.3e} > tolerance {tol:.1e}; {n_obs} observations over "
        f"{m} actions)"
    )
