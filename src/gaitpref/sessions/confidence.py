"""A session's confidence in its recommendation, and its stopping rule (``loop/stopping.py``).

The probability comes from posterior samples drawn with a generator of its own,
``SeedSequence(session seed, spawn_key=(CONFIDENCE_STREAM, answers))``: asking for it never moves
the loop's generator (so replay is unaffected) and gives the same number for the same session
state, whoever asks (terminal, console, export).
"""

from __future__ import annotations

import numpy as np

from gaitpref.loop.stopping import Confidence, StopRule, confidence
from gaitpref.sessions.state import SessionState

CONFIDENCE_STREAM = 0xC0F1DE7CE  # the confidence's generator: (seed, this, answers in force)


def session_confidence(state: SessionState, rule: StopRule) -> Confidence:
    """The confidence of ``state``'s posterior with the rule's tolerance and sample count."""
    loop = state.loop
    answers = len(loop.answers)
    rng = np.random.default_rng(
        np.random.SeedSequence(state.seed, spawn_key=(CONFIDENCE_STREAM, answers))
    )
    return confidence(
        loop.posterior,
        rng,
        tolerance=rule.tolerance,
        samples=rule.samples,
        allowed=loop.allowed(),
    )


def stop_reason(state: SessionState, rule: StopRule) -> str | None:
    """Why ``state`` should move to blind validation now (None: go on, or no rule)."""
    if not rule.active:
        return None
    trials = len(state.loop.executed)
    sure = session_confidence(state, rule) if rule.confidence is not None else None
    return rule.reason(trials, sure)


__all__ = ["CONFIDENCE_STREAM", "session_confidence", "stop_reason"]
