"""Warm starts: earlier subjects' answers in a new subject's model, through the population kernel.

A :class:`WarmStart` holds the earlier subjects' observations as population data (node codes
``subject * A + gait``, ``model/population.py``; the new subject is subject 0, the earlier ones
1, 2, ...) and the shared fraction ``rho``.  :func:`warm_start` builds it from each earlier
subject's preferences and learns ``rho`` by the evidence when two or more earlier subjects are
given (how alike they are to each other); with one, ``rho`` is the prior's median.  The new
subject's answers join those data in every fit (``CoSpar.warm_start``): with ``rho = 0`` their
posterior is the one they would have had alone.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gaitpref.feedback import Preference
from gaitpref.model.evidence import Hyperparameters, PairData
from gaitpref.model.gp import PreferenceGP
from gaitpref.model.hyperfit import HyperPrior
from gaitpref.model.likelihood import ActionLikelihood
from gaitpref.model.population import PopulationModel, check_rho
from gaitpref.model.population_fit import LogitNormal, fit_population
from gaitpref.model.posterior import Posterior
from gaitpref.space import IntArray, Space


@dataclass(frozen=True)
class WarmStart:
    """Earlier subjects' observations (node codes; the new subject is 0) and ``rho``."""

    data: PairData
    rho: float
    subjects: int  # earlier subjects

    def __post_init__(self) -> None:
        object.__setattr__(self, "rho", check_rho(self.rho))


def warm_data(space: Space, earlier: Sequence[Sequence[Preference]]) -> PairData:
    """The earlier subjects' preferences as population data (subject ``k + 1`` for the k-th)."""
    size = len(space)
    first = [(k + 1) * size + p.winner for k, prefs in enumerate(earlier) for p in prefs]
    second = [(k + 1) * size + p.loser for k, prefs in enumerate(earlier) for p in prefs]
    sigma = [p.noise for prefs in earlier for p in prefs]
    n = len(sigma)
    return PairData(
        np.array(first, dtype=np.intp), np.array(second, dtype=np.intp),
        np.array(sigma, dtype=np.float64), np.zeros(n, dtype=bool), np.zeros(n, dtype=bool),
    )  # fmt: skip


def warm_start(
    space: Space,
    hyper: Hyperparameters,
    prior: HyperPrior,
    earlier: Sequence[Sequence[Preference]],
    rho_prior: LogitNormal | None = None,
) -> WarmStart:
    """The warm start from the earlier subjects' preferences (one sequence per subject)."""
    rho_prior = LogitNormal() if rho_prior is None else rho_prior
    data = warm_data(space, earlier)
    rho = rho_prior.median
    with_data = sum(1 for p in earlier if p)
    if with_data >= 2 and rho_prior.sd > 0:
        held = HyperPrior(
            tuple(type(p)(p.median, 0.0) for p in prior.lengthscale),
            type(prior.variance)(prior.variance.median, 0.0),
        )  # only rho: the kernel stays the config's (the new subject's refits move it)
        rho = fit_population(space, hyper, rho, data, held, rho_prior).rho_after
    return WarmStart(data, rho, len(earlier))


def warm_posterior(
    warm: WarmStart,
    gp: PreferenceGP,
    own: PairData,
    band: float,
    single: IntArray | None = None,
    single_likelihood: ActionLikelihood | None = None,
) -> Posterior:
    """The new subject's posterior given their own observations ``own`` (grid indices) and the
    earlier subjects' (``warm``), in one population fit."""
    data = PairData(
        np.concatenate([own.first, warm.data.first]),
        np.concatenate([own.second, warm.data.second]),
        np.concatenate([own.sigma, warm.data.sigma]),
        np.concatenate([own.banded, warm.data.banded]),
        np.concatenate([own.tie, warm.data.tie]),
    )
    model = PopulationModel(gp.space, gp.kernel, warm.rho, gp.noise, gp.sampler, gp.ordinal)
    return model.posterior(
        data.first, data.second, data.likelihood(band), 0,
        single=single, single_likelihood=single_likelihood,
    )  # fmt: skip


__all__ = ["WarmStart", "warm_data", "warm_posterior", "warm_start"]
