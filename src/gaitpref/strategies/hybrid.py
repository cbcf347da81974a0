"""Strategies that are strong both early and late in a short session.

Measured on the paper's benchmark (``docs/results/learning``): EUBO (``acquire.py``) finds good
gaits far sooner than self-sparring, but with ``n = 1, b = 1`` it keeps pairing the best gait with
an exploratory one, so late in a session half the executed gaits are exploratory; self-sparring
(Thompson sampling) executes near-best gaits late but explores widely early.

- :class:`GatedEubo` (``"gated-eubo"``): a Thompson gate decides whether to exploit.  Draw
  ``gates`` posterior samples; if one of their argmaxes is a buffered action, run that action
  again (as self-sparring would, with probability ``P(buffered action is best)``); otherwise run
  the EUBO challenger of the best buffered action.  Early the posterior is wide, the gate rarely
  fires and the loop behaves like EUBO; late the buffered gait is usually the best, and the loop
  behaves like self-sparring.  A repeat brings no comparison, but the gate is random and
  re-drawn every trial, so the loop cannot lock in (EUBO's failure when it may re-propose the
  winner: once every challenger's value is below rounding it repeats the winner forever).
  With no buffer the first action is the first sample's argmax and the others are EUBO's.
  ``early_scale`` (off at 1): during the first ``early_trials`` trials EUBO's challenger is
  chosen on the same answers refitted with the lengthscales times ``early_scale``; with 0.5 and
  coactive feedback the challenger stays nearer the gaits the answers favour, and trials 1-20 of
  the paper's benchmark gain 0.039 (``docs/learning.md``, "A local challenger early"; on fresh
  objectives like them +0.011 ± 0.012, "An exploration burst").
  ``sparring_from`` and ``sparring_until`` (off unless ``sparring_until`` is the larger): the
  trials after the first ``sparring_from`` up to trial ``sparring_until`` run self-sparring
  instead (each new action a posterior sample's argmax over the whole space, the paper's rule): a
  burst of global exploration once EUBO has found a good region, so that the gate and EUBO
  exploit afterwards on a posterior that has looked everywhere (``docs/learning.md``, "An
  exploration burst"): it lifts the later trials at the cost of the burst's own, and is level
  over a whole 150-trial session.
- :class:`Switch` (``"eubo-then-sparring"``): one strategy for the first ``trials`` trials
  (EUBO), another after (self-sparring).

Notation: ``n`` new actions per query, ``b`` buffered.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from gaitpref.checks import is_count, is_number
from gaitpref.strategies.acquire import Eubo, eubo_fill
from gaitpref.strategies.base import (
    MAX_GATES,
    AskContext,
    SelfSparring,
    Strategy,
    check_count,
    joint_draws,
    plain,
)


@dataclass(frozen=True)
class GatedEubo:
    """Thompson-gated EUBO (see the module docstring); with ``early_scale`` other than 1, EUBO
    chooses during the first ``early_trials`` trials on the posterior refitted with every
    lengthscale times ``early_scale`` (``AskContext.rescaled``), the gate on the loop's own."""

    gates: int = 1
    early_scale: float = 1.0
    early_trials: int = 20
    sparring_from: int = 0
    sparring_until: int = 0
    name: str = "gated-eubo"

    def __post_init__(self) -> None:
        check_count(self, "gates", 1, MAX_GATES)
        scale = self.early_scale
        if not is_number(scale) or not 0.01 <= scale <= 100:
            raise ValueError(f"early_scale must be a number in [0.01, 100], got {scale!r}")
        object.__setattr__(self, "early_scale", plain(scale))  # a NumPy number as Python's
        for setting in ("early_trials", "sparring_from", "sparring_until"):
            trials = getattr(self, setting)
            if not is_count(trials) or trials < 0:
                raise ValueError(f"{setting} must be an integer >= 0, got {trials!r}")
            object.__setattr__(self, setting, int(trials))

    def propose(self, context: AskContext) -> tuple[int, ...]:
        if self.sparring_from <= context.trial < self.sparring_until:
            return SelfSparring().propose(context)
        picks = [
            int(a)
            for a in context.posterior.argmax_samples(context.rng, self.gates, context.allowed)
        ]
        if not context.buffer:
            return eubo_fill(self._chooser(context), picks[:1], None)
        if context.n == 1:
            for pick in picks:
                if pick in context.buffer:
                    return (pick,)
        return eubo_fill(self._chooser(context), [], None)

    def joint_draws(self, n: int) -> tuple[int, str | None]:
        """``gates``, or ``n`` in a burst of self-sparring when that is more (as
        :class:`SelfSparring`)."""
        if self.sparring_from < self.sparring_until and n > self.gates:
            return n, "n"
        return self.gates, "gates"

    def _chooser(self, context: AskContext) -> AskContext:
        """The context EUBO chooses in: the rescaled posterior early, else ``context``."""
        early = context.trial < self.early_trials and self.early_scale != 1.0
        if not early or context.rescaled is None:
            return context
        return replace(context, posterior=context.rescaled(float(self.early_scale)))


@dataclass(frozen=True)
class Switch:
    """``early`` for the first ``trials`` trials, ``late`` after."""

    trials: int = 20
    early: Strategy = field(default_factory=Eubo)
    late: Strategy = field(default_factory=SelfSparring)
    name: str = "eubo-then-sparring"

    def __post_init__(self) -> None:
        if not is_count(self.trials) or self.trials < 0:
            raise ValueError(f"trials must be an integer >= 0, got {self.trials!r}")
        object.__setattr__(self, "trials", int(self.trials))
        for part in ("early", "late"):  # a name in place of a strategy failed at its first ask
            if not callable(getattr(getattr(self, part), "propose", None)):
                raise TypeError(
                    f"{part} must be a strategy (make_strategy(name)), got {getattr(self, part)!r}"
                )

    def propose(self, context: AskContext) -> tuple[int, ...]:
        chosen = self.early if context.trial < self.trials else self.late
        return chosen.propose(context)

    def joint_draws(self, n: int) -> tuple[int, str | None]:
        """The more of ``early``'s and ``late``'s (as :class:`SelfSparring`)."""
        return max(joint_draws(self.early, n), joint_draws(self.late, n), key=lambda d: d[0])
