"""The Laplace approximation's log evidence and its gradient in the hyperparameters.

GPML (Rasmussen & Williams 2006) Section 5.5.1, eq. (5.20)-(5.24), written for a pairwise
likelihood and worked in the visited subspace ``V`` (``laplace.py``).  With the mode ``f`` on
``V`` (``f = K a``, ``a = G^T g``), ``W = G^T diag(c) G`` and ``Sigma = (K^-1 + W)^-1``:

    log q(D | theta) = sum_k log p_k(d_k) - 1/2 f^T K^-1 f - 1/2 log |I + K W|            (5.20)

Its derivative in a kernel parameter ``theta_j`` has an explicit part and an implicit one
through the mode's dependence on ``theta`` (the mode's own first-order terms vanish):

    explicit  1/2 a^T dK a - 1/2 tr((W - W Sigma W) dK)                                   (5.22)
    implicit  s2^T (I - Sigma W) dK a,     s2 = -1/2 G^T (c' * diag(G Sigma G^T))         (5.23-24)

(``c' = dc/dd``, the likelihood's third derivative; ``(I + K W)^-1 = I - Sigma W`` and
``W (I + K W)^-1 = W - W Sigma W`` need no inverse of the singular ``W``).  For the likelihood's
own parameter, ``log band`` of the ordered probit, the explicit part is
``sum_k dlog p_k - 1/2 sum_k dc_k (G Sigma G^T)_kk`` and the implicit one
``s2^T (I - Sigma W) K G^T dg``.  ``Sigma = S^T S`` with ``S = R^-1 L^T`` from the Laplace fit.

Single-action terms (``singles.py``; ordinal ratings) are observations of ``f_s``: they stack
under the pairs as rows ``e_s`` of ``G`` (``E``), so ``W`` gains ``E^T diag(c_s) E``, the first
term their ``log p``, and ``s2`` their third derivatives; every formula above holds with the
stacked ``G``.  Fitted ordinal thresholds ``t_j`` are likelihood parameters like the band:
explicit ``sum dlog p / dt_j - 1/2 sum dc / dt_j (E Sigma E^T)_ss``, implicit
``s2^T (I - Sigma W) K E^T dg / dt_j``; they enter ``theta`` as ``t_1`` and the log gaps
``log(t_(j+1) - t_j)`` (so they stay increasing), by the chain rule.  The rating noise is held
fixed like ``sigma`` (the same scale argument).

The parameters are ``theta = (log l_1, ..., log l_d, log s^2, log band)``: lengthscales, the
signal variance and the indifference band (then the thresholds' entries, when fitted).  The
jitter scales with ``s^2`` (its ratio to the signal variance is the config's), and the probit
noise ``sigma`` is held fixed: scaling ``f``, ``s``, ``sigma`` and the band by one factor leaves
every probability unchanged, so only ``s / sigma`` and ``band / sigma`` are identifiable, and
fixing ``sigma`` removes the redundancy.

Notation: ``N`` observations, ``m`` visited actions, ``d`` features; ``K`` is ``K_VV``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
import scipy.sparse
from numpy.typing import NDArray
from scipy.linalg import solve_triangular

from gaitpref.checks import is_number
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.laplace import LaplaceMode, check_visited, fit_laplace
from gaitpref.model.likelihood import OrderedProbit, check_scales
from gaitpref.model.singles import SingleData
from gaitpref.space import FloatArray, IntArray, Space


@dataclass(frozen=True)
class PairData:
    """Observations of ``d_k = f[first_k] - f[second_k]`` (grid indices).

    ``tie[k]``: a "no preference" answer; otherwise ``first`` was preferred.  ``banded[k]``:
    the indifference band applies (answers to comparisons); coactive suggestions are plain
    probit preferences (no band).
    """

    first: IntArray
    second: IntArray
    sigma: FloatArray
    banded: NDArray[np.bool_]
    tie: NDArray[np.bool_]

    def __post_init__(self) -> None:
        n = self.first.shape[0]
        shapes = {a.shape for a in (self.first, self.second, self.sigma, self.banded, self.tie)}
        if shapes != {(n,)}:
            raise ValueError("first, second, sigma, banded and tie need one entry per observation")
        for name in ("first", "second"):
            check_codes(getattr(self, name), name)
        if np.any(self.tie & ~self.banded):
            raise ValueError("a 'no preference' observation must be banded")
        check_scales(self.sigma, "sigma (each observation's probit noise)")

    @property
    def size(self) -> int:
        return int(self.first.shape[0])

    def likelihood(self, band: float) -> OrderedProbit:
        """The ordered probit with ``band`` on the banded observations (0 elsewhere)."""
        return OrderedProbit(self.sigma, np.where(self.banded, band, 0.0), self.tie)


@dataclass(frozen=True)
class Hyperparameters:
    """Kernel lengthscales (feature units), signal variance, jitter, indifference band, and
    the ordinal thresholds when the evidence fits them (None: not fitted)."""

    lengthscale: tuple[float, ...]
    variance: float
    jitter: float
    band: float = 0.0
    thresholds: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        ls = self.lengthscale
        items = list(ls) if isinstance(ls, tuple | list | np.ndarray) else []
        if not items or not all(_finite(v, 0.0) for v in items):
            raise ValueError(f"lengthscale must be a tuple of finite numbers > 0, got {ls!r}")
        if not _finite(self.variance, 0.0):
            raise ValueError(f"variance must be finite and > 0, got {self.variance!r}")
        for name in ("jitter", "band"):
            value = getattr(self, name)
            if not _finite(value, 0.0, strict=False):
                raise ValueError(f"{name} must be finite and >= 0, got {value!r}")
        t = self.thresholds
        if t is not None and not (isinstance(t, tuple | list) and all(_finite(v) for v in t)):
            raise ValueError(f"thresholds must be None or a tuple of finite numbers, got {t!r}")
        if t is not None and any(b < a for a, b in pairwise(t)):
            # out of order, their log gaps (log_vector, what a fit starts from) were NaN
            raise ValueError(f"thresholds must be in increasing order, got {t!r}")
        # plain floats in tuples: a NumPy array here made two values unequal to compare
        object.__setattr__(self, "lengthscale", tuple(float(v) for v in items))
        object.__setattr__(self, "variance", float(self.variance))
        object.__setattr__(self, "jitter", float(self.jitter))
        object.__setattr__(self, "band", float(self.band))
        if t is not None:
            object.__setattr__(self, "thresholds", tuple(float(v) for v in t))

    @classmethod
    def from_kernel(
        cls, kernel: SquaredExponential, ndim: int, band: float = 0.0
    ) -> Hyperparameters:
        return cls(kernel.lengthscales(ndim), kernel.variance, kernel.jitter, float(band))

    def kernel(self) -> SquaredExponential:
        return SquaredExponential(self.lengthscale, self.variance, self.jitter)

    def log_vector(self) -> FloatArray:
        """``(log l_1, ..., log l_d, log s^2, log band)`` (``log band = -inf`` for no band), then
        with thresholds ``(t_1, log(t_2 - t_1), ..., log(t_T - t_(T-1)))``: every value of
        this vector gives increasing thresholds."""
        with np.errstate(divide="ignore"):
            out: FloatArray = np.log(np.array([*self.lengthscale, self.variance, self.band]))
            if self.thresholds is not None:
                t = np.asarray(self.thresholds, dtype=np.float64)
                out = np.concatenate([out, t[:1], np.log(np.diff(t))])
        return out

    def with_log_vector(self, theta: FloatArray) -> Hyperparameters:
        """New values from a log vector; the jitter keeps its ratio to the signal variance."""
        theta = np.asarray(theta, dtype=np.float64)
        d = len(self.lengthscale)
        values = np.exp(theta[: d + 2])
        variance = float(values[d])
        thresholds = None
        if self.thresholds is not None:
            rest = theta[d + 2 :]
            if rest.shape != (len(self.thresholds),):
                raise ValueError(f"expected {d + 2 + len(self.thresholds)} entries")
            t = rest[0] + np.concatenate([[0.0], np.cumsum(np.exp(rest[1:]))])
            thresholds = tuple(float(x) for x in t)
        return Hyperparameters(
            tuple(float(v) for v in values[:d]),
            variance,
            self.jitter * variance / self.variance,
            float(values[d + 1]),
            thresholds,
        )


def check_codes(codes: object, name: str) -> None:
    """ValueError naming ``name`` unless ``codes`` is a 1-D array of integers >= 0: grid
    indices, or a population's node codes ``subject * A + gait`` (a float was truncated to a
    gait, a negative code wrapped to the last gait of subject -1)."""
    arr = np.asarray(codes)
    if arr.ndim != 1 or (arr.size and not np.issubdtype(arr.dtype, np.integer)):
        raise ValueError(
            f"{name} must be a 1-D array of integer indices, got dtype {arr.dtype} and shape "
            f"{arr.shape}"
        )
    if arr.size and int(arr.min()) < 0:
        raise ValueError(f"{name} must hold indices >= 0, got {int(arr.min())}")


def _finite(value: object, low: float = -np.inf, *, strict: bool = True) -> bool:
    """Whether ``value`` is a finite number above ``low`` (``>= low`` unless ``strict``)."""
    if not is_number(value):
        return False
    x = float(value)  # type: ignore[arg-type]
    return bool(np.isfinite(x) and (x > low if strict else x >= low))


@dataclass(frozen=True)
class Evidence:
    """Laplace log evidence, its gradient in :meth:`Hyperparameters.log_vector`, the fit."""

    value: float
    gradient: FloatArray  # (d + 2,), or (d + 2 + T,) with T fitted thresholds
    fit: LaplaceMode


def visited_pairs(data: PairData) -> tuple[IntArray, IntArray, IntArray]:
    """The visited grid actions (sorted) and each observation's pair as indices into them."""
    visited, inverse = np.unique(np.concatenate([data.first, data.second]), return_inverse=True)
    n = data.size
    return visited.astype(np.intp), inverse[:n].astype(np.intp), inverse[n:].astype(np.intp)


