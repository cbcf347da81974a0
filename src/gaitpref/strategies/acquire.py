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

from gaitpref.model.posterior import Posterior, random_argmax
from gaitpref.space import IntArray
from gaitpref.strategies.base import AskContext
from gaitpref.strategies.eubo import best_pair, eubo_against


def _top_candidates(posterior: Posterior, k: int, rng: np.random.Generator) -> IntArray:
    """The ``k`` actions with the highest ``mu + 2 sd`` (exact ties in random order)."""
    score = np.asarray(posterior.mean) + 2.0 * np.asarray(posterior.std)
    order = np.lexsort((rng.permutation(score.shape[0]), -score))
    return order[: min(k, score.shape[0])].astype(np.intp)


def _best_reference(posterior: Posterior, refs: list[int], rng: np.random.Generator) -> int:
    mu = np.asarray(posterior.mean)[np.asarray(refs, dtype=np.intp)]
    return refs[random_argmax(mu, rng)]


def eubo_fill(context: AskContext, chosen: list[int], allowed: IntArray | None) -> tuple[int, ...]:
    """Add actions one at a time, each the EUBO maximiser against the best reference."""
    post, rng = context.posterior, context.rng
    size = len(post.space)
    while len(chosen) < context.n:
        refs = [*context.buffer, *chosen]
        ref = _best_reference(post, refs, rng)
        values = eubo_against(post, ref)
        mask = np.zeros(size, dtype=bool)
        if allowed is None:
            mask[:] = True
        else:
            mask[allowed] = True
        mask[np.asarray(refs, dtype=np.intp)] = False
        if not mask.any():  # nothing new left in the allowed set: use every other action
            mask[:] = True
            mask[np.asarray(refs, dtype=np.intp)] = False
        if not mask.any():  # a grid smaller than the query: repeat the reference
            chosen.append(ref)
            continue
        chosen.append(random_argmax(np.where(mask, values, -np.inf), rng))
    return tuple(chosen)


def _start(context: AskContext, candidates: int) -> list[int]:
    """With no buffer: the best EUBO pair of the top candidates (n >= 2) or one sample's argmax."""
    if context.buffer:
        return []
    if context.n == 1 or len(context.posterior.space) < 2:
        return [int(context.posterior.argmax_samples(context.rng, 1)[0])]
    top = _top_candidates(context.posterior, candidates, context.rng)
    x, y, _ = best_pair(context.posterior, top)
    return [x, y]


def _check_candidates(candidates: object) -> None:
    if isinstance(candidates, bool) or not isinstance(candidates, int) or candidates < 2:
        raise ValueError(f"candidates must be an integer >= 2, got {candidates!r}")


@dataclass(frozen=True)
class Eubo:
    """Greedy EUBO against the best buffered or chosen action (see the module docstring)."""

    candidates: int = 64
    name: str = "eubo"

    def __post_init__(self) -> None:
        _check_candidates(self.candidates)

    def propose(self, context: AskContext) -> tuple[int, ...]:
        return eubo_fill(context, _start(context, self.candidates)[: context.n], None)


@dataclass(frozen=True)
class ConfidentEubo:
    """EUBO among actions whose ``mu + beta sd`` reaches the best ``mu - beta sd``."""

    beta: float = 1.0
    candidates: int = 64
    name: str = "confident-eubo"

    def __post_init__(self) -> None:
        beta = self.beta
        if isinstance(beta, bool) or not isinstance(beta, int | float) or not 0 <= beta < np.inf:
            raise ValueError(f"beta must be a finite number >= 0, got {beta!r}")
        _check_candidates(self.candidates)

    def propose(self, context: AskContext) -> tuple[int, ...]:
        post = context.posterior
        chosen = _start(context, self.candidates)[: context.n]
        mu, sd = np.asarray(post.mean), np.asarray(post.std)
        ucb = mu + self.beta * sd
        plausible = np.flatnonzero(ucb >= np.max(mu - self.beta * sd))
        refs = np.asarray([*context.buffer, *chosen], dtype=np.intp)
        rest = np.setdiff1d(plausible, refs)
        if rest.size == 0:  # only the references are plausible: the most plausible challenger
            masked = ucb.copy()
            masked[refs] = -np.inf
            rest = np.array([int(np.argmax(masked))], dtype=np.intp)
        return eubo_fill(context, chosen, rest.astype(np.intp))
