"""Replay: rebuild a session's state from its log, re-deriving and checking every event.

Each logged event is derived again from the state so far (``session_state.py``: the proposal
CoSpar makes with the session's seed, the answer's preferences, the exclusion, the validation
order) and compared with the log field by field (``session_log.CHECKED_FIELDS``).  The first
difference raises :class:`~gaitpref.sessions.records.ReplayError` showing it; nothing is written.
An answer's events (one transaction) are replayed together.
"""

from __future__ import annotations

from collections.abc import Sequence

from gaitpref.errors import ReplayError, SessionStateError
from gaitpref.loop.cospar import QueryError
from gaitpref.sessions import records as log
from gaitpref.sessions.state import SessionState
from gaitpref.storage import EventRecord, NewEvent


def replay(state: SessionState, records: Sequence[EventRecord]) -> None:
    """Apply logged ``records`` to ``state``, re-deriving and checking each one."""
    i = 0
    while i < len(records):
        r = records[i]
        if r.seq != state.last_seq + 1:
            raise ReplayError(f"event {r.seq} follows event {state.last_seq}: the log has a gap")
        if r.kind in log.ANSWER_KINDS:
            j = i
            while (
                j < len(records)
                and records[j].kind in log.ANSWER_KINDS
                and records[j].payload.get("query") == r.payload.get("query")
                and (j == i or records[j].kind != log.TRIAL or records[j - 1].kind == log.TRIAL)
            ):
                j += 1
            _replay_answer(state, records[i:j])
            i = j
            continue
        _replay_one(state, r)
        i += 1


def _check(r: EventRecord, derived: NewEvent) -> None:
    fields = log.CHECKED_FIELDS.get(r.kind, ())
    if derived.kind != r.kind or any(r.payload.get(f) != derived.payload.get(f) for f in fields):
        raise ReplayError(log.describe_mismatch(r.seq, r.kind, r.payload, derived.payload))


def _replay_one(state: SessionState, r: EventRecord) -> None:
    p = r.payload
    try:
        if r.kind == log.QUERY:
            if state.pending is not None:
                raise ReplayError(
                    f"event {r.seq}: a query was issued while {state.pending.id} was pending"
                )
            _check(r, NewEvent(log.QUERY, state.derive_query()))
        elif r.kind == log.UNDO:
            _check(r, state.undo_event())
        elif r.kind == log.EXCLUDED:
            _check(r, state.exclude_event(p["trial"], p["reason"], p.get("detail", "")))
            state.apply_exclusion(p)
        elif r.kind == log.VALIDATION_STARTED:
            _check(r, state.validation_event())
        elif r.kind == log.VALIDATION_ANSWERED:
            _check(r, state.validation_answer_event(p["round"], p["ranking"]))
    except (SessionStateError, QueryError, ValueError, KeyError) as exc:
        raise ReplayError(f"event {r.seq} ({r.kind}) cannot be applied: {exc}") from None
    state.commit([r])


def _replay_answer(state: SessionState, group: Sequence[EventRecord]) -> None:
    first = group[0]
    query = state.pending
    if first.kind != log.TRIAL or query is None or first.payload.get("query") != query.id:
        pending = "no query is pending" if query is None else f"the pending query is {query.id}"
        raise ReplayError(
            f"event {first.seq} ({first.kind}) answers query {first.payload.get('query')}, "
            f"but {pending}"
        )
    comparisons = [
        (r.payload["first"], r.payload["second"], r.payload["outcome"])
        for r in group
        if r.kind == log.COMPARISON
    ]
    suggestions = [
        (r.payload["action"], r.payload["feature"], r.payload["move"])
        for r in group
        if r.kind == log.SUGGESTION
    ]
    try:
        answer = state.tell(query, comparisons, suggestions)
    except (QueryError, ValueError, ArithmeticError, RuntimeError) as exc:
        raise ReplayError(
            f"event {first.seq}: the logged answer to query {query.id} is refused now: {exc}"
        ) from None
    derived = state.answer_events(query, answer)
    try:
        if len(derived) != len(group):
            raise ReplayError(
                f"event {first.seq}: the answer to query {query.id} has {len(group)} events "
                f"in the log, {len(derived)} on replay"
            )
        for r, d in zip(group, derived, strict=True):
            _check(r, d)
    except ReplayError:
        state.revert_tell()
        raise
    state.commit(group, answer)