def _visited(
    data: PairData, singles: SingleData | None
) -> tuple[IntArray, IntArray, IntArray, IntArray | None]:
    if singles is None:
        return (*visited_pairs(data), None)
    n = data.size
    visited, inverse = np.unique(
        np.concatenate([data.first, data.second, singles.actions]), return_inverse=True
    )
    inv = inverse.astype(np.intp)
    return visited.astype(np.intp), inv[:n], inv[n : 2 * n], inv[2 * n :]


def laplace_evidence(
    space: Space,
    hyper: Hyperparameters,
    data: PairData,
    init: FloatArray | None = None,
    *,
    singles: SingleData | None = None,
) -> Evidence:
    """Log evidence and gradient at ``hyper``; ``init`` warm-starts the mode on the visited set.

    ``singles``: single-action terms besides the pairs; with ``hyper.thresholds`` set, those
    thresholds replace the fitted part's (:class:`~gaitpref.model.singles.SingleData`) and
    the gradient has their entries.  Raises what :func:`~gaitpref.model.laplace.fit_laplace`
    raises (``ConvergenceError``, ``PriorNotPositiveDefiniteError``).
    """
    if singles is not None and singles.size == 0:
        singles = None
    if data.size == 0 and singles is None:
        raise ValueError("the evidence needs at least one observation")
    space.check_indices(data.first, "data.first")
    space.check_indices(data.second, "data.second")
    if singles is not None:
        space.check_indices(singles.actions, "singles.actions")
    fitted = singles is not None and hyper.thresholds is not None and singles.thresholds is not None
    if singles is not None:
        singles = singles.at(hyper.thresholds)
    visited, a, b, s = _visited(data, singles)
    check_visited(visited.shape[0])  # before the m x m prior is built
    kernel = hyper.kernel()
    K = kernel.cross(space, visited, rows=visited)
    m = visited.shape[0]
    points = space.points_of(visited)  # not every grid point (A x d) for the visited ones

    def kernel_gradient(B: FloatArray) -> FloatArray:
        out = np.zeros(space.ndim + 1)
        se = K - kernel.jitter * np.eye(m)  # the squared-exponential part
        for j, ell in enumerate(hyper.lengthscale):
            dK = se * ((points[:, j, None] - points[None, :, j]) / ell) ** 2
            out[j] = float(np.sum(dK * B))
        out[space.ndim] = float(np.sum(K * B))  # dK / dlog s^2 = K (the jitter scales along)
        return out

    return evidence_from_prior(
        K, visited, (a, b, s), data, singles, hyper, kernel_gradient, init, fitted=fitted
    )


