"""A session's proposals with gaits made on demand: an infeasible gait never reaches the subject.

With ``[gaits] generator`` (issue 13, item 4) every action a query proposes gets its gait before
the query is logged (``gaitpref.gaits.on_demand``: this session's gait, else the cached one, else
a new one warm-started from the nearest feasible gait made so far, within ``[gaits]
max_iterations`` solver iterations, so that no gait costs more than that).  A gait that cannot be
made is logged as ``gait_infeasible`` with the solver's reason; the loop then never proposes it,
nor the actions within ``[gaits].avoid_radius`` of it (:meth:`~gaitpref.loop.CoSpar.avoid_all`,
the unsafe-flag neighbourhood of ``loop/safety.py``, for every such action of the proposal at
once), and proposes again with the same random state (the avoidance withdraws the proposal; on the
line path that frees its rows, so they are all named before).  Each gait new to the session is
logged as ``gait_made`` (even when the proposal is then withdrawn: its gait is made); both events
carry the gait itself (payload version 2).

One ask is bounded: once its proposals reach ``[gaits] max_infeasible`` gaits that cannot be
made (counted at the end of a proposal, so the last may pass it by a few when a query proposes
several actions), it stops and proposes nothing.  Its batch, every ``gait_made`` and
``gait_infeasible`` so far, is then logged with a closing ``query_stopped`` (how many, and the
limit) instead of a ``query_issued``, and the session raises
:class:`~gaitpref.errors.InfeasibleProposalsError`.  The loop has avoided each of them, exactly
as the log says, so the next ask goes on from there (with the same random state a longer ask
would have had), and replay derives the stopped batch again with the logged limit.  Replay of
a batch that ends in ``query_issued`` applies no limit: logs written before it replay as they
ran.

An ask whose infeasible gaits leave no gait that may be proposed before the limit (``ask``
raises :class:`~gaitpref.errors.NoSafeGaitError`: the region of avoidance, the unsafe flags and
the gaits avoided cover the space; or, on the line path,
:class:`~gaitpref.errors.ShortLinesError`: each line drawn that still has such a point holds
fewer than the query's ``n`` points) stops the same way: its batch is logged with a closing
``query_stopped`` whose ``infeasible`` is under its ``limit``, and the session raises a plain
:class:`~gaitpref.errors.NoSafeGaitError` saying so.  Before, such an ask wrote nothing: its
gaits were in the gait cache only, so the log, and what the next ask or a replay saw, lacked
them.  A log has no such batch from before (an ask that ran out wrote nothing), so every log
replays as it ran; replay derives such a batch again as it derives one stopped at the limit (the
same rounds, then ``ask`` refuses where the log stops: the loop alone decides, from the log).
An ask that finds no gait may be proposed before any proposal writes nothing, as before.

An ask in which the gait generator fails (raises a :class:`~gaitpref.errors.GaitError`, as
opposed to finding a gait infeasible) writes nothing, even after it found gaits: a batch cut
there ends neither at the limit nor where no gait is left, the two stops a ``query_stopped``
can say and replay re-derives without the generator; replay would go on proposing past the end
of such a batch (making, or failing to make, the next gait) and find a difference, and a reload
that says a stop again from its payload (``retry=False``) would give the wrong reason.  Logging
it needs a payload that says why (a new version and a migration) or a new event kind.  Nothing
is lost: every gait it made is in the gait cache, so the next ask, with nothing logged in
between, proposes the same gaits with the same random state and takes them from the cache (or
makes them again the same way, each warm-started from the same earlier gait), logging exactly
what an ask without the failure would have; the error says so (:func:`unlogged_error`).
A generator that raises anything else (a bug, a ``LinAlgError`` of numpy or scipy) raises a
:class:`~gaitpref.errors.GaitGeneratorFaultError` naming the generator, the gait and the error
(``gaits/on_demand.py``), handled the same way, and saying that nothing is logged even at the
ask's first gait; the terminal, the console and the CLI report it as any ``GaitError``.  The
session writes nothing either way and rebuilds its state from the log before its next
operation, so a retry is the ask the log says comes next: logging the failure would add an
event kind (or a payload version) that earlier releases cannot replay, and record nothing the
next ask needs.

Replay derives the same batch and checks it event by event (``replay.py``).  A gait the log
carries is taken from the log (:class:`RecordedGaits`), never optimised again: its key must be
the one derived for the proposed point, its document must read as a gait, and its verdict must
be the event's (``gait_made`` feasible, ``gait_infeasible`` not); it is then put into the gait
cache.  A version-1 event carries no gait: that one is taken from the cache, or made again.
A logged gait is also checked as a freshly made one is
(:func:`~gaitpref.gaits.on_demand.made_gait_problem`, with the step length the proposal asks
for).  One that fails (an edited or damaged database, or a release whose checks were weaker)
does not stop the replay, since databases of earlier releases must open and replay as they
ran: the session replays as logged (the same queries, the same posterior), but the gait is
neither put into the gait cache (folder or memory) nor used as a warm start, and a
:class:`~gaitpref.gaits.gait_cache.GaitCacheWarning` names the session, the event (seq, kind),
the gait id, its key and the problem (:attr:`RecordedGaits.handed_out`).  An ask of that point
from the cache then makes it afresh, as for a version-1 event whose gait is not cached (a cache
file failing the check is not used either: ``OnDemandGaits._usable``).  The replayed session
itself keeps the point as the log says it was made: proposing it again logs and makes nothing.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from gaitpref.config import ExperimentConfig
from gaitpref.errors import (
    GaitError,
    GaitGeneratorError,
    GaitGeneratorFaultError,
    GaitLibraryError,
    InfeasibleProposalsError,
    NoSafeGaitError,
    ReplayError,
    ShortLinesError,
    SimulationError,
)
from gaitpref.loop import CoSpar, Query
from gaitpref.sessions import events as log
from gaitpref.storage import EventRecord, NewEvent

if TYPE_CHECKING:
    from gaitpref.gaits.gait_cache import CachedGait
    from gaitpref.gaits.on_demand import MadeGait, OnDemandGaits


class RecordedGaits:
    """The gaits a logged query batch carries, handed out in the log's order: the ``k``-th gait
    event the replay derives for the batch is the batch's ``k``-th (each is a gait new to the
    session, but for an infeasible one proposed again, which :meth:`skip` passes over).

    Called with the key derived for the proposed point: the logged gait, checked (key,
    document, verdict; a :class:`ReplayError` names the event), or None for an event that
    carries none (version 1) or when the log has no more (replay then finds the difference).
    """

    def __init__(self, records: Sequence[EventRecord]) -> None:
        self._next = deque(r for r in records if log.is_query_part(r.kind))
        #: the event of the gait handed out last, as a warning names it
        self.handed_out: str | None = None
        last = records[-1] if records else None
        #: the limit a stopped ask's batch was logged with (None: the batch issued its query)
        self.limit: int | None = (
            int(last.payload["limit"])
            if last is not None and last.kind == log.QUERY_STOPPED
            else None
        )

    @property
    def exhausted(self) -> bool:
        """Whether every gait event of the batch has been handed out (or skipped)."""
        return not self._next

    def skip(self) -> None:
        if self._next:
            self._next.popleft()

    def __call__(self, key: str) -> CachedGait | None:
        if not self._next:
            return None
        r = self._next.popleft()
        p = r.payload
        if "gait" not in p:
            return None
        where = f"event {r.seq} ({r.kind})"
        self.handed_out = f"session {r.session_id}, {where}"
        if p["key"] != key:
            raise ReplayError(
                f"{where}: key: the log has {p['key']}, the proposed point's gait is {key}: "
                "the logged gait is not the gait of this proposal"
            )
        from gaitpref.gaits.gait_cache import CachedGait, read_gait

        try:
            gait = read_gait(p["gait"], f"{where} gait")
        except GaitLibraryError as exc:
            raise ReplayError(str(exc)) from None
        if gait.feasible != (r.kind == log.GAIT_MADE):
            verdict = "feasible" if gait.feasible else "infeasible"
            raise ReplayError(f"{where}: the logged gait is {verdict}, the event says otherwise")
        return CachedGait(key, gait, p.get("warm_start"))


def propose_with_gaits(
    loop: CoSpar,
    gaits: OnDemandGaits,
    config: ExperimentConfig,
    recorded: RecordedGaits | None = None,
) -> tuple[list[NewEvent], Query | None]:
    """The events of the gaits made for the loop's next feasible proposal, and the proposal;
    ``recorded``: on replay, the gaits the log carries for it.  None instead of a proposal when
    the ask stopped at ``[gaits] max_infeasible`` (live; on replay, the logged batch's limit, or
    none), or when no gait was left to propose after some were infeasible: the events then end
    with ``query_stopped``.  :class:`~gaitpref.errors.NoSafeGaitError` (or, on the line path,
    :class:`~gaitpref.errors.ShortLinesError`) when none may be proposed at the first proposal
    (nothing to log), or on replay of a batch that issued its query.  A
    :class:`~gaitpref.errors.GaitError` of the generator is raised as it is, or, live after
    this ask found gaits, as :func:`unlogged_error` says it (nothing is logged).

    Terminates: each round takes at least one more action out of the proposals, an empty
    choice raises :class:`~gaitpref.errors.NoSafeGaitError` from ``ask``, a live ask makes at
    most ``max_infeasible`` rounds, and a replay at most one round past the logged batch.
    """
    assert config.generator is not None
    radius = config.generator.avoid_radius
    limit = config.generator.max_infeasible if recorded is None else recorded.limit
    infeasible = 0
    events: list[NewEvent] = []
    while True:
        past_the_log = recorded is not None and recorded.exhausted
        try:
            query = loop.ask()
        except (NoSafeGaitError, ShortLinesError):  # nothing left (line path: no line of n)
            if not infeasible or limit is None:  # none found yet (nothing to log), or a replay
                raise  # of a batch that issued its query: the log has a difference
            # no gait left before the limit: the ask stops as at the limit, logging what it found
            events.append(log.new_event(log.QueryStopped(infeasible=infeasible, limit=limit)))
            return events, None
        space = loop.space  # the grid, or the line path's points (which the ask may extend)
        bad = []
        for action in dict.fromkeys(query.actions):  # each distinct action once, in order
            try:
                made, new = gaits.get(space.point(action), recorded)
            except GaitError as exc:  # not logged: see the module's docstring
                fault = isinstance(exc, GaitGeneratorFaultError)
                if recorded is not None or not (events or fault):
                    raise
                raise unlogged_error(exc, events) from exc
            if made.feasible:
                if new:
                    events.append(log.new_event(_made(action, made, space.values_of(action))))
                continue
            bad.append(action)
            if not new and recorded is not None:
                recorded.skip()  # logged again without being looked up: keep the log's order
            events.append(log.new_event(_infeasible(action, made, space.values_of(action), radius)))
        if not bad:
            return events, query
        loop.avoid_all(bad, radius)  # all at once: on the line path withdrawal frees their rows
        infeasible += len(bad)
        if limit is not None and infeasible >= limit:  # the loop has avoided all it logs
            events.append(log.new_event(log.QueryStopped(infeasible=infeasible, limit=limit)))
            return events, None
        if past_the_log:  # replay: a proposal the log does not have; it finds the difference
            return events, None


def stopped_error(payload: dict[str, Any], config: ExperimentConfig) -> NoSafeGaitError:
    """What a stopped ask (its logged ``query_stopped`` ``payload``) tells the operator: an
    :class:`~gaitpref.errors.InfeasibleProposalsError` when it reached the limit, a plain
    :class:`~gaitpref.errors.NoSafeGaitError` when no gait was left to propose before it
    (``infeasible`` < ``limit``: asking again proposes nothing until something changes)."""
    infeasible, limit = int(payload["infeasible"]), int(payload["limit"])
    radius = config.generator.avoid_radius if config.generator is not None else 0.0
    logged = (
        f"Each is logged as infeasible and never proposed again, nor the gaits within "
        f"avoid_radius {radius:g} of it."
    )
    if infeasible < limit:
        on_lines = config.subspace == "line"
        short = (
            "; or each line tried that has a gait that may be proposed holds fewer than the "
            f"query's n = {config.n} points, as a line snapped to the values of discrete "
            "features may"
            if on_lines
            else ""
        )
        return NoSafeGaitError(
            f"this ask stopped without proposing: its proposals had {infeasible} gaits that "
            "cannot be made, and then no gait was left that may be proposed (every gait, on the "
            "line path every point of each line tried, is in the region of avoidance, near a "
            f"gait flagged unsafe, or near a gait that cannot be made{short}).  "
            f"{logged}  Withdraw an unsafe flag if one is wrong; or finish this session "
            "and start one whose [space] leaves those gaits out (or with a smaller [gaits] "
            "avoid_radius" + (", or a smaller [cospar] n" if on_lines else "") + ")"
        )
    return InfeasibleProposalsError(
        f"this ask stopped without proposing: its proposals had {infeasible} gaits that cannot "
        f"be made (at most {limit} per ask, [gaits] max_infeasible).  {logged}  Ask again to go "
        "on proposing from there; or, if most of [space] has no gait, finish this session and "
        "start one whose [space] leaves those gaits out (or with a larger [gaits] avoid_radius "
        "or max_infeasible)",
        infeasible=infeasible,
        limit=limit,
    )


def unlogged_error(exc: GaitError, events: Sequence[NewEvent]) -> GaitError:
    """The generator's error ``exc`` saying what became of the gaits this ask found before it
    (``events``: their events, none logged): of ``exc``'s class when it is one of gaitpref's
    (a generator's own class may take other arguments: then a :class:`GaitError`, raised
    from ``exc``).  With no ``events`` (a :class:`~gaitpref.errors.GaitGeneratorFaultError` at
    the ask's first gait) it says that nothing is logged."""
    found = {e.payload["gait_id"]: e.kind for e in events if log.is_query_part(e.kind)}
    bad = sum(kind == log.GAIT_INFEASIBLE for kind in found.values())
    said = str(exc).rstrip(".") or type(exc).__name__
    if not found:  # a generator's fault at the ask's first gait
        text = (
            f"{said}.  Nothing is logged: the session is as it was before this ask, and "
            "asking again, with nothing changed, proposes the same gaits and makes the failed "
            "one again"
        )
        return GaitGeneratorFaultError(text) if isinstance(exc, GaitGeneratorFaultError) else exc
    text = (
        f"{said}.  This ask had found {len(found)} gaits before it "
        f"({bad} that cannot be made): none is logged (an ask is logged whole, and its log "
        "cannot say that the generator failed), but each is in the gait cache: asking again, "
        "with nothing changed, proposes the same gaits and logs them, taking them from there "
        "(or making them again the same way), and makes the failed one again"
    )
    own = (
        GaitError,
        GaitLibraryError,
        GaitGeneratorError,
        GaitGeneratorFaultError,
        SimulationError,
    )
    return type(exc)(text) if type(exc) in own else GaitError(text)  # each takes a message


def _made(action: int, made: MadeGait, values: dict[str, float]) -> log.GaitMade:
    from gaitpref.gaits.gait_cache import gait_document

    return log.GaitMade(
        action=action,
        gait_id=made.gait_id,
        key=made.key,
        values=values,
        cot=float(made.gait.cot),
        warm_start=made.warm_start,
        gait=gait_document(made.gait),
    )


def _infeasible(
    action: int, made: MadeGait, values: dict[str, float], radius: float
) -> log.GaitInfeasible:
    from gaitpref.gaits.gait_cache import gait_document

    return log.GaitInfeasible(
        action=action,
        gait_id=made.gait_id,
        key=made.key,
        radius=radius,
        values=values,
        reason=made.gait.message,
        warm_start=made.warm_start,
        gait=gait_document(made.gait),
    )


#: what ``session show`` and the console say of a recommended gait that is not made
#: (:meth:`~gaitpref.sessions.session.Session.gait_made` is False): on the line path the
#: posterior's highest is often a point no query proposed, a coactive suggestion's
NOT_MADE = (
    "its gait is not made yet: no query has proposed it, so the subject has not walked it; a "
    "query that proposes it makes it, or skips it if it cannot be made"
)

__all__ = ["NOT_MADE", "RecordedGaits", "propose_with_gaits", "stopped_error", "unlogged_error"]
