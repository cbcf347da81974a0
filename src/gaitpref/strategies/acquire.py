"""EUBO strategies for the CoSpar loop (``base.py``'s :class:`Strategy` protocol).

- :class:`Eubo`: each new action maximises ``EUBO(x, r)`` (``eubo.py``) against the reference
  ``r``, the buffered or already chosen action with the highest posterior mean.  With no buffer
  and ``n >= 2`` the first two actions are the best pair among the top ``candidates`` actions by
  ``mu + 2 sd`` (all pairs of the whole grid would need its ``A x A`` covariance); with no buffer
  and ``n = 1`` (the first query of ``b >= 1``) the first action is a posterior sample's argmax.
  Buffered and already chosen actions are never proposed again while others exist, so every
  query yields a comparison: EUBO cannot lock in on a winner that is never compared.
- :class:`ConfidentEubo`: the same, restricted to the plausible maximisers by confidence bounds,
  ``{x : mu_x + beta sd_x >= max_y (mu_y - beta sd_y)}``, as MaxInP (Saha, NeurIPS 2021) duels
  only among arms that may still be best.  When only the references are plausible it takes the
  non-reference action with the highest upper bound.

Notation: ``A`` actions, ``n`` new actions per query, ``b`` buffered.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gaitpref.checks import is_number
from gaitpref.model.posterior import Posterior, random_argmax
from gaitpref.space import IntArray
from gaitpref.strategies.base import MAX_CANDIDATES, AskContext, check_count, plain
from gaitpref.strategies.eubo import best_pair, eubo_against


def _top_candidates(
    posterior: Posterior, k: int, rng: np.random.Generator, allowed: NDArray[np.bool_] | None
) -> IntArray:
    """The ``k`` (allowed) actions with the highest ``mu + 2 sd`` (exact ties in random order)."""
    score = np.asarray(posterior.mean) + 2.0 * np.asarray(posterior.std)
    order = np.lexsort((rng.permutation(score.shape[0]), -score))
    if allowed is not None:
        order = order[allowed[order]]
    return order[: min(k, order.shape[0])].astype(np.intp)


def _best_reference(posterior: Posterior, refs: list[int], rng: np.random.Generator) -> int:
    mu = np.asarray(posterior.mean)[np.asarray(refs, dtype=np.intp)]
    return refs[random_argmax(mu, rng)]


def eubo_fill(context: AskContext, chosen: list[int], allowed: IntArray | None) -> tuple[int, ...]:
    """Add actions one at a time, each the EUBO maximiser against the best reference.

    ``allowed`` (indices) narrows the choice (confident-eubo's plausible set) while it has new
    actions; ``context.allowed`` (a mask: the region of interest) is never left.
    """
    post, rng = context.posterior, context.rng
    size = len(post.space)
    safe = np.ones(size, dtype=bool) if context.allowed is None else context.allowed
    while len(chosen) < context.n:
        refs = [*context.buffer, *chosen]
        ref = _best_reference(post, refs, rng)
        values = eubo_against(post, ref)
        mask = np.zeros(size, dtype=bool)
        if allowed is None:
            mask[:] = True
        else:
            mask[allowed] = True
        mask &= safe
        mask[np.asarray(refs, dtype=np.intp)] = False
        if not mask.any():  # nothing new left in the allowed set: any other safe action
            mask[:] = safe
            mask[np.asarray(refs, dtype=np.intp)] = False
        if not mask.any():  # a grid (or region) smaller than the query: repeat a safe action
            mask[:] = safe
            if not mask[ref]:
                chosen.append(random_argmax(np.where(mask, values, -np.inf), rng))
                continue
            chosen.append(ref)
            continue
        chosen.append(random_argmax(np.where(mask, values, -np.inf), rng))
    return tuple(chosen)


def _start(context: AskContext, candidates: int) -> list[int]:
    """With no buffer: the best EUBO pair of the top candidates (n >= 2) or one sample's argmax."""
    if context.buffer:
        return []
    allowed = context.allowed
    few = len(context.posterior.space) < 2 or (allowed is not None and allowed.sum() < 2)
    if context.n == 1 or few:
        return [int(context.posterior.argmax_samples(context.rng, 1, allowed)[0])]
    top = _top_candidates(context.posterior, candidates, context.rng, allowed)
    x, y, _ = best_pair(context.posterior, top)
    return [x, y]


@dataclass(frozen=True)
class Eubo:
    """Greedy EUBO against the best buffered or chosen action (see the module docstring)."""

    candidates: int = 64
    name: str = "eubo"

    def __post_init__(self) -> None:
        check_count(self, "candidates", 2, MAX_CANDIDATES)

    def propose(self, context: AskContext) -> tuple[int, ...]:
        return eubo_fill(context, _start(context, self.candidates)[: context.n], None)

    def joint_draws(self, n: int) -> tuple[int, str | None]:
        """One sample (the first action of an unbuffered query; as :class:`SelfSparring`)."""
        return 1, None


@dataclass(frozen=True)
class ConfidentEubo:
    """EUBO among actions whose ``mu + beta sd`` reaches the best ``mu - beta sd``."""

    beta: float = 1.0
    candidates: int = 64
    name: str = "confident-eubo"

    def __post_init__(self) -> None:
        beta = self.beta
        if not is_number(beta) or not 0 <= beta < np.inf:
            raise ValueError(f"beta must be a finite number >= 0, got {beta!r}")
        object.__setattr__(self, "beta", plain(beta))  # a NumPy number as Python's
        check_count(self, "candidates", 2, MAX_CANDIDATES)

    def propose(self, context: AskContext) -> tuple[int, ...]:
        post = context.posterior
        chosen = _start(context, self.candidates)[: context.n]
        mu, sd = np.asarray(post.mean), np.asarray(post.std)
        ucb = mu + self.beta * sd
        safe = np.ones(mu.shape[0], dtype=bool) if context.allowed is None else context.allowed
        plausible = np.flatnonzero((ucb >= np.max(mu - self.beta * sd)) & safe)
        refs = np.asarray([*context.buffer, *chosen], dtype=np.intp)
        rest = np.setdiff1d(plausible, refs)
        if rest.size == 0:  # only the references are plausible: the most plausible challenger
            masked = np.where(safe, ucb, -np.inf)
            masked[refs] = -np.inf
            if context.allowed is None or np.isfinite(masked).any():
                rest = np.array([int(np.argmax(masked))], dtype=np.intp)
        return eubo_fill(context, chosen, rest.astype(np.intp))

    def joint_draws(self, n: int) -> tuple[int, str | None]:
        """One sample (the first action of an unbuffered query; as :class:`SelfSparring`)."""
        return 1, None