#: ``B -> d log q / d (kernel entries of theta)``, given ``B`` with ``d log q = sum(dK * B)``.
KernelGradient = Callable[[FloatArray], FloatArray]


def evidence_from_prior(
    K: FloatArray,
    visited: IntArray,
    indices: tuple[IntArray, IntArray, IntArray | None],
    data: PairData,
    singles: SingleData | None,
    hyper: Hyperparameters,
    kernel_gradient: KernelGradient,
    init: FloatArray | None = None,
    *,
    fitted: bool = False,
    sparse: bool = False,
) -> Evidence:
    """The Laplace evidence for any prior covariance ``K`` of the visited set (its entries
    ``visited`` are labels only), with the observations' ``indices`` into it (``first``,
    ``second``, single actions).  The gradient holds ``kernel_gradient(B)`` (the kernel's
    entries of ``theta``: eq. (5.22-24) give ``d log q = sum(dK * B)`` for each), then
    ``log band``, then the thresholds when ``fitted``.

    ``sparse``: ``G`` (two entries a row) and ``W = G^T diag(c) G`` (a graph Laplacian's
    pattern) held sparse, so that ``G Sigma``, ``diag(G Sigma G^T)`` and ``W Sigma W`` cost
    ``O(N m)`` instead of ``O(N m^2)`` and ``O(m^3)``: the same numbers up to rounding, not to
    the bit (a warm start's ``rho`` fit, whose result is recorded, uses it; the single-subject
    refits, which replay, do not).
    """
    a, b, s = indices
    lik = data.likelihood(hyper.band)
    single_lik = None if singles is None else singles.likelihood
    fit = fit_laplace(K, visited, a, b, lik, init, single=s, single_likelihood=single_lik)
    m = visited.shape[0]
    f = fit.mode
    diff = f[a] - f[b]
    _, g, c = lik.terms(diff)
    third = lik.third(diff)
    if singles is not None and s is not None:  # rows e_s below the pairs' (module docstring)
        _, g_s, c_s = singles.likelihood.terms(f[s])
        g, c = np.concatenate([g, g_s]), np.concatenate([c, c_s])
        third = np.concatenate([third, singles.third(f[s])])
    G = _incidence(a, b, s, m, sparse)
    alpha = G.T @ g
    S = solve_triangular(fit.chol_hessian, fit.chol_prior.T, lower=True, check_finite=False)
    Sigma = S.T @ S
    if isinstance(G, np.ndarray):
        W = G.T @ (c[:, None] * G)
        GS = G @ Sigma
        v = np.einsum("kj,kj->k", GS, G)  # diag(G Sigma G^T)
        s2 = -0.5 * (G.T @ (third * v))
        q = s2 - W @ (Sigma @ s2)  # (I - W Sigma) s2
        B = 0.5 * np.outer(alpha, alpha) - 0.5 * (W - W @ Sigma @ W) + np.outer(q, alpha)
    else:
        Ws = (G.T @ scipy.sparse.diags_array(c) @ G).tocsr()
        v = np.asarray(G.multiply(G @ Sigma).sum(axis=1)).ravel()  # diag(G Sigma G^T)
        s2 = -0.5 * (G.T @ (third * v))
        q = s2 - Ws @ (Sigma @ s2)
        WSW = Ws @ (Ws @ Sigma).T  # W Sigma W (both symmetric)
        B = 0.5 * np.outer(alpha, alpha) - 0.5 * (Ws.toarray() - WSW) + np.outer(q, alpha)
    n_thresholds = 0 if hyper.thresholds is None else len(hyper.thresholds)
    kernel_part = kernel_gradient(B)
    nk = kernel_part.shape[0]
    grad = np.zeros(nk + 1 + n_thresholds)
    grad[:nk] = kernel_part
    n = data.size
    if hyper.band > 0 and np.any(data.banded):
        dlogp, dg, dc = lik.band_terms(diff)
        explicit = float(np.sum(dlogp)) - 0.5 * float(np.sum(dc * v[:n]))
        grad[nk] = explicit + float(q @ (K @ (G[:n].T @ dg)))
    if fitted and singles is not None and s is not None and hyper.thresholds is not None:
        # K E^T (the sparse E on the left: K is symmetric)
        KE = K @ G[n:].T if isinstance(G, np.ndarray) else np.asarray((G[n:] @ K).T)
        grad[nk + 1 :] = _threshold_gradient(singles, f[s], v[n:], q, KE, hyper.thresholds)
    return Evidence(fit.log_evidence, grad, fit)


