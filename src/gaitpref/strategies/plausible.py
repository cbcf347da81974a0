"""EUBO among the plausible maximisers, gated by joint posterior samples.

Gated EUBO (``hybrid.py``) runs the EUBO challenger of the buffered gait whenever one Thompson
draw's argmax is not buffered.  Its challenger may be any gait of the grid, and EUBO
(``eubo.py``; Lin et al., AISTATS 2022, ``E[max(f_x, f_y)]``) favours the uncertain ones.
:class:`PlausibleEubo` (``"plausible-eubo"``) restricts the challenger to the *plausible
maximisers*: the distinct argmaxes of ``samples`` joint posterior draws, a Monte Carlo estimate of
the support of ``P(x is the best gait)`` (the distribution Thompson sampling draws from; Russo
and Van Roy 2014 use the same estimate for information-directed sampling).  A gait that no draw
ranks first is never run as a challenger, however uncertain it is, as MaxInP (Saha, NeurIPS 2021)
duels only among arms that may still be best, here with the posterior's joint samples in place
of confidence bounds.

The gate: with ``n = 1`` and a buffer, if one of the first ``gates`` draws' argmaxes is buffered,
that gait runs again (a draw's argmax is buffered with probability ``p = P(buffered gait is
best)``, so the gait repeats with probability ``1 - (1 - p)^gates``); otherwise the EUBO
challenger of the best buffered gait among the plausible maximisers runs.  Three gates (the
default) repeat a gait the posterior thinks best with ``p = 0.5`` seven times in eight: in the
learning study (``docs/results/learning``) they gained 0.016 over trials 31-150 against one gate
and lost nothing over trials 1-20, where ``p`` is small and the gate rarely fires.  With no
buffer the first action is the first draw's argmax and the others are EUBO challengers, as in
gated EUBO.  When every plausible maximiser is already a reference, EUBO falls back to the whole
grid (``acquire.eubo_fill``).

Every draw uses ``context.rng`` and only ``context.allowed`` actions, so the strategy replays
exactly from the loop's seed and never leaves the region of interest.

Notation: ``n`` new actions per query, ``b`` buffered, ``S`` (``samples``) joint draws.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitpref.strategies.acquire import eubo_fill
from gaitpref.strategies.base import MAX_GATES, MAX_SAMPLES, AskContext, check_count


@dataclass(frozen=True)
class PlausibleEubo:
    """Sample-gated EUBO among the argmaxes of ``samples`` joint draws (module docstring)."""

    samples: int = 32
    gates: int = 3
    name: str = "plausible-eubo"

    def __post_init__(self) -> None:
        check_count(self, "samples", 1, MAX_SAMPLES)
        check_count(self, "gates", 1, MAX_GATES)
        if self.gates > self.samples:
            raise ValueError(
                f"gates ({self.gates}) must not exceed samples ({self.samples}): "
                "the gate reads the first draws"
            )

    def propose(self, context: AskContext) -> tuple[int, ...]:
        draws = context.posterior.argmax_samples(context.rng, self.samples, context.allowed)
        picks = [int(a) for a in draws]
        plausible = np.unique(np.asarray(picks, dtype=np.intp))
        if not context.buffer:
            return eubo_fill(context, picks[:1], plausible)
        if context.n == 1:
            for pick in picks[: self.gates]:
                if pick in context.buffer:
                    return (pick,)
        return eubo_fill(context, [], plausible)

    def joint_draws(self, n: int) -> tuple[int, str | None]:
        """``samples`` (as :class:`~gaitpref.strategies.SelfSparring`)."""
        return self.samples, "samples"
