"""A session's confidence in its recommendation, and its stopping rule (``loop/stopping.py``).

The probability comes from posterior samples drawn with a generator of its own,
``SeedSequence(session seed, spawn_key=(CONFIDENCE_STREAM, answers))``: asking for it never moves
the loop's generator (so replay is unaffected) and gives the same number for the same session
state, whoever asks (terminal, console, export).  :func:`confidence_history` replays a log and
states the confidence after every step that changed the model (an answer, an undo, an
exclusion): the export's ``confidence`` table, whose row says ``learned`` false and names no gait
while no preference is learned (:func:`preference_learned`), as the terminal and the console
then state no confidence.  When no gait may be proposed (the region of
avoidance and the unsafe flags cover the grid, or no gait was made yet: below) there is nothing
to recommend: the session states no confidence (:class:`~gaitpref.errors.NoSafeGaitError`), the
rule does not act on one and the table has no row for that step.  :func:`recommended` names
the same gait without sampling (what ``session show``, the console and exports call the best so
far).

With gaits made on demand (``[gaits] generator``) the model's points are not all gaits: on a
continuous space the posterior's highest is often a point only a coactive suggestion named, whose
gait was never made and may not exist.  Under ``[gaits] recommend = "made"`` (the default since
defaults version 0.13) the recommendation is the best gait the session made (feasible: a
``gait_made`` event), by posterior mean, among those that may be proposed: an operator can only
put the subject in a gait that exists.  The confidence is then that this gait is within the
tolerance of the best of every gait that may be proposed, made or not (so more exploration shows
as a lower probability, and the ``[stop]`` rule waits for it), and blind validation's "max" is the
same gait.  Before any gait is made there is nothing to recommend (:func:`no_recommendation`
says why).  Sessions recorded under earlier defaults (``recommend = "any"``) recommend the best
point, made or not, as they did.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from gaitpref.errors import NoSafeGaitError
from gaitpref.loop.stopping import (
    Confidence,
    StopRule,
    confidence,
    preference_learned,
    recommendation,
)
from gaitpref.sessions.replay import replay
from gaitpref.sessions.state import SessionState
from gaitpref.storage import EventRecord


class StopCheckWarning(UserWarning):
    """The ``[stop]`` rule could not be checked after an answer (its confidence raised, or
    opening the blind validation round failed, or Ctrl-C stopped it): the answer is stored
    and reported as stored (:attr:`~gaitpref.sessions.records.Answered.stop_warning` says
    why), and the rule is checked again after the next answer."""


CONFIDENCE_STREAM = 0xC0F1DE7CE  # the confidence's generator: (seed, this, answers in force)
Mask = NDArray[np.bool_]  # over the posterior's gaits (rows)


def _made(state: SessionState) -> Mask | None:
    """The gaits (rows) this session made, when its recommendation is restricted to them
    (``[gaits] recommend = "made"``); None when it is not (no generator, or ``"any"``)."""
    spec = state.config.generator
    if spec is None or not spec.recommends_made:
        return None
    made = np.zeros(len(state.loop.space), dtype=bool)
    made[state.walkable] = True
    return made


def no_recommendation(state: SessionState) -> str | None:
    """Why ``state`` recommends no gait (None: it recommends one): every gait is in the region
    of avoidance or near a gait flagged unsafe, or, with ``[gaits] recommend = "made"``, no gait
    was made yet, or every gait made is."""
    return _masks(state)[2]


def _masks(state: SessionState) -> tuple[Mask | None, Mask | None, str | None]:
    """``loop.allowed()``, :func:`_made` and :func:`no_recommendation`'s reason (one
    ``allowed()``: the region of avoidance reads the posterior's variance)."""
    allowed = state.loop.allowed()
    if allowed is not None and allowed.size and not allowed.any():  # size 0: no point yet
        return (
            allowed,
            None,
            "every gait is in the region of avoidance or near a gait flagged unsafe",
        )
    made = _made(state)
    why = None
    if made is not None and not made.any():
        why = (
            "no gait has been made yet (gaits made on demand: only a gait a query proposed and "
            "the generator made may be recommended)"
        )
    elif made is not None and allowed is not None and not (made & allowed).any():
        why = "every gait made so far is in the region of avoidance or near a gait flagged unsafe"
    return allowed, made, why


def session_confidence(state: SessionState, rule: StopRule) -> Confidence:
    """The confidence of ``state``'s posterior with the rule's tolerance and sample count (fewer
    samples on large grids: :meth:`StopRule.samples_for`);
    :class:`~gaitpref.errors.NoSafeGaitError` when no gait may be recommended
    (:func:`no_recommendation` says why)."""
    loop = state.loop
    allowed, made, why = _masks(state)
    if why is None and not len(loop.space):
        why = "the line path has no point before its first query"
    if why is not None:
        raise NoSafeGaitError(
            f"no gait may be recommended: {why}, so there is no confidence to state"
        )
    answers = len(loop.answers)
    rng = np.random.default_rng(
        np.random.SeedSequence(state.seed, spawn_key=(CONFIDENCE_STREAM, answers))
    )
    return confidence(
        loop.posterior,
        rng,
        tolerance=rule.tolerance,
        samples=rule.samples_for(len(loop.posterior.space)),
        allowed=allowed,
        draws=loop.share_mixture(),
        among=made,
    )


