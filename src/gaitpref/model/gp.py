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

from gaitpref.checks import MAX_NOISE, is_noise
from gaitpref.model.engines import (
    GridEngine,
    PointEngine,
    check_grid_size,
    make_engine,
    resolve_sampler,
)
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.laplace import check_visited, fit_laplace
from gaitpref.model.likelihood import ActionLikelihood, PairLikelihood, Probit
from gaitpref.model.ordinal import Ordinal, rating_likelihood
from gaitpref.model.posterior import Posterior
from gaitpref.space import FloatArray, IntArray, Space


class PreferenceGP:
    """A preference GP over the grid ``space`` with ``kernel`` and default probit ``noise``.

    ``sampler`` picks how posteriors reach all actions: ``"dense"``, ``"scalable"`` or
    ``"auto"`` (by grid size; ``engines.py``).  Both give the same draws for the same seed up to
    rounding.

    ``ordinal`` (an :class:`Ordinal`) lets :meth:`posterior` take ratings ``(action, label)``,
    labels ``1..K`` or category names, in the same fit as the preferences; the posterior then
    gives each action's rating probabilities (``n x K``)::

        >>> import gaitpref
        >>> space = gaitpref.Space([gaitpref.Feature("x", [0.0, 0.25, 0.5, 0.75, 1.0])])
        >>> gp = gaitpref.PreferenceGP(
        ...     space, gaitpref.SquaredExponential(0.3, 1.0), 0.1,
        ...     ordinal=gaitpref.Ordinal(["bad", "ok", "good"]),
        ... )
        >>> post = gp.posterior([4], [0], ratings=[(4, "good"), (0, 1)])
        >>> post.rating_probabilities([0, 4]).round(2)
        array([[0.67, 0.33, 0.  ],
               [0.  , 0.33, 0.67]])
        >>> post.preference_probability(4, 0) > 0.9
        True
    """

    def __init__(
        self,
        space: Space,
        kernel: SquaredExponential,
        noise: float,
        sampler: str = "auto",
        ordinal: Ordinal | None = None,
    ) -> None:
        if not isinstance(space, Space):
            raise TypeError(f"space must be a gaitpref.Space, got {space!r}")
        if not isinstance(kernel, SquaredExponential):
            raise TypeError(f"kernel must be a gaitpref.SquaredExponential, got {kernel!r}")
        if not is_noise(noise):
            raise ValueError(
                f"preference noise must be positive with a finite square, got {noise!r}"
            )
        if ordinal is not None and not isinstance(ordinal, Ordinal):  # failed at a rating
            raise TypeError(f"ordinal must be a gaitpref.Ordinal or None, got {ordinal!r}")
        kernel.lengthscales(space.ndim)  # checks the count
        check_grid_size(space)
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
        """Laplace posterior given preferences ``winners[k] > losers[k]`` (grid indices, never
        ``winners[k] == losers[k]``: a ValueError names the first such ``k``) and
        ordinal ``ratings`` ``(action, label)`` (labels ``1..K`` or category names; needs the
        model's ``ordinal``), all in one fit.

        ``noise`` overrides the default probit noise per comparison; ``init`` is a previous
        posterior whose mean warm-starts Newton's method.
        """
        if init is not None and not isinstance(init, Posterior):
            raise TypeError(f"init must be a Posterior (a previous fit) or None, got {init!r}")
        w = self.space.check_indices(winners, "winners")
        loser_idx = self.space.check_indices(losers, "losers")
        if w.shape != loser_idx.shape:
            raise ValueError(f"{w.size} winners but {loser_idx.size} losers")
        _check_distinct_pairs(w, loser_idx, "winners/losers")
        sigma = np.full(w.size, self.noise) if noise is None else _comparison_noise(noise, w.size)
        if not ratings:
            return self.posterior_from(w, loser_idx, Probit(sigma), init=init)
        if self.ordinal is None:
            raise ValueError("ratings need PreferenceGP(..., ordinal=Ordinal(...))")
        rated, labels = [], []
        for k, item in enumerate(ratings):
            try:
                action, label = item
            except (TypeError, ValueError):
                raise ValueError(
                    f"ratings[{k}] must be an (action, label) pair, got {item!r}"
                ) from None
            try:
                labels.append(self.ordinal.label_index(label))
            except ValueError as exc:
                raise ValueError(f"ratings[{k}]: {exc}") from None
            rated.append(action)
        actions = self.space.check_indices(rated, "rating actions")
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
        A pair of an action with itself (``first[k] == second[k]``) is taken as given: its
        difference is 0 whatever the utilities, so it adds the constant ``log p(0)`` to the
        evidence and nothing to the posterior (an ordered probit's "no preference" between a gait
        and itself does carry evidence about the band).  :meth:`posterior`, where a preference of
        an action over itself can only be a mislabelling, refuses one.
        """
        # grid indices, as posterior's: floats were truncated to gaits, an index off the grid
        # was NumPy's error, a list an AttributeError
        first = self.space.check_indices(first, "first")
        second = self.space.check_indices(second, "second")
        if first.shape != second.shape:
            raise ValueError(f"{first.size} first but {second.size} second actions")
        for name, lik in (("likelihood", likelihood), ("single_likelihood", single_likelihood)):
            if lik is not None and not callable(getattr(lik, "terms", None)):
                raise TypeError(f"{name} must be a likelihood (with terms), got {lik!r}")
        if single is not None:
            single = self.space.check_indices(single, "single")
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
        check_visited(visited.size)  # before the m x m prior is built
        a, b = inverse[:n_first].astype(np.intp), inverse[n_first : 2 * n_first].astype(np.intp)
        s = None if single is None else inverse[2 * n_first :].astype(np.intp)
        kernel, space = self.kernel, self.space

        def prior() -> FloatArray:
            k_vv: FloatArray = kernel.cross(space, visited, rows=visited)
            return k_vv

        start = None if init is None else init.mean_at(visited)
        engine = self.engine
        # K_VV from the K over every point the engine holds (the same floats), else the kernel
        k_vv = engine.prior_block(visited) if isinstance(engine, PointEngine) else None
        if k_vv is None:
            k_vv = prior()
        fit = fit_laplace(
            k_vv, visited, a, b, likelihood, start, single=s,
            single_likelihood=single_likelihood, prior=prior,
        )  # fmt: skip
        if isinstance(engine, PointEngine) and visited.size == len(space):
            engine.offer_square(k_vv)  # every point visited: K_VV is the posterior's K_{:,V}
        return Posterior(self.space, self.kernel, fit, engine, self.noise, self.ordinal)


def _comparison_noise(noise: ArrayLike, size: int) -> FloatArray:
    """``noise`` (one number, or one per comparison) as ``size`` probit noises, each a number
    in ``(0, MAX_NOISE]`` (its square finite, as the model's own noise), else a ValueError
    naming it: NumPy read True as a noise of 1 and "0.1" as 0.1, and a noise of 1e200 squared
    to inf in the likelihood."""
    try:
        raw = None if isinstance(noise, str | bytes) else np.asarray(noise)
    except (TypeError, ValueError):
        raw = None
    listed = noise if isinstance(noise, list | tuple) else ()  # [True, 0.1] read as [1.0, 0.1]
    if (
        raw is None
        or raw.dtype.kind not in "iuf"
        or any(isinstance(v, bool | np.bool_) for v in listed)
    ):
        raise ValueError(f"noise must be numbers (one, or one per comparison), got {noise!r}")
    try:
        sigma = np.broadcast_to(raw.astype(np.float64), (size,)).copy()
    except ValueError:
        raise ValueError(
            f"noise must be one number or one per comparison ({size}), got {noise!r}"
        ) from None
    bad = ~(np.isfinite(sigma) & (sigma > 0) & (sigma <= MAX_NOISE))
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"every comparison's noise must be positive with a finite square (at most "
            f"{MAX_NOISE:.3g}), got {float(sigma[k])!r} for comparison {k}"
        )
    return sigma


def _check_distinct_pairs(first: IntArray, second: IntArray, names: str) -> None:
    """Raise ``ValueError`` naming the first observation ``k`` with ``first[k] == second[k]``
    (``names``: ``"winners/losers"`` or the like).

    A preference of an action over itself is a term in ``f_a - f_a = 0`` whatever the
    utilities: it says nothing about them, yet it would enter the fit (``log Phi(0)`` in the
    evidence) and make the action visited; a caller who passes one has mislabelled something.
    The loop never makes one (``CoSpar.tell`` keeps a self-comparison in the answer's records
    and :attr:`~gaitpref.loop.Answer.ignored`, and drops its term: ``docs/model.md``)."""
    same = np.flatnonzero(np.asarray(first) == np.asarray(second))
    if same.size:
        k = int(same[0])
        a, b = names.split("/")
        raise ValueError(
            f"{a}[{k}] and {b}[{k}] are both action {int(first[k])}: a preference of an action "
            f"over itself says nothing about utilities ({same.size} such); leave it out"
        )
