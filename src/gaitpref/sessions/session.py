"""An experiment session with a real subject: durable, resumable, undoable, blind-validated.

A session is a config, a subject and a seed in a database (``gaitpref.storage``), plus the
append-only log of what happened.  The CoSpar state is never stored: it is rebuilt by replaying
the log (``session_state.py``), and replay re-derives every proposal with the same seed and checks
it against the logged one, so a resumed session is the one that was interrupted, bit for bit.

    session = Session.create("sqlite:///lab.db", "exo-1d-step-length", subject="S01")
    query = session.next_query()             # logged before it is returned
    session.answer(query.id, [(query.actions[0], query.buffer[0], "first")],
                   [(query.actions[0], "step_length", "+small")])
    session.undo()                           # the answer is taken back; query is pending again
    session = Session.open("sqlite:///lab.db", session.id)   # after a crash: same state

Every write is committed before the call returns (one answer is one transaction), and nothing is
written when a call raises.  One writer per session: writes are checked against the last event
the session has seen, so two writers cannot both answer the same query (the loser gets
:class:`~gaitpref.storage.ConflictError` or a stale-query :class:`~gaitpref.loop.cospar.QueryError`
and is brought up to date).  Writers take turns (``Storage.writer_turn``: fair, bounded,
shared between processes on SQLite) and catch up with each other before they write, so a second
writer is not starved; past the bounded wait :class:`~gaitpref.storage.SessionBusyError` names
the session.  A ``Session`` object is safe to share between threads.
"""

from __future__ import annotations

import contextlib
import threading
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any, Literal, TypeVar

from gaitpref.checks import is_count
from gaitpref.config import ExperimentConfig, check_new, load_config
from gaitpref.errors import (
    InfeasibleProposalsError,
    NoSafeGaitError,
    ReplayError,
    SessionStateError,
)
from gaitpref.feedback.suggestion import clipped_note
from gaitpref.loop.cospar import QueryError, as_records
from gaitpref.loop.stopping import Confidence
from gaitpref.model.fit_memo import FitMemo, remembering
from gaitpref.model.posterior import Posterior
from gaitpref.sessions import events as log
from gaitpref.sessions.confidence import (
    StopCheckWarning,
    confidence_history,
    no_recommendation,
    recommended,
    session_confidence,
    stop_reason,
)
from gaitpref.sessions.fit_cache import load_memo, memo_path, save_memo
from gaitpref.sessions.gaits import stopped_error
from gaitpref.sessions.records import (
    REASONS,
    Answered,
    ComparisonRecord,
    FeedbackEntry,
    InfeasibleGait,
    SessionQuery,
    ShownGait,
    SuggestionRecord,
    Trial,
    ValidationRound,
    check_printable,
    check_storable,
    check_withdraw_reason,
)
from gaitpref.sessions.replay import replay
from gaitpref.sessions.state import SessionState
from gaitpref.sessions.stored_config import (
    GaitLibraryLike,
    check_same_config,
    config_of,
    gait_cache_of,
    gait_ids_of,
    library_meta,
    software_version,
)
from gaitpref.sessions.validation import ValidationPlan, ValidationResult
from gaitpref.sessions.warm import (
    RELEARN_EVERY,
    SHARE_GATE,
    Replayed,
    check_prior_from,
    new_warm_start,
    prepare_state,
)
from gaitpref.space import Space
from gaitpref.storage import (
    ConflictError,
    EventRecord,
    NewEvent,
    SessionBusyError,
    SessionRecord,
    SessionSpec,
    Status,
    Storage,
    StorageConnectError,
    StorageFailureError,
    SubjectRecord,
    open_storage,
)
from gaitpref.storage.base import check_subject

T = TypeVar("T")
R = TypeVar("R")
#: why an undo proposed anew, before the error that stopped it proposing
_WITHDRAWN = (
    "the answer was undone, but its query proposed a gait flagged unsafe since, or in the "
    "region of avoidance now, and was withdrawn"
)