def recommended(state: SessionState) -> int | None:
    """The gait the session recommends: the posterior mean's argmax among the gaits that may be
    proposed (``loop.allowed()``: the region of avoidance, gaits flagged unsafe and their
    radius) and, with ``[gaits] recommend = "made"``, were made, the lowest index among exact
    ties, as :func:`session_confidence` recommends it.  None while the posterior has no point
    (the line path before its first query) and when no gait may be recommended
    (:func:`no_recommendation`).  Unlike ``Posterior.argmax`` it never names a gait that may
    not be walked."""
    loop = state.loop
    if not len(loop.space):
        return None
    allowed, made, why = _masks(state)
    if why is not None:
        return None
    if made is not None:
        allowed = made if allowed is None else made & allowed
    return recommendation(loop.posterior.mean, allowed)


def recommends(state: SessionState) -> bool:
    """Whether some gait may be recommended (else no confidence is stated)."""
    return no_recommendation(state) is None


def stop_reason(
    state: SessionState, rule: StopRule, sure: Callable[[], Confidence] | None = None
) -> str | None:
    """Why ``state`` should move to blind validation now (None: go on, or no rule); ``sure``
    gives the confidence of ``state`` when the caller keeps it (default: worked out here).
    The gait is named as the confidence sentence names it (:meth:`SessionState.gait_name`).
    The confidence counts only once a preference is learned (:func:`preference_learned`):
    before, the recommendation is the first gait for no reason, and no confidence is shown."""
    if not rule.active:
        return None
    trials = len(state.loop.executed)
    stated = None
    learned = preference_learned(state.loop.posterior.mean)
    if rule.confidence is not None and learned and recommends(state):
        stated = session_confidence(state, rule) if sure is None else sure()
    name = None if stated is None else state.gait_name(stated.recommended)
    return rule.reason(trials, stated, name)


#: a ``confidence_history`` row's fields when no confidence is stated (no preference learned)
_UNSTATED: dict[str, Any] = dict.fromkeys(
    (
        "action", "gait", "made", "probability", "regret", "relative_regret", "tolerance",
        "samples",
    )
)  # fmt: skip


def confidence_history(
    state: SessionState,
    events: Sequence[EventRecord],
    rule: StopRule,
    progress: Callable[[int, int], None] | None = None,
) -> list[dict[str, Any]]:
    """Replay ``events`` into the fresh ``state`` and, after every step whose posterior differs
    from the one before, the confidence then (the same numbers the terminal and the console
    showed): one row per step with ``seq`` (its last event), ``answers`` and ``trials`` in
    force, ``learned`` (:func:`preference_learned`: False while the posterior mean is flat,
    before any answer tells gaits apart and after ties only, when the terminal and the console
    state no confidence and every field below is None, the feature values too), the recommended
    ``action``, its ``gait`` name, ``made`` (with gaits made on demand,
    whether the session had made its gait then: :meth:`SessionState.gait_made`, as the terminal
    and the console say it; None without) and feature ``values`` then (on the line path a row
    may name another point later), ``probability``, ``regret``,
    ``relative_regret``, ``tolerance`` and ``samples``.  ``progress(done, total)``: called
    after each step with the events replayed so far and their number (an export of a long
    session on a large grid takes minutes: the CLI shows a bar)."""
    rows: list[dict[str, Any]] = []
    unstated_values = {f.name: None for f in state.config.space.features}
    seen = [state.loop.posterior]
    first = events[0].seq if events else 0

    def step(st: SessionState, last: EventRecord) -> None:
        if progress is not None:
            progress(last.seq - first + 1, len(events))
        if st.loop.posterior is seen[0]:
            return
        seen[0] = st.loop.posterior
        if not recommends(st):  # nothing may be proposed: no confidence was stated
            return
        counts = {
            "seq": last.seq,
            "answers": len(st.loop.answers),
            "trials": len(st.loop.executed),
        }
        if not preference_learned(st.loop.posterior.mean):
            # the mean is flat (no answer yet told gaits apart): the recommendation would be
            # the first gait for no reason, and the terminal and the console state nothing
            rows.append({**counts, "learned": False, **_UNSTATED, "values": unstated_values})
            return
        sure = session_confidence(st, rule)
        rows.append(
            {
                **counts,
                "learned": True,
                "action": sure.recommended,
                "gait": st.gait_name(sure.recommended),
                "made": st.gait_made(sure.recommended),
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


__all__ = [
    "CONFIDENCE_STREAM",
    "StopCheckWarning",
    "confidence_history",
    "no_recommendation",
    "recommended",
    "recommends",
    "session_confidence",
    "stop_reason",
]
