"""Single-action terms as the Laplace evidence sees them (``evidence.py``).

An observation of one utility ``f_s`` (an ordinal rating, a Gaussian score, ...) enters the fit
through an :class:`~gaitpref.model.likelihood.ActionLikelihood` (``terms``).  The evidence's
gradient in the kernel's parameters also needs ``c``'s derivative ``third`` (GPML eq. (5.23));
a likelihood with thresholds the evidence may fit (:class:`ThresholdLikelihood`, the ordered
probit of ``ordinal.py``) adds their derivatives.  :class:`SingleData` holds the actions and one
likelihood over them (possibly stacked over kinds), checks that every part can take part, and
substitutes fitted thresholds into the part that has them.

At most one part may have fitted thresholds (one ordinal scale per loop); a part whose
thresholds the config fixes (``thresholds_fixed``) takes part in the kernel gradient only.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from gaitpref.errors import ModelError
from gaitpref.model.likelihood import ActionLikelihood, StackedActionLikelihood
from gaitpref.space import FloatArray, IntArray


class UnsupportedLikelihoodError(ModelError, TypeError):
    """A single-action likelihood the evidence cannot differentiate (it has no ``third``)."""


@runtime_checkable
class EvidenceLikelihood(Protocol):
    """A single-action likelihood the evidence can take: ``terms`` and ``third`` (``dc/df``)."""

    def terms(self, values: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]: ...

    def third(self, values: FloatArray) -> FloatArray: ...


@runtime_checkable
class ThresholdLikelihood(EvidenceLikelihood, Protocol):
    """... with increasing thresholds the evidence may fit (unless ``thresholds_fixed``)."""

    @property
    def thresholds(self) -> FloatArray: ...

    @property
    def thresholds_fixed(self) -> bool: ...

    def with_thresholds(self, thresholds: Sequence[float] | FloatArray) -> ThresholdLikelihood: ...

    def threshold_terms(self, values: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Derivatives of ``(log p, g, c)`` in each threshold: ``n x T`` arrays."""
        ...


def _parts(likelihood: ActionLikelihood, size: int) -> list[tuple[int, ActionLikelihood]]:
    if isinstance(likelihood, StackedActionLikelihood):
        return list(likelihood.parts)
    return [(size, likelihood)]


def _learnable(part: ActionLikelihood) -> bool:
    return isinstance(part, ThresholdLikelihood) and not part.thresholds_fixed


@dataclass(frozen=True)
class SingleData:
    """Observations of ``f[actions[k]]`` (grid indices) under ``likelihood``.

    Raises :class:`UnsupportedLikelihoodError` naming the part that has no ``third``, or that
    more than one part has fitted thresholds.
    """

    actions: IntArray
    likelihood: ActionLikelihood

    def __post_init__(self) -> None:
        parts = _parts(self.likelihood, self.size)
        if sum(n for n, _ in parts) != self.size:
            raise ValueError(f"{self.size} single actions for {sum(n for n, _ in parts)} terms")
        for _, part in parts:
            if not isinstance(part, EvidenceLikelihood):
                raise UnsupportedLikelihoodError(
                    f"the single-action likelihood {type(part).__name__} has no third() "
                    "(d c / d f): the evidence's gradient needs it"
                )
        if sum(_learnable(p) for _, p in parts) > 1:
            raise UnsupportedLikelihoodError(
                "more than one single-action likelihood has thresholds to fit; fix all but one"
            )

    @property
    def size(self) -> int:
        return int(self.actions.shape[0])

    def _learnable_part(self) -> tuple[int, int, ThresholdLikelihood] | None:
        """``(start, stop, part)`` of the part with fitted thresholds, if any."""
        start = 0
        for n, part in _parts(self.likelihood, self.size):
            if _learnable(part):
                assert isinstance(part, ThresholdLikelihood)
                return start, start + n, part
            start += n
        return None

    @property
    def thresholds(self) -> tuple[float, ...] | None:
        """The fitted part's thresholds as built (the prior's centre), None if none is fitted."""
        found = self._learnable_part()
        return None if found is None else tuple(float(t) for t in found[2].thresholds)

    def at(self, thresholds: Sequence[float] | None) -> SingleData:
        """The same data with the fitted part's thresholds replaced (no fitted part, or
        ``thresholds`` None: unchanged)."""
        found = self._learnable_part()
        if thresholds is None or found is None:
            return self
        parts: list[tuple[int, ActionLikelihood]] = []
        for n, p in _parts(self.likelihood, self.size):
            if _learnable(p):
                assert isinstance(p, ThresholdLikelihood)
                p = p.with_thresholds(thresholds)
            parts.append((n, p))
        if isinstance(self.likelihood, StackedActionLikelihood):
            return SingleData(self.actions, StackedActionLikelihood(tuple(parts)))
        return SingleData(self.actions, parts[0][1])

    def third(self, values: FloatArray) -> FloatArray:
        out, start = [], 0
        for n, part in _parts(self.likelihood, self.size):
            assert isinstance(part, EvidenceLikelihood)
            out.append(part.third(values[start : start + n]))
            start += n
        return np.concatenate(out) if out else np.zeros(0)

    def threshold_terms(self, values: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(d log p, d g, d c)`` in the fitted thresholds: ``n x T``, zero off their part."""
        found = self._learnable_part()
        if found is None:
            empty = np.zeros((self.size, 0))
            return empty, empty, empty
        start, stop, part = found
        inner = part.threshold_terms(values[start:stop])
        out = []
        for block in inner:
            full = np.zeros((self.size, block.shape[1]))
            full[start:stop] = block
            out.append(full)
        return out[0], out[1], out[2]


__all__ = ["EvidenceLikelihood", "SingleData", "ThresholdLikelihood", "UnsupportedLikelihoodError"]