class Session:
    """One subject's session.  Make one with :meth:`create` or :meth:`open`."""

    def __init__(
        self,
        storage: Storage,
        record: SessionRecord,
        owns_storage: bool,
        replayed: Replayed | None = None,
    ) -> None:
        """``replayed``: the earlier sessions :meth:`create` replayed for the warm start a
        moment ago (keyed by the hashes it recorded), read by the first build instead of
        replaying them again; every later build (:meth:`_rebuild`) replays them."""
        self.storage = storage
        self._replayed_at_creation = replayed
        self._record = record
        self._owns = owns_storage
        self._lock = threading.RLock()
        self.config = config_of(record)
        self._gait_cache = gait_cache_of(storage, self.config)
        self._memo_path = memo_path(storage, record.id)
        self._memo = FitMemo() if self._memo_path is None else load_memo(self._memo_path)
        self._state = self._fresh_state()
        self._broken = False
        self._in_turn = False
        self._sure: tuple[int, Confidence] | None = None  # (last_seq, its confidence)

    # -- making and opening ------------------------------------------------------------------
    @classmethod
    def create(
        cls,
        db: str | Storage | None,
        config: str | Path | ExperimentConfig,
        subject: str,
        seed: int | None = None,
        library: GaitLibraryLike | None = None,
        prior_from: Sequence[int | str] = (),
    ) -> Session:
        """A new session of ``subject`` with ``config`` (a path, a shipped name or a config).

        ``db``: a URL, a storage, or None (``--db``/``$GAITPREF_DB``/``sqlite:///gaitpref.db``).
        ``seed`` defaults to the config's; ``library`` names the gait of each action.
        ``prior_from`` (session ids or subject codes) warm-starts the model with those
        sessions' answers, read and never changed (``sessions/warm.py``).
        Everything is checked before the database is touched.
        """
        cfg = config if isinstance(config, ExperimentConfig) else load_config(config)
        check_new(cfg)
        check_subject(subject)
        use_seed = cfg.seed if seed is None else seed
        if isinstance(use_seed, bool) or not isinstance(use_seed, int) or not 0 <= use_seed < 2**63:
            raise ValueError(f"seed must be an integer in 0 .. 2**63 - 1, got {use_seed!r}")
        meta = library_meta(cfg)
        if library is not None and cfg.generator is not None:
            raise ValueError(
                f"config {cfg.name!r} makes its gaits on demand ([gaits] generator = "
                f"{cfg.generator.name!r}); it takes no gait library"
            )
        if library is None and cfg.library is not None:
            library = cfg.library
        if library is not None and cfg.subspace == "line":
            raise ValueError("a gait library names the gaits of a grid; this config runs on lines")
        gait_ids = None if library is None else gait_ids_of(library, cfg.space)
        if gait_ids is not None:
            meta["gait_ids"] = gait_ids
        cfg.make_loop(seed=use_seed)  # the settings make a loop
        named = check_prior_from(prior_from)
        storage = open_storage(db)
        prior: list[log.PriorSession] = []
        rho: float | None = None
        replayed: Replayed = {}
        if named:
            prior, rho = new_warm_start(storage, cfg, named, use_seed, replayed)
            meta["prior_from"] = [p.model_dump() for p in prior]
            meta["prior_rho"] = rho
            meta["prior_terms"] = "all"
            meta["prior_relearn_every"] = RELEARN_EVERY
            meta["prior_share_gate"] = SHARE_GATE
        version = software_version()
        spec = SessionSpec(
            subject=subject,
            config_name=cfg.name,
            config_text=cfg.text,
            config_sha256=cfg.sha256,
            seed=use_seed,
            software_version=version,
            meta=meta,
        )
        created = log.new_event(
            log.Created(
                subject=subject,
                config_name=cfg.name,
                config_sha256=cfg.sha256,
                seed=use_seed,
                software_version=version,
                gait_library=gait_ids is not None,
                prior_from=prior,
                prior_rho=rho,
                prior_terms="all" if prior else None,
                prior_relearn_every=RELEARN_EVERY if prior else None,
                prior_share_gate=SHARE_GATE if prior else None,
            )
        )
        record = storage.create_session(spec, [created])
        session = cls(storage, record, owns_storage=not isinstance(db, Storage), replayed=replayed)
        session._catch_up()
        return session

    @classmethod
    def open(
        cls,
        db: str | Storage | None,
        session_id: int,
        config: str | Path | ExperimentConfig | None = None,
    ) -> Session:
        """Reopen a session and rebuild its state from the log (checking every step).

        With ``config``, it must be the session's config: a different one raises
        :class:`ReplayError` showing the difference.
        """
        storage = open_storage(db, create=False)
        owns = not isinstance(db, Storage)
        try:
            record = storage.get_session(session_id)
            if config is not None:
                check_same_config(record, config)
            session = cls(storage, record, owns_storage=owns)
            session._catch_up()
        except BaseException:
            if owns:
                storage.close()
            raise
        return session

    @staticmethod
    def list_sessions(db: str | Storage | None, subject: str | None = None) -> list[SessionRecord]:
        """The sessions in ``db`` (only ``subject``'s, if given), by id."""
        return _reading(db, lambda storage: storage.list_sessions(subject))

    @staticmethod
    def list_subjects(db: str | Storage | None) -> list[SubjectRecord]:
        """The subjects in ``db``, by code."""
        return _reading(db, lambda storage: storage.list_subjects())

    def close(self) -> None:
        """Release the database if this session opened it."""
        if self._owns:
            self.storage.close()

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- what it is ----------------------------------------------------------------------------
    @property
    def id(self) -> int:
        return self._record.id

    @property
    def subject(self) -> str:
        return self._record.subject

    @property
    def seed(self) -> int:
        return self._record.seed

    @property
    def record(self) -> SessionRecord:
        """The stored session row as last read."""
        return self._record

    @property
    def status(self) -> Status:
        return self._state.status

    @property
    def last_seq(self) -> int:
        return self._state.last_seq

    @property
    def ask_stopped(self) -> bool:
        """Whether the last event logged is an ask that stopped without proposing
        (``query_stopped``: its infeasible gaits are logged; ``sessions/gaits.py``)."""
        return self._state.stopped is not None

    @property
    def gait_ids(self) -> list[str] | None:
        return self._state.gait_ids

    # -- the loop ------------------------------------------------------------------------------
    def next_query(self, *, retry: bool = True) -> SessionQuery:
        """The pending query, or a new one, logged (committed) before it is returned.

        With gaits made on demand, an ask whose proposals reach ``[gaits] max_infeasible``
        gaits that cannot be made stops: it logs them (each avoided from then on, as always)
        and raises :class:`~gaitpref.errors.InfeasibleProposalsError`; asking again goes on
        from there (``sessions/gaits.py``).  An ask whose infeasible gaits leave no gait to
        propose before that logs them the same way and raises
        :class:`~gaitpref.errors.NoSafeGaitError`.

        ``retry=False``: when the last event logged is such a stopped ask (nothing logged
        since: no answer, undo, flag, note, resume...), raise its error again instead of asking
        again, making no gait: what a reader that may be repeated without end wants (a page
        reload, a device controller's poll), so that it does not make up to ``max_infeasible``
        gaits each time.  Only an explicit ask (the default) goes on proposing."""
        return self._locked(lambda: self._next_query(retry))

    def _next_query(self, retry: bool = True) -> SessionQuery:
        st = self._state
        st.check_active("queries")
        if st.open_round is not None:
            raise SessionStateError(
                f"blind validation round {st.open_round.plan.round} is open: "
                "record its ranking first, or withdraw it"
            )
        if st.pending is not None:
            return st.pending
        if not retry and st.stopped is not None:
            raise stopped_error(st.stopped, self.config)
        try:
            records = self._write(self._derived_query(st))
        except ConflictError:  # a writer that does not take turns: catch up and ask once more
            self._rebuild()
            if self._state.pending is not None:
                return self._state.pending
            st = self._state
            try:
                records = self._write(self._derived_query(st))
            except ConflictError:
                self._rebuild()
                raise SessionBusyError(
                    f"session {self.id} is busy: another writer kept appending while a query "
                    "was being issued; nothing was written, try again"
                ) from None
        st.commit(records)
        self._broken = False
        if st.pending is None:  # the ask stopped (query_stopped): its gaits are logged
            raise stopped_error(records[-1].payload, self.config)
        return st.pending

    def _derived_query(self, st: SessionState) -> list[NewEvent]:
        """The query's events; until they are written and booked the state counts as broken
        (rebuilt from the log by the next operation): deriving them may have moved the loop
        (gaits made on demand that it now avoids)."""
        self._broken = True
        return st.derive_query()

    @property
    def pending(self) -> SessionQuery | None:
        """The logged query awaiting its answer, if any."""
        return self._state.pending

    def answer(
        self,
        query_id: int,
        answers: Iterable[object] = (),
        suggestions: Iterable[object] = (),
        *,
        comparisons: Iterable[object] = (),
    ) -> Answered:
        """Answer the pending query with feedback records of any registered kind (as for
        ``CoSpar.tell``; raw ``(i, j, outcome)`` items are comparisons, and ``suggestions``
        takes ``(action, feature, move)``: the paper's convenience form; ``comparisons=`` as a
        keyword is the same as giving them in ``answers``).

        Refuses (and writes nothing) for a stale or unknown ``query_id``, actions off the grid or
        not in the query, a session that is finished or paused, and while a blind validation
        round is open (:class:`SessionStateError`: record its ranking first, or withdraw the
        round; the query stays pending).
        """
        if not is_count(query_id):
            raise QueryError(
                f"query_id must be the pending query's id (an integer: SessionQuery.id), "
                f"got {query_id!r}"
            )
        comps = [*as_records("answers", answers), *as_records("comparisons", comparisons)]
        suggs = as_records("suggestions", suggestions)
        return self._locked(lambda: self._answer(query_id, comps, suggs, retry=True))

    def _answer(
        self, query_id: int, comps: list[object], suggs: list[object], retry: bool
    ) -> Answered:
        st = self._state
        st.check_active("answers")
        query = st.pending
        if query is None or isinstance(query_id, bool) or query_id != query.id:
            raise st.pending_query_error(query_id)
        self._check_no_open_round(query)
        answer = st.tell(query, comps, suggs)
        try:  # told, not written: taken back if anything (Ctrl-C too) stops it being written
            events = st.answer_events(query, answer)
            records = self._write(events)
        except ConflictError:
            st.revert_tell()
            self._rebuild()
            if retry and self._state.pending is not None and self._state.pending.id == query_id:
                return self._answer(query_id, comps, suggs, retry=False)
            raise self._state.pending_query_error(query_id) from None
        except BaseException:
            st.revert_tell()
            raise
        try:
            st.commit(records, answer)
        except BaseException:  # written, booked in part (Ctrl-C): rebuilt from the log next
            self._broken = True
            raise
        loop = self._state.loop
        kept = len(answer.preferences) - len(loop.excluded.get(query.loop_id, ()))
        singles = len(answer.singles) - len(loop.excluded_singles.get(query.loop_id, ()))
        seqs = tuple(r.seq for r in records)
        clipped = self._clipped_after(seqs)
        warning, stopped = self._stop_check_after(query, seqs)
        return Answered(query.id, query.trials, seqs, kept, singles, warning, clipped, stopped)

    def _clipped_after(self, seqs: tuple[int, ...]) -> tuple[str, ...]:
        """What to tell the operator of the suggestions just logged at ``seqs`` that went past
        the edge of a feature's range (:func:`clipped_note`).  Only a report, worked out after
        the answer is stored: an error here leaves it out rather than report the stored answer
        as failed."""
        first = min(seqs, default=0)
        log = self._state.suggestions_log
        start = len(log)  # the answer's suggestions are the log's last rows: read only those
        while start and log[start - 1].seq >= first:
            start -= 1
        space = self._state.loop.space
        try:
            return tuple(
                note
                for r in log[start:]
                if (note := clipped_note(space, r.action, r.feature, r.move, r.trial))
            )
        except Exception:  # a report only: the answer is stored
            return ()

    def _stop_check_after(
        self, query: SessionQuery, seqs: tuple[int, ...]
    ) -> tuple[str | None, str | None]:
        """:meth:`_stop_if_sure` after the answer to ``query`` (logged at ``seqs``) is stored
        and booked: nothing it raises (a numerical error in the confidence, a failed write of
        the round, Ctrl-C while the confidence is sampled) may turn the stored answer into a
        reported failure, which a caller would answer again.  A failure is issued as a
        :class:`StopCheckWarning` and returned (why, first); the rule is checked again after
        the next answer (it runs after every answer until a round is opened).  Second: the
        rule's reason when it opened blind validation (None: it did not)."""
        try:
            stopped = self._stop_if_sure()
        except (Exception, KeyboardInterrupt) as exc:
            why = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
            warning = (
                f"the answer to query {query.id} is stored (events {', '.join(map(str, seqs))}), "
                f"but the [stop] rule could not be checked after it ({why}); it is checked again "
                "after the next answer"
            )
            warnings.warn(warning, StopCheckWarning, stacklevel=6)  # Session.answer's caller
            return warning, None
        return None, stopped

    def _check_no_open_round(self, query: SessionQuery) -> None:
        """Refuse an answer while a blind validation round is open (the query was pending when
        the round opened, or an undo made it pending again): the round compares the subject's
        ranking with the model as it stood when it opened, and no answer may move the model
        before the ranking is recorded.  Only new answers: a log written by an earlier release
        that answered inside a round replays as written (replay does not come here)."""
        current = self._state.open_round
        if current is None:
            return
        number = current.plan.round
        raise SessionStateError(
            f"blind validation round {number} is open: record its ranking before answering "
            f"query {query.id} (gaitpref session validate {self.id}, the console's validation "
            f"page, or Session.answer_validation({number}, ...)), or withdraw it (gaitpref "
            f"session validate {self.id} --withdraw --reason TEXT, or "
            f"Session.withdraw_validation({number}, reason)).  Query {query.id} stays pending; "
            "nothing was written"
        )

    def undo(self, *, query: int | None = None) -> SessionQuery | None:
        """Take back the last answer: its query is pending again, the model as it was before.

        ``query``: the id of the query whose answer the caller means to undo (the one it showed
        as the last, ``Trial.query``); refused (:class:`SessionStateError`, nothing written)
        when another writer answered or undid meanwhile, so that the last answer is now
        another's: without it, whatever answer is last when the undo runs is taken back.

        When that query proposes a gait flagged unsafe (or within the flag's radius) after it
        was asked, or a gait in the region of avoidance of the model as the undo leaves it (an
        exclusion made after the answer changes the model, and so the region), it is withdrawn,
        as a flag withdraws the pending query, and a new query is proposed and logged in its
        place; None when none may be proposed yet (the session is
        paused, or a blind validation round is open: the next :meth:`next_query` proposes).
        Should no gait be left to propose at all, the undo stands and
        :class:`~gaitpref.errors.NoSafeGaitError` says so; should the database not write the
        new query (:class:`~gaitpref.storage.StorageFailureError`, ``StorageConnectError``,
        ``SessionBusyError``), the undo stands too, and the error's message says so ("the undo
        is written; the query drawn in place of the one it withdrew was not: ...").
        """

        def run() -> SessionQuery | None:
            st = self._state
            st.check_open("undo")
            if query is not None:
                last = st.told[-1].query if st.told else None
                if last is None or last.id != query:
                    now = (
                        "no answer is in force"
                        if last is None
                        else f"the last answer is trial {', '.join(map(str, last.trials))}'s"
                    )
                    asked = [k.query.trials for k in st.told if k.query.id == query]
                    which = f" (trial {', '.join(map(str, asked[0]))})" if asked else ""
                    raise SessionStateError(
                        f"the answer to query {query}{which} is no longer the last one: another "
                        f"writer answered or undid meanwhile and {now} now; nothing was undone"
                    )
            self._append([st.undo_event()])
            return self._after_undo()

        return self._locked(run)

    def _after_undo(self) -> SessionQuery | None:
        """After an undo is written and booked: the query pending again, or the one proposed
        and logged in place of a withdrawn one (None while paused or a round is open)."""
        st = self._state
        if st.pending is not None:
            return st.pending
        if st.status == "paused" or st.open_round is not None:
            return None
        try:
            return self._next_query()
        except (StorageFailureError, StorageConnectError, SessionBusyError) as e:  # it stands
            # (busy: another writer kept appending; its message says nothing was written, of
            # the query alone)
            raise type(e)(
                f"the undo is written; the query drawn in place of the one it withdrew was not: {e}"
            ) from e
        except InfeasibleProposalsError as e:
            raise InfeasibleProposalsError(
                f"{_WITHDRAWN}; {e}",
                infeasible=e.infeasible,
                limit=e.limit,
            ) from e
        except NoSafeGaitError as e:
            raise NoSafeGaitError(f"{_WITHDRAWN}; {e}") from e

    def exclude(self, trial: int, reason: str, detail: str = "") -> Trial:
        """Exclude an answered trial (``reason`` in ``REASONS``): its comparisons and
        suggestions leave the model; the records stay, flagged.

        The model without them has its own region of avoidance (``[safety]``): a pending query
        that proposes a gait in it now is withdrawn, as an unsafe flag withdraws one, and the
        next :meth:`next_query` proposes anew (:attr:`pending` is None meanwhile); an open
        blind validation round that shows such a gait is withdrawn and drawn again at once
        among the gaits still allowed (none is open after it when fewer than three are)."""

        if isinstance(detail, str):
            check_printable(
                check_storable(detail, "the exclusion's detail"), "the exclusion's detail"
            )

        def run() -> Trial:
            st = self._state
            st.check_open("exclusions")
            before = st.open_round
            event = st.exclude_event(trial, reason, detail)
            try:  # Ctrl-C during the refit too: the state may have moved, the log has not
                st.apply_exclusion(event.payload, event.version)
                records = self._write([event])
                st.commit(records)
            except BaseException:
                self._broken = True  # the model already moved: rebuild from the log
                raise
            if before is not None and st.open_round is None:  # it showed a gait in the region
                with contextlib.suppress(SessionStateError):  # fewer than 3 gaits left to show
                    self._redraw(st, f"trial {trial} is excluded", before.opened_by)
            return next(t for t in self.trials() if t.number == trial)

        return self._locked(run)

    def flag_unsafe(self, trial: int, reason: str) -> bool:
        """The operator's hard stop: the trial's gait, and the gaits within
        ``[safety].unsafe_radius`` of it, are never proposed again.  A pending query that
        proposes one of them is withdrawn (the next query is proposed under the flag); so is an
        open blind validation round that shows one, and the round is drawn again at once among
        the gaits still allowed (none is open after it when fewer than three are).  Returns
        whether a round was withdrawn."""

        if isinstance(reason, str):
            what = "the unsafe flag's reason"
            check_printable(check_storable(reason, what), what)

        def run() -> bool:
            st = self._state
            st.check_open("unsafe flags")
            before = st.open_round
            self._append([st.unsafe_event(trial, reason)])
            st = self._state
            if before is None or st.open_round is not None:
                return False
            with contextlib.suppress(SessionStateError):  # fewer than 3 gaits left to show
                self._redraw(st, f"trial {trial} is flagged unsafe", before.opened_by)
            return True

        return self._locked(run)

    def _redraw(self, st: SessionState, done: str, opened_by: log.Opener | None) -> None:
        """Draw again the blind validation round that the change ``done`` (written) withdrew,
        opened by whoever opened it (``opened_by``); a storage failure of that write says the
        change stands."""
        try:
            self._append([st.validation_event(opened_by=opened_by)])
        except (StorageFailureError, StorageConnectError) as e:
            raise type(e)(
                f"{done} (written); the blind validation round it withdrew was not drawn again: {e}"
            ) from e

    def withdraw_unsafe(self, trial: int) -> None:
        """Take back the unsafe flag of ``trial`` (its undo)."""

        def run() -> None:
            st = self._state
            st.check_open("unsafe flags")
            self._append([st.withdraw_unsafe_event(trial)])

        self._locked(run)

    def check_change(
        self, change: Literal["undo", "unsafe", "withdraw", "exclude"], trial: int = 0
    ) -> None:
        """Refuse, writing nothing, as :meth:`undo`, :meth:`flag_unsafe`, :meth:`withdraw_unsafe`
        or :meth:`exclude` (of ``trial``) would now: the :class:`SessionStateError` of a
        finished session, of nothing to undo, of a trial not answered (or undone since), already
        flagged, not flagged or already excluded.  For a confirm step, so that a stale one is
        refused before the operator confirms it."""

        def run() -> None:
            st = self._state
            if change == "undo":
                st.check_open("undo")
                st.undo_event()
            elif change == "exclude":
                st.check_open("exclusions")
                st.exclude_event(trial, REASONS[0], "")
            elif change == "unsafe":
                st.check_open("unsafe flags")
                st.unsafe_event(trial, "(checked)")
            else:
                st.check_open("unsafe flags")
                st.withdraw_unsafe_event(trial)

        self._locked(run)

    def infeasible_gaits(self) -> list[InfeasibleGait]:
        """Proposals whose gait could not be made (gaits on demand): never shown as trials."""
        return list(self._state.infeasible)

    def unsafe_flags(self) -> dict[int, tuple[int, str]]:
        """Trials flagged unsafe: trial -> (action, reason)."""
        return dict(self._state.unsafe)

    def note(self, text: str) -> int:
        """Log a free-text note (anything the operator saw); returns its sequence number."""
        if not isinstance(text, str) or not text.strip() or len(text) > 10_000:
            raise ValueError("a note is a non-empty text of at most 10000 characters")
        check_storable(text, "the note")
        check_printable(text, "the note")

        def run() -> int:
            if self._state.status == "finished":
                raise SessionStateError("the session is finished: it takes no notes")
            return self._append([log.new_event(log.Note(text=text))])[-1].seq

        return self._locked(run)

    def pause(self) -> None:
        """Mark the session paused (the operator stepped away): no queries or answers until
        :meth:`resume`; undo, exclusions, notes and validation stay possible."""
        self._locked(lambda: self._set_status(log.PAUSED, "active", "pause"))

    def resume(self) -> None:
        """Resume a paused session."""
        self._locked(lambda: self._set_status(log.RESUMED, "paused", "resume"))

    def finish(self) -> None:
        """Close the session for good: it takes no more events."""

        def run() -> None:
            if self._state.status == "finished":
                raise SessionStateError("the session is already finished")
            self._append([log.new_event(log.Finished())], status="finished")

        self._locked(run)

    def _set_status(self, kind: str, need: str, verb: str) -> None:
        if self._state.status != need:
            raise SessionStateError(f"cannot {verb}: the session is {self._state.status}")
        self._append([NewEvent(kind, {})], status="paused" if kind == log.PAUSED else "active")

    # -- how sure are we -----------------------------------------------------------------------
    def confidence(self) -> Confidence:
        """How sure the model is of its recommendation (``sessions/confidence.py``), with the
        config's ``[stop]`` tolerance and sample count: ``.sentence(name)`` reads
        "88% that G95 is within 5% of the best".  Kept until the log moves on.
        :class:`~gaitpref.errors.NoSafeGaitError` when no gait may be proposed: there is no
        gait to recommend."""

        def run() -> Confidence:
            seq = self._state.last_seq
            if self._sure is None or self._sure[0] != seq:
                self._sure = (seq, session_confidence(self._state, self.config.stop))
            return self._sure[1]

        return self._locked(run)

    def recommended(self) -> int | None:
        """The gait to walk as the best so far: the posterior mean's highest among the gaits that
        may be proposed (never one flagged unsafe, near one, or in the region of avoidance) and,
        with gaits made on demand under ``[gaits] recommend = "made"`` (defaults 0.13 on), were
        made: the gait :meth:`confidence` recommends.  None while the posterior has no point
        (the line path before its first query) and when no gait may be recommended
        (:meth:`no_recommendation` says why).
        ``posterior().argmax`` is the unrestricted highest, which may be a gait not to walk."""
        return self._locked(lambda: recommended(self._state))

    def no_recommendation(self) -> str | None:
        """Why the session recommends no gait now (None: it recommends one, or will once the
        posterior has a point): every gait is in the region of avoidance or near a gait flagged
        unsafe, or, with gaits made on demand and ``[gaits] recommend = "made"`` (defaults 0.13
        on), no gait was made yet, or every gait made is avoided."""
        return self._locked(lambda: no_recommendation(self._state))

    def confidence_history(
        self, progress: Callable[[int, int], None] | None = None
    ) -> list[dict[str, Any]]:
        """The confidence after every answer, undo and exclusion so far, as it was stated then
        (``sessions/confidence.py``; the log is replayed afresh): the export's table.
        ``progress(done, total)``: the events replayed so far, and their number."""
        return self._locked(
            lambda: confidence_history(
                self._fresh_state(), self.events(), self.config.stop, progress
            )
        )

    def stop_reason(self) -> str | None:
        """Why the config's ``[stop]`` rule says to stop now (None: go on, or no rule); its
        confidence is :meth:`confidence`'s, kept until the log moves on (the console's page asks
        both: the samples were drawn twice)."""
        return self._locked(lambda: stop_reason(self._state, self.config.stop, self.confidence))

    def stop_blocked(self) -> str | None:
        """Why the ``[stop]`` rule, which says to stop now, cannot open blind validation: no
        round can be drawn (fewer than three gaits may be shown: unsafe flags, the region of
        avoidance, gaits made so far; or the posterior mean is flat).  None when there is no
        rule, it says go on, a round is open or answered (a withdrawn one does not count), one
        can be drawn, or the session is finished.  The terminal and the console show it after
        each answer: the rule cannot act, and the operator decides (finish the session, or go
        on: the rule opens the round after the first answer that lets one be drawn)."""

        def run() -> str | None:
            st = self._state
            if st.rounds_in_force or st.status == "finished":
                return None
            reason = stop_reason(st, self.config.stop, self.confidence)
            why = None if reason is None else st.validation_blocked()
            if why is None:
                return None
            return (
                f"the [stop] rule says stop ({reason}), but it cannot open blind validation: "
                f"{why}.  Finish the session, or go on with trials (the rule opens the round "
                "after an answer once one can be drawn)"
            )

        return self._locked(run)

    def _stop_if_sure(self) -> str | None:
        """After an answer: the first time the ``[stop]`` rule says stop, open blind validation
        (while no round is open or answered: the operator may go on afterwards, and the rule
        opens none again unless that round is withdrawn) and return
        the rule's reason (None: no round was opened).  When no round can be drawn, nothing is
        written and :meth:`stop_blocked` says why."""
        st = self._state
        if st.rounds_in_force or st.pending is not None or st.validation_blocked() is not None:
            return None
        reason = stop_reason(st, self.config.stop, self.confidence)
        if reason is None:
            return None
        try:
            self._append([st.validation_event(opened_by="rule")])
        except ConflictError:  # another writer moved on: it decides
            return None
        return reason

    # -- blind validation ----------------------------------------------------------------------
    def start_validation(self) -> ValidationPlan:
        """Fix and log a random order of the max/mean/min gaits (the open round, if any).

        A query pending when the round opens stays pending, and is answered once the round's
        ranking is recorded (:meth:`answer` refuses it until then)."""

        def run() -> ValidationPlan:
            st = self._state
            st.check_open("validation")
            if st.open_round is None:
                self._append([st.validation_event()])
            current = self._state.open_round
            assert current is not None
            return current.plan

        return self._locked(run)

    @property
    def validation_plan(self) -> ValidationPlan | None:
        """The open validation round's blind plan, if any."""
        current = self._state.open_round
        return None if current is None else current.plan

    def answer_validation(
        self,
        round_: int,
        ranking: Sequence[str] | str,
        *,
        shown: Sequence[str] | None = None,
    ) -> ValidationResult:
        """Record the subject's ranking (best first, e.g. ``"BAC"``), then unblind.

        ``shown``: the names of the gaits the subject walked, in label order, as the terminal or
        a console page showed them (:meth:`validation_gaits`).  A flag on a gait an open round
        shows draws the round again with the same number; given ``shown``, a ranking of the
        gaits walked before is refused (:class:`SessionStateError` naming both; nothing is
        written) rather than booked against the new ones.  Checked in the same turn as the
        write, so another writer's flag cannot come in between."""

        def run() -> ValidationResult:
            self._append([self._validation_answer(round_, ranking, shown)])
            result = self._state.rounds[-1].result
            assert result is not None
            return result

        return self._locked(run)

    def check_validation_answer(
        self, round_: int, ranking: Sequence[str] | str, *, shown: Sequence[str] | None = None
    ) -> None:
        """Refuse, writing nothing, as :meth:`answer_validation` would now (a round not open,
        drawn again since ``shown``, a ranking that is not one of its labels): for a confirm
        step, so that a stale ranking is refused before the operator confirms it."""

        def run() -> None:
            self._validation_answer(round_, ranking, shown)

        self._locked(run)

    def _validation_answer(
        self, round_: int, ranking: Sequence[str] | str, shown: Sequence[str] | None
    ) -> NewEvent:
        st = self._state
        st.check_open("validation")
        current = st.open_round
        if shown is not None and current is not None and current.plan.round == round_:
            now = [current.shown[g.label].gait for g in current.plan.gaits]
            if [str(g) for g in shown] != now:
                raise SessionStateError(
                    f"validation round {round_} was drawn again since its gaits were shown "
                    "(an unsafe flag withdrew a gait it showed): it now shows "
                    f"{', '.join(now)}, not {', '.join(map(str, shown))}; nothing was "
                    "written, run the round's gaits as shown now"
                )
        return st.validation_answer_event(round_, ranking)

    def withdraw_validation(
        self, round_: int, reason: str, *, undo: bool = False
    ) -> SessionQuery | None:
        """Withdraw the open, unanswered blind validation round ``round_``, saying why
        (``reason``: 1 to 2000 characters); its ``validation_started`` event stays as written,
        a ``validation_withdrawn`` event closes it unanswered.  Queries and answers go on, the
        ``[stop]`` rule may open a round again (it opens one while no round is open or answered),
        and the next round takes the next number.

        ``undo``: also take back the answer that opened the round, in the same transaction (an
        ``undo`` event after it): only for a round the ``[stop]`` rule opened (``opened_by`` is
        ``"rule"``) while that answer is still the last in force.  Returns the query pending
        then (as :meth:`undo` does: the undone one asked again, or one proposed in place of it),
        or the pending query, if any, without ``undo``.

        Refused (:class:`SessionStateError` naming the problem, nothing written): a finished
        session, a round that is answered, withdrawn, never started or not the open one, and
        ``undo`` of a round the rule did not open or whose answer is no longer the last one (or
        cannot be undone: excluded, flagged unsafe); a reason that is empty, over-long or holds
        a control character is a ValueError naming the rule it breaks."""
        reason = check_withdraw_reason(reason)

        def run() -> SessionQuery | None:
            self._append(self._withdraw_events(round_, reason, undo))
            return self._after_undo() if undo else self._state.pending

        return self._locked(run)

    def check_withdraw_validation(self, round_: int, *, undo: bool = False) -> None:
        """Refuse, writing nothing, as :meth:`withdraw_validation` would now: for a confirm
        step, so that a stale withdrawal is refused before the operator confirms it."""

        def run() -> None:
            self._withdraw_events(round_, "(checked)", undo)

        self._locked(run)

    def _withdraw_events(self, round_: int, reason: str, undo: bool) -> list[NewEvent]:
        st = self._state
        st.check_open("validation")
        events = [st.withdraw_validation_event(round_, reason)]
        if undo:
            current = st.open_round
            assert current is not None  # the withdrawal is of the open round
            if current.opened_by != "rule":
                who = (
                    "by the operator"
                    if current.opened_by == "operator"
                    else "by an unknown hand (logged before rounds recorded who opened them)"
                )
                raise SessionStateError(
                    f"validation round {round_} was opened {who}, not by the [stop] rule: no "
                    "answer opened it, so none is undone with it; withdraw it without undo"
                )
            last = st.told[-1].query.id if st.told else None
            if current.opened_after is None or last != current.opened_after:
                raise SessionStateError(
                    f"the answer to query {current.opened_after} that made the [stop] rule open "
                    f"validation round {round_} is no longer the last answer in force; nothing "
                    "was written (withdraw the round without undo, then undo as usual)"
                )
            events.append(st.undo_event())
        return events

    def validation_rounds(self) -> list[ValidationRound]:
        """Every blind validation round logged, open, answered or withdrawn, with who opened it
        (``opened_by``: ``"rule"``, ``"operator"``, or None for rounds logged before it was
        recorded)."""
        return self._state.validation_rounds()

    def validations(self) -> list[ValidationResult]:
        """The answered validation rounds, unblinded."""
        return [r.result for r in self._state.rounds if r.result is not None]

    def validation_gaits(self, round_: int | None = None) -> list[ShownGait]:
        """The gaits of validation round ``round_`` (None: the open one) in the order they are
        presented, as the round showed them: name, feature values and their text when the round
        started.  Show a round's gaits from here rather than by looking up their rows
        (``ShownGait``: on the line path a row may name another point later)."""
        rounds = self._state.rounds
        if round_ is None:
            current = self._state.open_round
            if current is None:
                raise SessionStateError("no blind validation round is open")
        elif 1 <= round_ <= len(rounds):
            current = rounds[round_ - 1]
        else:
            raise SessionStateError(
                f"validation round {round_!r} does not exist (rounds: 1..{len(rounds)})"
                if rounds
                else f"validation round {round_!r} does not exist (no round was started)"
            )
        return [current.shown[g.label] for g in current.plan.gaits]

    # -- reading -------------------------------------------------------------------------------
    def posterior(self) -> Posterior:
        """The current posterior (answers in force, exclusions applied)."""
        return self._locked(lambda: self._state.loop.posterior)

    def events(self) -> list[EventRecord]:
        """The whole log, from the database."""
        return self.storage.events(self.id)

    def trials(self, include_undone: bool = False) -> list[Trial]:
        """Executed trials in order (with the undone ones, flagged, if asked)."""
        return [t for t in self._state.trials_log if include_undone or not t.undone]

    def comparisons(self) -> list[ComparisonRecord]:
        """Every comparison ever answered, with ``undone``/``excluded`` flags."""
        return list(self._state.comparisons_log)

    def suggestions(self) -> list[SuggestionRecord]:
        """Every coactive suggestion ever given, with ``undone``/``excluded`` flags."""
        return list(self._state.suggestions_log)

    def feedback(self) -> list[FeedbackEntry]:
        """Answers of every other registered feedback kind, in order (undone ones flagged)."""
        return list(self._state.feedback_log)

    def history(self) -> list[tuple[SessionQuery, Posterior]]:
        """Each answer in force with the posterior right after it (as it was then)."""

        def run() -> list[tuple[SessionQuery, Posterior]]:
            told = self._state.told
            if not told:
                return []
            after = [k.answer.posterior_before for k in told[1:]] + [self._state.loop.posterior]
            return [(k.query, p) for k, p in zip(told, after, strict=True)]

        return self._locked(run)

    def notes(self) -> list[tuple[int, str]]:
        """``(sequence number, text)`` of every note."""
        return list(self._state.notes)

    @property
    def space(self) -> Space:
        """The actions' space: the config's grid, or on the line path the points so far
        (a :class:`~gaitpref.pointset.PointSet`: action ``a`` is its row ``a``)."""
        return self._state.loop.space

    def gait_id(self, action: int) -> str | None:
        """The gait library's id of ``action`` (None without a library)."""
        return self._state.gait_id(action)

    def gait_name(self, action: int) -> str:
        """How the terminal, the console and exports name a gait: its library id, or
        ``G<action>`` without a library."""
        return self._state.gait_name(action)

    def gait_made(self, action: int) -> bool | None:
        """Whether ``action``'s gait was made by this session (gaits on demand: a query proposed
        it and it could be made); False for a point whose gait is not made (a coactive
        suggestion's, on the line path, which the posterior's argmax may be, and under
        ``[gaits] recommend = "any"`` the recommendation: it is made, or found infeasible and
        skipped, when a query proposes it); None when gaits are not made on demand (a
        library's, or none)."""
        return self._state.gait_made(action)

    def describe(self, action: int) -> str:
        """Feature values with units, and the gait id when there is a library."""
        text = self.space.describe(action)
        gait = self.gait_id(action)
        return f"{text} [gait {gait}]" if gait is not None else text

    def refresh(self) -> None:
        """Bring this object up to date with events other writers appended (full replay)."""
        self._locked(self._rebuild)

    def read(self, fn: Callable[[Session], T], *, turn: bool = False) -> T:
        """``fn(self)``, the session brought up to date first and held still throughout: this
        object's own calls inside do not catch up midway, so what they return is of one event
        (as an export needs), however other writers go on meanwhile.  Other writers are not held
        up unless ``turn``: the writer turn is then held throughout, for a write that must
        follow what ``fn`` read (``session undo`` names the answer it undoes)."""
        if turn:
            return self._locked(lambda: fn(self))
        with self._lock:
            if self._in_turn:  # inside an operation already
                return fn(self)
            self.sync()
            self._in_turn = True  # calls inside run as parts of this one: no catch-up, no turn
            try:
                return fn(self)
            finally:
                self._in_turn = False

    def sync(self) -> bool:
        """Replay only the events other writers appended since this object last looked.

        Cheap when nothing changed (one read of the session's record); True if it caught up.
        """

        def run() -> bool:
            if self.storage.get_session(self.id).last_seq == self._state.last_seq:
                # a state left to be rebuilt (an ask that raised) was rebuilt by _locked, up to
                # what other writers appended: caught up too
                return self._state.last_seq != seen
            self._catch_up()
            return True

        with self._lock:
            seen = self._state.last_seq
            return self._locked(run, catch_up=False)

    # -- internals -----------------------------------------------------------------------------
    def _locked(self, fn: Callable[[], T], catch_up: bool = True) -> T:
        """``fn()`` with this object's lock and the session's writer turn held, up to date.

        The turn (``Storage.writer_turn``: fair, bounded, shared with other processes) is taken
        around the whole operation, and the events other writers appended are replayed first,
        so the append at its end does not lose a compare-and-set to another writer, and two
        writers alternate.  Past the bounded wait: :class:`~gaitpref.storage.SessionBusyError`.
        """
        with self._lock:
            if self._in_turn:  # an operation inside an operation: the turn is held already
                return fn()
            with self.storage.writer_turn(self.id), self._remembering():
                self._in_turn = True
                try:
                    if self._broken:
                        self._rebuild()
                    elif catch_up and self._moved_on():
                        self._catch_up()  # another writer moved the session on
                    return fn()
                finally:
                    self._in_turn = False

    def _moved_on(self) -> bool:
        return self.storage.get_session(self.id).last_seq != self._state.last_seq

    def _fresh_state(self) -> SessionState:
        replayed, self._replayed_at_creation = self._replayed_at_creation, None
        with self._remembering():
            return prepare_state(
                self.storage, self._record, self.config, self._gait_cache, memo=replayed
            )

    def _catch_up(self) -> None:
        """Replay the events this object has not seen."""
        records = self.storage.events(self.id, after=self._state.last_seq)
        try:
            with self._remembering():
                replay(self._state, records)
        except ReplayError as exc:
            raise ReplayError(
                f"session {self.id} cannot be rebuilt exactly from its log; stopped instead of "
                f"going on along a different path.\n{exc}\n{self._provenance()}"
            ) from None

    @contextlib.contextmanager
    def _remembering(self) -> Iterator[None]:
        """The session's large Laplace fits remembered (``model/fit_memo.py``: a replay checks
        each at its mode instead of making it again, the same numbers), and the memo saved
        beside a SQLite database when something was added (a cache: never an error)."""
        with remembering(self._memo):
            try:
                yield
            finally:
                if self._memo.dirty and self._memo_path is not None:
                    save_memo(self._memo, self._memo_path)

    def _rebuild(self) -> None:
        self._record = self.storage.get_session(self.id)
        self._state = self._fresh_state()
        self._broken = True
        self._catch_up()
        self._broken = False

    def _provenance(self) -> str:
        version = software_version()
        rec = self._record
        same = "the same" if rec.software_version == version else f"gaitpref {version}"
        return (
            f"The session was recorded with gaitpref {rec.software_version} and config "
            f"{rec.config_name!r} (sha256 {rec.config_sha256[:12]}); this is {same}."
        )

    def _write(self, events: list[NewEvent], status: Status | None = None) -> list[EventRecord]:
        for event in events:  # every payload validated on write, whoever built it
            log.check_new(event, self.id)
        return self.storage.append(self.id, self._state.last_seq, events, status)

    def _append(self, events: list[NewEvent], status: Status | None = None) -> list[EventRecord]:
        """Write and book events that change nothing before they are written."""
        try:
            records = self._write(events, status)
        except ConflictError:
            self._rebuild()
            raise
        try:
            self._state.commit(records)
        except BaseException:  # written, booked in part (Ctrl-C): rebuilt from the log next
            self._broken = True
            raise
        return records


__all__ = [
    "Answered",
    "ComparisonRecord",
    "QueryError",
    "ReplayError",
    "Session",
    "SessionQuery",
    "SessionStateError",
    "SuggestionRecord",
    "Trial",
]


def _reading(db: str | Storage | None, read: Callable[[Storage], list[R]]) -> list[R]:
    """``read(storage)`` on ``db``, closing the storage afterwards if it was opened here."""
    storage = open_storage(db, create=False)
    try:
        return list(read(storage))
    finally:
        if not isinstance(db, Storage):
            storage.close()