def _incidence(
    a: IntArray, b: IntArray, s: IntArray | None, m: int, sparse: bool
) -> FloatArray | scipy.sparse.csr_array:
    """``G``: a row ``e_a - e_b`` per pair, then ``e_s`` per single action (``N x m``)."""
    n = a.shape[0]
    ns = 0 if s is None else s.shape[0]
    if not sparse:
        G = np.zeros((n + ns, m))
        G[np.arange(n), a] += 1.0
        G[np.arange(n), b] -= 1.0
        if s is not None:
            G[n + np.arange(ns), s] = 1.0
        return G
    rows = np.concatenate([np.arange(n), np.arange(n), n + np.arange(ns)])
    cols = np.concatenate([a, b, np.zeros(0, np.intp) if s is None else s])
    values = np.concatenate([np.ones(n), -np.ones(n), np.ones(ns)])
    return scipy.sparse.csr_array((values, (rows, cols)), shape=(n + ns, m))  # sums repeats


def _threshold_gradient(
    singles: SingleData,
    values: FloatArray,
    v: FloatArray,
    q: FloatArray,
    KE: FloatArray,
    thresholds: tuple[float, ...],
) -> FloatArray:
    """The gradient in ``(t_1, log gaps)`` (:meth:`Hyperparameters.log_vector`): per threshold
    ``sum dlog p - 1/2 sum dc v + q^T K E^T dg``, then the chain rule ``t_j = t_1 + sum gaps``."""
    dlogp, dg, dc = singles.threshold_terms(values)
    per_t = dlogp.sum(axis=0) - 0.5 * (v @ dc) + q @ (KE @ dg)
    gaps = np.diff(np.asarray(thresholds, dtype=np.float64))
    tail = np.cumsum(per_t[::-1])[::-1]  # tail[j] = sum_{i >= j} per_t[i]
    out: FloatArray = np.concatenate([tail[:1], gaps * tail[1:]])
    return out
