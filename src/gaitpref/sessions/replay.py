"""Replay: rebuild a session's state from its log, re-deriving and checking every event.

Each logged event is read through its payload class (validated, its schema version checked;
``events.py``), derived again from the state so far (``state.py``: the proposal CoSpar makes with
the session's seed, the answer's terms, the exclusion, the validation order) and compared with the
log on the payload class's checked fields (numbers within rounding: a log written on another
machine replays, and a refit's numbers are then taken from the log).  The first difference
raises :class:`~gaitpref.errors.ReplayError` showing it; nothing is written.  An answer's
events (one transaction: trials, one event per feedback record of any registered kind, the
refit) are replayed together, and so are a query's (the gaits made on demand for it, then the
query, or the ``query_stopped`` of an ask that stopped at ``[gaits] max_infeasible``, or with
no gait left to propose).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from gaitpref.errors import QueryError, ReplayError, SessionStateError
from gaitpref.feedback import kind_for_event
from gaitpref.loop.cospar import Answer
from gaitpref.sessions import events as log
from gaitpref.sessions.gaits import RecordedGaits
from gaitpref.sessions.state import SessionState
from gaitpref.sessions.stored_config import check_row
from gaitpref.storage import EventRecord, NewEvent


def replay(
    state: SessionState,
    records: Sequence[EventRecord],
    after: Callable[[SessionState, EventRecord], None] | None = None,
) -> None:
    """Apply logged ``records`` to ``state``, re-deriving and checking each one; ``after`` is
    called with the state and the last event of each step (one event, or an answer's events)."""
    i = 0
    while i < len(records):
        r = records[i]
        if r.seq != state.last_seq + 1:
            raise ReplayError(f"event {r.seq} follows event {state.last_seq}: the log has a gap")
        log.read_payload(r)  # validates the payload and its version
        if (r.seq == 1) != (r.kind == log.CREATED):
            raise ReplayError(
                f"event {r.seq} ({r.kind}): a log starts with its 'created' event, and only "
                "there; the database was altered"
            )
        if r.kind == log.CREATED and state.row is not None:
            check_row(state.row, r.payload)  # the row replay reads seed and config from
        if log.is_answer_part(r.kind):
            j = i
            while (
                j < len(records)
                and log.is_answer_part(records[j].kind)
                and records[j].payload.get("query") == r.payload.get("query")
                and (j == i or records[j].kind != log.TRIAL or records[j - 1].kind == log.TRIAL)
            ):
                if j > i:
                    log.read_payload(records[j])
                j += 1
            _replay_answer(state, records[i:j])
            if after is not None:
                after(state, records[j - 1])
            i = j
            continue
        if log.is_query_part(r.kind) or r.kind in (log.QUERY, log.QUERY_STOPPED):
            j = i
            while j < len(records) and log.is_query_part(records[j].kind):
                j += 1
                if j < len(records):
                    log.read_payload(records[j])
            _replay_query(state, records[i : j + 1])
            i = j + 1
            continue
        _replay_one(state, r)
        if after is not None:
            after(state, r)
        i += 1


def _check(r: EventRecord, derived: NewEvent) -> None:
    if not log.same_event(r, derived):
        raise ReplayError(log.describe_mismatch(r.seq, r.kind, r.payload, derived.payload))


def _replay_one(state: SessionState, r: EventRecord) -> None:
    p = r.payload
    try:
        if r.kind == log.UNDO:
            _check(r, state.undo_event())
        elif r.kind == log.EXCLUDED:
            _check(r, state.exclude_event(p["trial"], p["reason"], p.get("detail", "")))
            state.apply_exclusion(p, r.version)
        elif r.kind == log.UNSAFE:
            _check(r, state.unsafe_event(p["trial"], p["reason"]))
        elif r.kind == log.UNSAFE_WITHDRAWN:
            _check(r, state.withdraw_unsafe_event(p["trial"]))
        elif r.kind == log.VALIDATION_STARTED:
            _check(r, state.validation_event(r.version, p.get("opened_by")))
        elif r.kind == log.VALIDATION_WITHDRAWN:
            _check(r, state.withdraw_validation_event(p["round"], p["reason"]))
        elif r.kind == log.VALIDATION_ANSWERED:
            _check(r, state.validation_answer_event(p["round"], p["ranking"]))
    except (SessionStateError, QueryError, ValueError, KeyError) as exc:
        raise ReplayError(f"event {r.seq} ({r.kind}) cannot be applied: {exc}") from None
    state.commit([r])


def _replay_query(state: SessionState, group: Sequence[EventRecord]) -> None:
    """A query's batch: the gaits made on demand for it (if any), then its ``query_issued`` (or
    ``query_stopped``: an ask that proposed nothing); the gaits themselves are taken from the log
    where it carries them (``gaits.py``)."""
    first, last = group[0], group[-1]
    if last.kind not in (log.QUERY, log.QUERY_STOPPED):
        raise ReplayError(
            f"event {first.seq} ({first.kind}): gaits made for a query that was never issued"
        )
    if state.pending is not None:
        raise ReplayError(
            f"event {last.seq}: a query was issued while {state.pending.id} was pending"
        )
    try:
        derived = state.derive_query(RecordedGaits(group))
    except ReplayError:
        raise
    except (SessionStateError, QueryError, ValueError, RuntimeError) as exc:
        raise ReplayError(f"event {first.seq} ({first.kind}) cannot be applied: {exc}") from None
    kinds = [d.kind for d in derived]
    if kinds != [r.kind for r in group]:
        raise ReplayError(
            f"event {first.seq}: the log issues this query with {[r.kind for r in group]}, "
            f"replay with {kinds}"
        )
    for r, d in zip(group, derived, strict=True):
        _check(r, d)
    state.commit(group)


def _replay_answer(state: SessionState, group: Sequence[EventRecord]) -> None:
    first = group[0]
    query = state.pending
    if first.kind != log.TRIAL or query is None or first.payload.get("query") != query.id:
        pending = "no query is pending" if query is None else f"the pending query is {query.id}"
        raise ReplayError(
            f"event {first.seq} ({first.kind}) answers query {first.payload.get('query')}, "
            f"but {pending}"
        )
    answers: list[object] = []
    for r in group:
        kind = kind_for_event(r.kind)
        if kind is not None:
            answers.append(kind.from_payload(log.read_payload(r)))
    try:
        answer = state.tell(query, answers)
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
    state.commit(group, _adopt_recorded(state, answer, group, derived))


def _adopt_recorded(
    state: SessionState, answer: Answer, group: Sequence[EventRecord], derived: Sequence[NewEvent]
) -> Answer:
    """The answer with its refits' numbers as the log has them where they differ in the last
    bits from what this machine derived (another machine's rounding; already checked to agree
    within it): what follows is then derived from the log's numbers (``CoSpar.adopt_recorded``)."""
    refit: dict[str, Any] | None = None
    share: float | None = None
    shares: list[dict[str, Any]] | None = None
    for r, d in zip(group, derived, strict=True):
        if r.payload == d.payload:  # bit for bit, as on the machine that recorded it
            continue
        if r.kind == log.REFIT:
            refit = r.payload
        elif r.kind == log.SHARE_REFIT:
            share = float(r.payload["after"])
            shares = r.payload.get("hypotheses")
    if refit is None and share is None:
        return answer
    return state.loop.adopt_recorded(refit, share, shares)
