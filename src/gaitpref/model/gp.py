"""The preference Gaussian process: a grid, a kernel, a probit noise, and Laplace posteriors.

Chu & Ghahramani (2005) as the paper uses it (Section "Modeling Utilities from Preference Data",
eq. (1)): prior ``f ~ N(0, K)`` over the ``A`` grid actions, likelihood
``P(w > l | f) = Phi((f_w - f_l) / (sqrt(2) sigma_k))`` per preference, and the Laplace posterior
``N(f_hat, (K^-1 + Lambda)^-1)`` computed in the visited subspace (``laplace.py``) and read over
all actions (``posterior.py``).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from gaitpref.model.engines import GridEngine, make_engine, resolve_sampler
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.laplace import fit_laplace
from gaitpref.model.likelihood import ActionLikelihood, PairLikelihood, Probit
from gaitpref.model.ordinal import Ordinal, rating_likelihood
from gaitpref.model.posterior import Posterior
from gaitpref.space import IntArray, Space


def _as_indices(space: Space, values: ArrayLike, name: str) -> IntArray:
    arr = np.asarray(values)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be a 1-D sequence of grid indices")
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        raise TypeError(f"{name} must hold integer grid indices, got dtype {arr.dtype}")
    idx = arr.astype(np.intp)
    bad = (idx < 0) | (idx >= len(space))
    if np.any(bad):
        raise IndexError(
            f"{name}[{int(np.flatnonzero(bad)[0])}] = {int(idx[bad][0])} is off the grid "
            f"(0..{len(space) - 1})"
        )
    return idx


class PreferenceGP:
    """A preference GP over the grid ``space`` with ``kernel`` and default probit ``noise``.

    ``sampler`` picks how posteriors reach all actions: ``"dense"``, ``"scalable"`` or
    ``"auto"`` (by grid size; ``engines.py``).  Both give the same draws for the same seed up to
    rounding.
    """

    def __init__(
        self,
        space: Space,
        kernel: SquaredExponential,
        noise: float,
        sampler: str = "auto",
        ordinal: Ordinal | None = None,
    ) -> None:
        if not (np.isfinite(noise) and noise > 0):
            raise ValueError(f"preference noise must be positive, got {noise!r}")
        kernel.lengthscales(space.ndim)  # checks the count
        self.space = space
        self.kernel = kernel
        self.noise = float(noise)
        self.sampler = resolve_sampler(sampler, len(space))
        self.ordinal = ordinal

    @cached_property
    def engine(self) -> GridEngine:
        return make_engine(self.space, self.kernel, self.sampler)

    def prior(self) -> Posterior:
        """The prior as a :class:`Posterior` (no data)."""
        return Posterior(self.space, self.kernel, None, self.engine, self.noise, self.ordinal)

    def posterior(
        self,
        winners: ArrayLike,
        losers: ArrayLike,
        noise: ArrayLike | None = None,
        *,
        ratings: Sequence[tuple[int, object]] | None = None,
        init: Posterior | None = None,
    ) -> Posterior:
        """Laplace posterior given preferences ``winners[k] > losers[k]`` (grid indices) and
        ordinal ``ratings`` ``(action, label)`` (labels ``1..K`` or category names; needs the
        model's ``ordinal``), all in one fit.

        ``noise`` overrides the default probit noise per comparison; ``init`` is a previous
        posterior whose mean warm-starts Newton's method.
        """
        w = _as_indices(self.space, winners, "winners")
        loser_idx = _as_indices(self.space, losers, "losers")
        if w.shape != loser_idx.shape:
            raise ValueError(f"{w.size} winners but {loser_idx.size} losers")
        if noise is None:
            sigma = np.full(w.size, self.noise)
        else:
            sigma = np.broadcast_to(np.asarray(noise, dtype=np.float64), w.shape).copy()
            if not np.all(np.isfinite(sigma) & (sigma > 0)):
                raise ValueError("every comparison's noise must be positive and finite")
        if not ratings:
            return self.posterior_from(w, loser_idx, Probit(sigma), init=init)
        if self.ordinal is None:
            raise ValueError("ratings need PreferenceGP(..., ordinal=Ordinal(...))")
        actions = _as_indices(self.space, [a for a, _ in ratings], "rating actions")
        labels = [self.ordinal.label_index(label) for _, label in ratings]
        lik = rating_likelihood(self.ordinal, self.kernel.variance, labels)
        return self.posterior_from(
            w, loser_idx, Probit(sigma), init=init, single=actions, single_likelihood=lik
        )

    def posterior_from(
        self,
        first: IntArray,
        second: IntArray,
        likelihood: PairLikelihood,
        *,
        init: Posterior | None = None,
        single: IntArray | None = None,
        single_likelihood: ActionLikelihood | None = None,
    ) -> Posterior:
        """Laplace posterior for any pairwise likelihood of ``f[first] - f[second]``.

        ``single`` (grid indices) with ``single_likelihood`` adds observations of single
        utilities ``f[single_k]`` (the second shape of likelihood term, ``laplace.py``).
        """
        if single is not None:
            single = _as_indices(self.space, single, "single")
            if single.size == 0:
                single = single_likelihood = None
            elif single_likelihood is None:
                raise ValueError("single-action observations need single_likelihood")
        if first.size == 0 and single is None:
            return self.prior()
        n_first = first.size
        parts = [first, second] if single is None else [first, second, single]
        visited, inverse = np.unique(np.concatenate(parts), return_inverse=True)
        visited = visited.astype(np.intp)
        a, b = inverse[:n_first].astype(np.intp), inverse[n_first : 2 * n_first].astype(np.intp)
        s = None if single is None else inverse[2 * n_first :].astype(np.intp)
        k_vv = self.kernel.cross(self.space, visited, rows=visited)
        start = None if init is None else init.mean_at(visited)
        fit = fit_laplace(
            k_vv, visited, a, b, likelihood, start, single=s, single_likelihood=single_likelihood
        )
        return Posterior(self.space, self.kernel, fit, self.engine, self.noise, self.ordinal)
