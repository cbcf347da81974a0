"""Many subjects in one preference GP: a kernel over (gait, subject) and one subject's posterior.

Each subject's utility is a shared part plus their own (an intrinsic coregionalisation model with
one shared and one individual component; Bonilla, Chai & Williams 2008, eq. (2), with the task
covariance ``rho 1 1^T + (1 - rho) I``):

    k((x, s), (x', s')) = k(x, x') (rho + (1 - rho) [s = s'])

i.e. ``f(x, s) = sqrt(rho) g(x) + sqrt(1 - rho) h_s(x)`` with ``g``, ``h_s`` independent draws
from the single-subject prior ``k`` (``kernels.py``, jitter included).  ``rho = 0``: the subjects
are independent, and a subject's posterior is the single-subject one; ``rho = 1``: they share one
utility, and the data pool as one subject's (a (gait, subject) pair is then its gait alone).

Observations name *nodes*, codes ``subject * A + gait`` (``A`` grid actions), so
:class:`~gaitpref.model.evidence.PairData` and :class:`~gaitpref.model.singles.SingleData` carry
them unchanged.  The Laplace fit runs in the visited subspace as for one subject (``laplace.py``):
the visited set is the distinct (gait, subject) pairs, so its cost grows with them, never with
the grid times the subjects.  One subject's posterior over the whole grid
(:class:`PopulationPosterior`) reads the fit through the cross-covariance
``K_{t,V} = k(x, x_V) (rho + (1 - rho) [s_V = t])``: the single-subject cross-covariance of the
visited gaits with a column scaling.  Its samples (pathwise, ``posterior.py``) need a joint
prior draw of the subject's grid and the visited nodes: ``g`` and ``h_t`` over the grid by the
model's engine, ``h_s`` of the other subjects on their visited gaits only (a Cholesky factor).

The new subject (subject 0) may have a shared fraction of their own, ``share`` (``rho_0``):
``f(x, 0) = sqrt(rho_0) g(x) + sqrt(1 - rho_0) h_0(x)``, the others as above, so the
new subject's covariance with another subject is ``sqrt(rho_0 rho) k(x, x')`` (a rank-one-plus-
diagonal task covariance, Bonilla et al. 2008, eq. (2), with per-task loadings); ``share = None``
is ``rho_0 = rho``, the model above, and ``share = 0`` leaves the new subject alone.  It is
re-learned as the new subject answers (``share_fit.py``, ``loop/warm.py``).

The evidence (``evidence.py``, GPML eq. (5.20)-(5.24)) gains the entry ``logit rho`` with
``dK / dlogit rho = rho (1 - rho) k(x, x') [s != s']``; :func:`fit_population` maximises it
with the lengthscales (and whatever else the :class:`HyperPrior` frees) under a logit-normal
prior on ``rho`` (``population_fit.py``).

Notation: ``A`` actions, ``S`` subjects, ``m`` visited nodes, ``u`` distinct visited gaits.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from functools import cached_property, partial

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import cholesky

from gaitpref.checks import is_count, is_noise, is_number
from gaitpref.model.cross import CrossCovariance
from gaitpref.model.engines import GridEngine, check_grid_size, make_engine
from gaitpref.model.evidence import (
    Evidence,
    Hyperparameters,
    PairData,
    check_codes,
    evidence_from_prior,
)
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.laplace import LaplaceMode, fit_laplace
from gaitpref.model.likelihood import ActionLikelihood, PairLikelihood
from gaitpref.model.ordinal import Ordinal
from gaitpref.model.posterior import Posterior
from gaitpref.model.singles import SingleData
from gaitpref.space import FloatArray, IntArray, Space


def check_rho(rho: float) -> float:
    """``rho`` as a float in ``[0, 1]``; ValueError otherwise (a number: "0.5" and True were
    read as 0.5 and 1)."""
    if not is_number(rho):
        raise ValueError(f"the population's shared fraction rho must lie in [0, 1], got {rho!r}")
    value = float(rho)
    if not (np.isfinite(value) and 0.0 <= value <= 1.0):
        raise ValueError(f"the population's shared fraction rho must lie in [0, 1], got {rho!r}")
    return value


def node_codes(space: Space, gaits: IntArray, subjects: IntArray) -> IntArray:
    """The node codes ``subject * A + gait`` of (gait, subject) pairs."""
    gaits = np.asarray(gaits, dtype=np.intp)
    subjects = np.asarray(subjects, dtype=np.intp)
    size = len(space)
    if np.any((gaits < 0) | (gaits >= size)):
        raise IndexError(f"a gait index is off the grid (0..{size - 1})")
    if np.any(subjects < 0):
        raise IndexError("subject indices must be >= 0")
    out: IntArray = subjects * size + gaits
    return out


def check_share(rho: float, share: float | None) -> float | None:
    """The new subject's shared fraction (None: ``rho``); it needs ``rho < 1``."""
    if share is None:
        return None
    value = check_rho(share)
    if rho >= 1.0:
        raise ValueError("the new subject's shared fraction (share) needs rho < 1")
    return value


