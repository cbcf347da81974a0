"""A session's confidence in its recommendation, and its stopping rule (``loop/stopping.py``).

The probability comes from posterior samples drawn with a generator of its own,
``SeedSequence(session seed, spawn_key=(CONFIDENCE_STREAM, answers))``: asking for it never moves
the loop's generator (so replay is unaffected) and gives the same number for the same session
state, whoever asks (terminal, console, export).  :func:`confidence_history` replays a log and
states the confidence after every step that changed the model (an answer, an undo, an
exclusion): the export's ``confidence`` table.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from gaitpref.loop.stopping import Confidence, StopRule, confidence
from gaitpref.sessions.replay import replay
from gaitpref.sessions.state import SessionState
from gaitpref.storage import EventRecord

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
        draws=loop.share_mixture(),
    )


def stop_reason(state: SessionState, rule: StopRule) -> str | None:
    """Why ``state`` should move to blind validation now (None: go on, or no rule)."""
    if not rule.active:
        return None
    trials = len(state.loop.executed)
    sure = session_confidence(state, rule) if rule.confidence is not None else None
    return rule.reason(trials, sure)


def confidence_history(
    state: SessionState, events: Sequence[EventRecord], rule: StopRule
) -> list[dict[str, Any]]:
    """Replay ``events`` into the fresh ``state`` and, after every step whose posterior differs
    from the one before, the confidence then (the same numbers the terminal and the console
    showed): one row per step with ``seq`` (its last event), ``answers`` and ``trials`` in
    force, the recommended ``action``, its ``gait`` name and feature ``values`` then (on the
    line path a row may name another point later), ``probability``, ``regret``,
    ``relative_regret``, ``tolerance`` and ``samples``."""
    rows: list[dict[str, Any]] = []
    seen = [state.loop.posterior]

    def step(st: SessionState, last: EventRecord) -> None:
        if st.loop.posterior is seen[0]:
            return
        seen[0] = st.loop.posterior
        sure = session_confidence(st, rule)
        rows.append(
            {
                "seq": last.seq,
                "answers": len(st.loop.answers),
                "trials": len(st.loop.executed),
                "action": sure.recommended,
                "gait": st.gait_id(sure.recommended) or f"G{sure.recommended}",
                "values": st.loop.space.values_of(sure.recommended),
                "probability": sure.probability,
                "regret": sure.regret,
                "relative_regret": sure.relative_regret,
                "tolerance": sure.tolerance,
                "samples": sure.samples,
            }
        )

    replay(state, events, step)
    return rows


__all__ = ["CONFIDENCE_STREAM", "confidence_history", "session_confidence", "stop_reason"]
