"""Information gain: query the gaits whose answers say most about the utility (active learning).

An active-learning mode for mapping the whole comfort landscape rather than only finding its
peak, as ROIAL (Li, Tucker et al., ICRA 2021) and POLAR (Tucker et al. 2022) do: each new action
``x`` maximises the mutual information between the trial's answers and the utility ``f``, BALD
(Houlsby et al. 2011; ``bald.py``): the preference of ``x`` against the reference ``r`` (the
buffered or already chosen action with the highest posterior mean, as ``eubo_fill`` picks it)
plus, when the posterior has an ordinal rating model, the rating of ``x``.

- Only actions in ``context.allowed`` (the region of interest, ``loop/safety.py``) are proposed,
  and never a reference while another allowed action exists (so every query yields a comparison).
- With no reference (no buffer, first action of a query): the allowed action whose rating is most
  informative when the posterior rates, else the one of largest posterior variance.
- ``n > 1``: greedily, each new action against the best reference among the buffered and those
  already chosen.
- Candidates: the whole grid's variance is the cost to avoid (``O(A m^2)``: 30 ms on 30 x 30
  at 300 visited, 0.6 s on 57,750 actions), so when more than ``2 candidates`` actions are
  allowed the pool is the ``candidates`` allowed actions least covered by the data (lowest
  ``sum_v k(a, v)`` over the visited ``v``, a kernel density of the data: the variance is high
  where it is low) plus the ``candidates`` of highest posterior mean (where a comparison with the
  best reference is closest to a coin flip), both ``O(A m)`` through the engine; only their
  variances and covariances with the reference are computed (``O(c m^2)``).

Ties are broken with ``context.rng``; the strategy is deterministic given it.

Notation: ``A`` actions, ``m`` visited, ``c`` candidates, ``n`` new actions per query.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from gaitpref.model.posterior import Posterior, random_argmax
from gaitpref.space import FloatArray, IntArray
from gaitpref.strategies.bald import information_against, rating_information, variance_at
from gaitpref.strategies.base import MAX_CANDIDATES, AskContext, check_count


def _top(score: FloatArray, k: int, rng: np.random.Generator) -> IntArray:
    """Positions of the ``k`` highest ``score`` values, exact ties in random order
    (``O(len(score))``: a partition, not a sort, of a random permutation)."""
    perm = rng.permutation(score.shape[0])
    shuffled = score[perm]
    k = min(k, score.shape[0])
    part = np.argpartition(-shuffled, k - 1)[:k] if k < score.shape[0] else np.arange(k)
    order = part[np.lexsort((part, -shuffled[part]))]
    out: IntArray = perm[order].astype(np.intp)
    return out


def _coverage(posterior: Posterior) -> FloatArray:
    """``sum_v k(a, v)`` over the visited actions ``v``, for every action ``a`` (``K_{:,V} 1``,
    one product through the engine, as cheap as the mean)."""
    out: FloatArray = np.zeros((1, len(posterior.space)))
    if posterior.visited.size:
        posterior.cross.add_product(out, np.ones((posterior.visited.size, 1)))
    row: FloatArray = out[0]
    return row


def candidate_pool(
    posterior: Posterior, allowed: IntArray, candidates: int, rng: np.random.Generator
) -> tuple[IntArray, FloatArray, FloatArray]:
    """The actions to score (a subset of ``allowed``), their posterior means and variances."""
    mean = np.asarray(posterior.mean)
    if allowed.shape[0] > 2 * candidates:
        far = _top(-_coverage(posterior)[allowed], candidates, rng)
        high = _top(mean[allowed], candidates, rng)
        allowed = allowed[np.union1d(far, high)]
    return allowed, mean[allowed], variance_at(posterior, allowed)


@dataclass(frozen=True)
class InformationGain:
    """BALD over the region of interest (see the module docstring)."""

    candidates: int = 64
    name: str = "information-gain"

    def __post_init__(self) -> None:
        check_count(self, "candidates", 2, MAX_CANDIDATES)

    def propose(self, context: AskContext) -> tuple[int, ...]:
        post, rng = context.posterior, context.rng
        size = len(post.space)
        safe: NDArray[np.bool_] = (
            np.ones(size, dtype=bool) if context.allowed is None else context.allowed
        )
        allowed = np.flatnonzero(safe).astype(np.intp)
        if allowed.size == 0:
            raise ValueError("information-gain: no action is allowed (the region is empty)")
        pool, mean, var = candidate_pool(post, allowed, self.candidates, rng)
        chosen: list[int] = []
        while len(chosen) < context.n:
            refs = [*context.buffer, *chosen]
            fresh = ~np.isin(pool, refs)
            if not fresh.any() and np.isin(allowed, refs, invert=True).any():
                pool = allowed[np.isin(allowed, refs, invert=True)]  # the pool ran out
                mean, var = np.asarray(post.mean)[pool], variance_at(post, pool)
                fresh = np.ones(pool.shape[0], dtype=bool)
            ref = _best_reference(post, refs, rng) if refs else None
            if ref is None:  # nothing to compare with: the most informative rating, or variance
                values = (
                    var
                    if post.ordinal is None
                    else rating_information(post.ordinal, post.kernel.variance, mean, var)
                )
            else:
                values = information_against(post, pool, ref, mean, var)
            if not fresh.any():  # a region no larger than the references: repeat one
                chosen.append(
                    ref if ref is not None and safe[ref] else int(pool[random_argmax(values, rng)])
                )
                continue
            chosen.append(int(pool[random_argmax(np.where(fresh, values, -np.inf), rng)]))
        return tuple(chosen)

    def joint_draws(self, n: int) -> tuple[int, str | None]:
        """None: it reads means and variances (as :class:`~gaitpref.strategies.SelfSparring`)."""
        return 0, None


def _best_reference(posterior: Posterior, refs: list[int], rng: np.random.Generator) -> int:
    """The reference with the highest posterior mean (exact ties at random)."""
    mean = np.asarray(posterior.mean)[np.asarray(refs, dtype=np.intp)]
    return refs[random_argmax(mean, rng)]


__all__ = ["InformationGain", "candidate_pool"]