def subject_weights(
    rows: IntArray, cols: IntArray, rho: float, share: float | None = None
) -> FloatArray:
    """The task covariance between subjects ``rows`` and ``cols``: 1 for the same subject,
    ``rho`` between two others, ``sqrt(rho share)`` between subject 0 and another."""
    same = rows[:, None] == cols[None, :]
    out: FloatArray = np.where(same, 1.0, rho)
    if share is not None:
        new = (rows[:, None] == 0) != (cols[None, :] == 0)
        out = np.where(new, rho if share == rho else float(np.sqrt(rho * share)), out)
    return out


def population_prior(
    space: Space,
    kernel: SquaredExponential,
    rho: float,
    rows: IntArray,
    cols: IntArray,
    share: float | None = None,
) -> FloatArray:
    """``k((x, s), (x', s'))`` between node codes ``rows`` and ``cols``."""
    size = len(space)
    out: FloatArray = kernel.cross(space, cols % size, rows=rows % size)
    if rho < 1.0:
        out *= subject_weights(rows // size, cols // size, rho, share)
    return out


def pooled(space: Space, codes: IntArray, rho: float) -> IntArray:
    """At ``rho = 1`` a node is its gait (every subject's utility is the same function)."""
    return codes % len(space) if rho >= 1.0 else codes


class SubjectCross:
    """``K_{t,V}`` for subject ``t``: the gaits' cross-covariance, columns scaled and repeated.

    ``base`` is ``K_{:,U}`` over the distinct visited gaits ``U``; node ``j`` is gait
    ``U[inverse[j]]`` with weight ``rho + (1 - rho) [s_j = t]``.
    """

    def __init__(
        self, base: CrossCovariance, visited: IntArray, inverse: IntArray, weight: FloatArray
    ) -> None:
        self.base, self.visited, self.inverse, self.weight = base, visited, inverse, weight
        self.unique = base.visited.shape[0]

    def add_product(self, out: FloatArray, coef: FloatArray) -> None:
        gathered = np.zeros((self.unique, coef.shape[1]))
        np.add.at(gathered, self.inverse, self.weight[:, None] * coef)
        self.base.add_product(out, gathered)

    def rows(self, rows: IntArray) -> FloatArray:
        out: FloatArray = self.base.rows(rows)[:, self.inverse] * self.weight
        return out

    def blocks(self) -> Iterator[tuple[int, FloatArray]]:
        for start, block in self.base.blocks():
            yield start, block[:, self.inverse] * self.weight


@dataclass(frozen=True, eq=False)
class PopulationPosterior(Posterior):
    """One subject's (``target``) Laplace posterior over the whole grid, from a population fit
    whose ``fit.visited`` holds node codes.  Everything :class:`Posterior` offers works."""

    rho: float = 0.0
    target: int = 0
    share: float | None = None  # subject 0's own shared fraction (None: rho)

    @property
    def _other(self) -> float:
        """The task covariance of the target with any other subject."""
        if self.share is None or self.share == self.rho:
            return self.rho
        if self.target != 0:
            raise ValueError("a posterior with the new subject's share is subject 0's")
        return float(np.sqrt(self.rho * self.share))

    @property
    def _mix(self) -> float:
        """The target's shared fraction."""
        return self.rho if self.share is None else self.share

    @cached_property
    def _nodes(self) -> tuple[IntArray, IntArray]:
        size = len(self.space)
        codes = self.visited
        return codes % size, codes // size

    @cached_property
    def cross(self) -> CrossCovariance:
        gaits, subjects = self._nodes
        unique, inverse = np.unique(gaits, return_inverse=True)
        weight = np.where(subjects == self.target, 1.0, self._other)
        base = self.engine.cross(unique.astype(np.intp))
        return SubjectCross(base, self.visited, inverse.astype(np.intp), weight)

    def visited_cross(self, actions: ArrayLike) -> FloatArray:
        return self.cross.rows(np.asarray(actions, dtype=np.intp))

    def _jitter_columns(self) -> tuple[IntArray, FloatArray]:
        gaits, subjects = self._nodes
        return gaits, np.where(subjects == self.target, 1.0, self._other)

    def _prior_draw(
        self, rng: np.random.Generator, size: int, *, jitter_part: bool = True
    ) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        """The subject's own part first (so ``rho = 0`` draws as one subject), then the shared
        part, then the other subjects' own parts on their visited gaits, in subject order.

        With ``rho = 0`` the factors are block-diagonal by subject and the other subjects' draws
        cannot reach this subject's samples: they are left at 0 and the generator moves exactly
        as a single-subject posterior's does.  The third entry is the jitter part of the
        subject's grid draw, ``sqrt(1 - rho) e_own + sqrt(rho) e_shared`` (None without
        ``jitter_part``).  The mixture is formed in the own part's array (each entry rounded as
        ``a * own + b * shared`` is), so the draw holds the two parts and one product."""
        gaits, subjects = self._nodes
        rho, mix = self.rho, self._mix
        keep = {"jitter_part": jitter_part}
        own, e_own = self.engine.prior_parts(rng, size, **keep) if mix < 1.0 else (None, None)
        shared, e_shared = self.engine.prior_parts(rng, size, **keep) if mix > 0.0 else (None, None)
        e: FloatArray | None
        if own is None:
            assert shared is not None
            f, e = shared, e_shared
        elif shared is None:
            f, e = own, e_own
        else:
            f = _mixed(own, shared, mix)
            e = None
            if e_own is not None and e_shared is not None:
                e = _mixed(e_own, e_shared, mix)
        f_visited = np.empty((size, gaits.shape[0]))
        mine = subjects == self.target
        f_visited[:, mine] = f[:, gaits[mine]]
        if self._other == 0.0:  # the others' nodes are independent of this subject: no draw
            f_visited[:, ~mine] = 0.0
            return f, f_visited, e
        for s in np.unique(subjects[~mine]):
            nodes = np.flatnonzero(subjects == s)
            at = gaits[nodes]
            root = cholesky(self.kernel.cross(self.space, at, rows=at), lower=True)
            draw = rng.standard_normal((size, at.shape[0])) @ root.T
            part = np.sqrt(1.0 - rho) * draw
            if shared is not None:
                part += np.sqrt(rho) * shared[:, at]
            f_visited[:, nodes] = part
        return f, f_visited, e


def _mixed(own: FloatArray, shared: FloatArray, mix: float) -> FloatArray:
    """``sqrt(1 - mix) own + sqrt(mix) shared`` in ``own``'s array (the same rounding as the
    expression: each product and the sum are rounded once either way)."""
    own *= np.sqrt(1.0 - mix)
    own += np.sqrt(mix) * shared
    return own


@dataclass(frozen=True)
class PopulationModel:
    """A grid, the single-subject kernel, the shared fraction ``rho`` and the probit noise."""

    space: Space
    kernel: SquaredExponential
    rho: float
    noise: float
    sampler: str = "auto"
    ordinal: Ordinal | None = None
    share: float | None = None  # subject 0's own shared fraction (None: rho)

    def __post_init__(self) -> None:
        # as PreferenceGP: a kernel or a space of another type failed at the first posterior
        if not isinstance(self.space, Space):
            raise TypeError(f"space must be a gaitpref.Space, got {self.space!r}")
        if not isinstance(self.kernel, SquaredExponential):
            raise TypeError(f"kernel must be a gaitpref.SquaredExponential, got {self.kernel!r}")
        if self.ordinal is not None and not isinstance(self.ordinal, Ordinal):
            raise TypeError(f"ordinal must be a gaitpref.Ordinal or None, got {self.ordinal!r}")
        if not is_noise(self.noise):
            raise ValueError(
                f"preference noise must be positive with a finite square, got {self.noise!r}"
            )
        self.kernel.lengthscales(self.space.ndim)  # checks the count
        check_grid_size(self.space)
        object.__setattr__(self, "rho", check_rho(self.rho))
        object.__setattr__(self, "share", check_share(self.rho, self.share))

    @cached_property
    def engine(self) -> GridEngine:
        return make_engine(self.space, self.kernel, self.sampler)

    def posterior(
        self,
        first: IntArray,
        second: IntArray,
        likelihood: PairLikelihood,
        target: int,
        *,
        init: FloatArray | None = None,
        single: IntArray | None = None,
        single_likelihood: ActionLikelihood | None = None,
        fit: LaplaceMode | None = None,
    ) -> Posterior:
        """Subject ``target``'s posterior given observations of ``f[first] - f[second]`` and of
        ``f[single]`` (node codes, :func:`node_codes`).  ``init``: a starting mode on the
        visited nodes (:meth:`visited` of the same data).  Codes are integers >= 0 and
        ``target`` a subject (an integer >= 0), else a ValueError naming them.  ``fit``: this
        model's Laplace fit of the same data, already made (:func:`population_evidence`'s, with
        the same kernel, ``rho`` and ``share``), taken instead of fitting again; its visited
        nodes must be these data's."""
        for name, codes in (("first", first), ("second", second), ("single", single)):
            if codes is not None:
                check_codes(codes, name)
        if np.shape(first) != np.shape(second):
            raise ValueError(f"{np.size(first)} first but {np.size(second)} second codes")
        if not is_count(target) or target < 0:
            raise ValueError(f"target must be a subject, an integer >= 0, got {target!r}")
        engine = self.engine
        if first.size == 0 and (single is None or single.size == 0):
            return Posterior(self.space, self.kernel, None, engine, self.noise, self.ordinal)
        visited, a, b, s = self.indices(first, second, single)
        if fit is not None:
            if not np.array_equal(fit.visited, visited):
                raise ValueError("the fit given is not of these data: its visited nodes differ")
        else:
            space, kernel, rho, share = self.space, self.kernel, self.rho, self.share

            def prior() -> FloatArray:
                return population_prior(space, kernel, rho, visited, visited, share)

            fit = fit_laplace(
                prior(), visited, a, b, likelihood, init, single=s,
                single_likelihood=single_likelihood, prior=prior,
            )  # fmt: skip
        target = 0 if self.rho >= 1.0 else int(target)
        return PopulationPosterior(
            self.space, self.kernel, fit, engine, self.noise, self.ordinal, self.rho, target,
            self.share,
        )  # fmt: skip

    def indices(
        self, first: IntArray, second: IntArray, single: IntArray | None = None
    ) -> tuple[IntArray, IntArray, IntArray, IntArray | None]:
        """The visited nodes (sorted) and each observation's index into them."""
        n = first.shape[0]
        parts = [first, second] if single is None else [first, second, single]
        codes = pooled(self.space, np.concatenate(parts).astype(np.intp), self.rho)
        visited, inverse = np.unique(codes, return_inverse=True)
        inv = inverse.astype(np.intp)
        s = None if single is None else inv[2 * n :]
        return visited.astype(np.intp), inv[:n], inv[n : 2 * n], s


def logit(p: float) -> float:
    return float(np.log(p) - np.log1p(-p))


def _population_k(
    space: Space,
    kernel: SquaredExponential,
    gaits: IntArray,
    subjects: IntArray,
    rho: float,
    share: float | None,
) -> FloatArray:
    """:func:`population_evidence`'s prior covariance of the visited nodes, the same product."""
    out: FloatArray = kernel.cross(space, gaits, rows=gaits) * subject_weights(
        subjects, subjects, rho, share
    )
    return out


def population_evidence(
    space: Space,
    hyper: Hyperparameters,
    rho: float,
    data: PairData,
    init: FloatArray | None = None,
    *,
    singles: SingleData | None = None,
    share: float | None = None,
    gradient: bool = True,
) -> Evidence:
    """The Laplace evidence of population data (node codes) and its gradient in
    ``(hyper.log_vector(), logit rho)``: the single-subject entries, then ``logit rho``.

    ``gradient=False``: the value and the fit only, the gradient all NaN.  The value is the same
    number (the same fit); what is skipped is the gradient's ``N x m`` and ``m x m`` products,
    more than the fit itself costs on a clinic's data (what a share's weight or MAP needs).

    ``rho`` must lie in ``(0, 1)`` for the gradient (``dlogit``); at 0 or 1 its entry is 0.
    With the new subject's ``share`` the value is exact but the gradient's ``logit rho`` entry
    is not defined (NaN): ``share_fit.py`` fits ``share`` alone from values.
    Fitted thresholds are not supported here (``hyper.thresholds`` must be None).
    """
    rho = check_rho(rho)
    share = check_share(rho, share)
    if hyper.thresholds is not None:
        raise ValueError("population_evidence does not fit ordinal thresholds")
    if singles is not None and singles.size == 0:
        singles = None
    if data.size == 0 and singles is None:
        raise ValueError("the evidence needs at least one observation")
    model = PopulationModel(space, hyper.kernel(), rho, 1.0, share=share)
    single = None if singles is None else singles.actions
    visited, a, b, s = model.indices(data.first, data.second, single)
    kernel = hyper.kernel()
    size = len(space)
    gaits, subjects = visited % size, visited // size
    full = kernel.cross(space, gaits, rows=gaits)
    same = subjects[:, None] == subjects[None, :]
    weights = subject_weights(subjects, subjects, rho, share)
    K = full * weights  # _population_k's product, kept apart for the gradient
    d = space.ndim
    points = space.points_of(gaits)  # not every grid point (A x d) for the gaits in the data

    def kernel_gradient(B: FloatArray) -> FloatArray:
        out = np.zeros(d + 2)
        se = (full - kernel.jitter * (gaits[:, None] == gaits[None, :])) * weights
        for j, ell in enumerate(hyper.lengthscale):
            dK = se * ((points[:, j, None] - points[None, :, j]) / ell) ** 2
            out[j] = float(np.sum(dK * B))
        out[d] = float(np.sum(K * B))
        out[d + 1] = rho * (1.0 - rho) * float(np.sum(np.where(same, 0.0, full) * B))
        if share is not None:
            out[d + 1] = np.nan
        return out

    if not gradient:
        lik = data.likelihood(hyper.band)
        single_lik = None if singles is None else singles.likelihood
        fit = fit_laplace(
            K, visited, a, b, lik, init, single=s, single_likelihood=single_lik,
            prior=partial(_population_k, space, kernel, gaits, subjects, rho, share),
        )  # fmt: skip
        return Evidence(fit.log_evidence, np.full(d + 3, np.nan), fit)
    ev = evidence_from_prior(
        K, visited, (a, b, s), data, singles, hyper, kernel_gradient, init, sparse=True
    )
    g = ev.gradient  # (l..., s^2, logit rho, band) -> (l..., s^2, band, logit rho)
    order = np.array([*range(d + 1), d + 2, d + 1])
    return Evidence(ev.value, g[order], ev.fit)


__all__ = [
    "PopulationModel",
    "PopulationPosterior",
    "SubjectCross",
    "check_rho",
    "check_share",
    "logit",
    "node_codes",
    "population_evidence",
    "population_prior",
    "subject_weights",
]
