"""The console's one door to the session API (:class:`gaitpref.Session`).

Routes never open sessions themselves: they call :class:`SessionService`, which

- holds one storage handle for the whole console (a connection pool, passed to ``Session``),
- keeps opened sessions (rebuilding one replays its whole log, so it is done once), and before
  each use checks that no other writer (the CLI, another console) moved the session on; if one
  did, the session is brought up to date first,
- runs compound operations (undo of an expected query, an answer with its note) under a
  per-session lock, so two browser tabs cannot interleave them.

Stale and already-answered queries are refused by the session API itself (``QueryError``), before
anything is written; :mod:`gaitpref.console.errors` turns that into HTTP 409.
"""

from __future__ import annotations

import io
import logging
import tempfile
import threading
import zipfile
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, TypeVar

from gaitpref.console.configs import choose_config, default_library_dir, discard
from gaitpref.console.errors import InputError
from gaitpref.errors import (
    GaitError,
    InfeasibleProposalsError,
    NoSafeGaitError,
    SessionStateError,
    StorageError,
)
from gaitpref.sessions.records import check_printable, check_storable
from gaitpref.sessions.session import Answered, Session, SessionQuery
from gaitpref.sessions.validation import ValidationPlan, ValidationResult
from gaitpref.storage import SessionRecord, Storage, SubjectRecord, open_storage, resolve_url

ExportFormat = Literal["csv", "json"]
T = TypeVar("T")
#: opened sessions kept in memory (reopening one replays its log)
KEEP = 32
#: per-session locks, striped by session id
LOCK_STRIPES = 64
#: the console's log: ``gaitpref console`` leaves it to Python's last-resort handler (stderr)
#: unless the application configures logging.  A warning is written there every time, unlike a
#: ``warnings.warn`` (Python's default filter shows one once per place per process)
logger = logging.getLogger("gaitpref.console")


@dataclass(frozen=True)
class Pending:
    """What the trial page can show now: a query, or why there is none."""

    query: SessionQuery | None
    reason: str  # "" when there is a query; else "paused", "finished", "validation", "no-safe",
    # "no-gait" (the gait generator failed to make a proposed gait), "infeasible" (the ask
    # stopped at [gaits] max_infeasible gaits that cannot be made: logged; an explicit ask, not
    # a reload, goes on); and, for an undo's query only (:class:`Undone`, :class:`WithdrawnRound`),
    # "unwritten" (the database failed to write it: the next ask proposes it)
    detail: str = ""  # why, in words (the NoSafeGaitError's or GaitError's message)


@dataclass(frozen=True)
class Undone:
    """An undo, read under the session's lock: the query whose answer was taken back (its
    ``trials``), the query pending now (the same one, or a new one where it was withdrawn for
    proposing a gait flagged unsafe since or in the region of avoidance now; None while none
    may be proposed yet), and the query
    that was pending before the undo."""

    undone_query: int
    trials: tuple[int, ...]
    pending: SessionQuery | None
    discarded_query: int | None
    #: why no query is pending in the withdrawn one's place, when one was to be proposed: the
    #: undo is written, but the gait generator failed ("no-gait"), no gait may be proposed
    #: ("no-safe"), as :class:`Pending` says, or the database failed to write the new query
    #: ("unwritten": the next ask proposes it); "" otherwise
    unproposed: str = ""
    detail: str = ""  # its error, in words

    @property
    def withdrawn(self) -> bool:
        return self.pending is None or self.pending.id != self.undone_query


@dataclass(frozen=True)
class WithdrawnRound:
    """A blind validation round withdrawn, read under the session's lock: its number, the
    query whose answer was undone with it (``trials``; None and empty without undo), the query
    pending now, and, when none could be proposed in place of a withdrawn one, why."""

    round: int
    undone_query: int | None
    trials: tuple[int, ...]
    pending: SessionQuery | None
    unproposed: str = ""
    detail: str = ""


class SessionService:
    """Sessions of one database, opened once and shared by all requests (thread-safe)."""

    def __init__(self, db: str | Storage | None, library_dir: str | Path | None = None) -> None:
        if isinstance(db, Storage):
            self.storage = db
            self.url = db.url
        else:
            url = resolve_url(db)
            self.storage = open_storage(url)
            # shown on the sessions page: the storage's, its password (if any) as ***, which
            # the page showed as given
            self.url = self.storage.url
        self.library_dir = (
            Path(library_dir)
            if library_dir is not None
            else default_library_dir(self.url if isinstance(db, Storage) else url)
        )
        self._open: dict[int, Session] = {}
        self._locks = tuple(threading.RLock() for _ in range(LOCK_STRIPES))
        self._guard = threading.Lock()

    def close(self) -> None:
        self.storage.close()

    # -- opening -------------------------------------------------------------------------------
    @contextmanager
    def locked(self, session_id: int) -> Iterator[Session]:
        """The session, up to date, with its console lock held."""
        with self._locks[session_id % LOCK_STRIPES]:  # bounded: any id a client sends
            yield self._current(session_id)

    def _keep(self, session: Session) -> None:
        """Remember an opened session (the ``KEEP`` most recently opened ones)."""
        with self._guard:
            self._open.pop(session.id, None)
            self._open[session.id] = session
            while len(self._open) > KEEP:
                self._open.pop(next(iter(self._open)))

    def _current(self, session_id: int) -> Session:
        session = self._open.get(session_id)
        if session is None:
            session = Session.open(self.storage, session_id)
            self._keep(session)
            return session
        session.sync()  # another writer may have moved it on
        return session

    def get(self, session_id: int) -> Session:
        """The session, up to date (for reading one thing; see :meth:`read` for several)."""
        with self.locked(session_id) as session:
            return session

    def read(self, session_id: int, fn: Callable[[Session], T]) -> T:
        """``fn(session)`` with the session's lock held: a consistent view of several things."""
        with self.locked(session_id) as session:
            return fn(session)

    # -- listing -------------------------------------------------------------------------------
    def list_sessions(self) -> list[SessionRecord]:
        return Session.list_sessions(self.storage)

    def list_subjects(self) -> list[SubjectRecord]:
        return Session.list_subjects(self.storage)

    # -- creating ------------------------------------------------------------------------------
    def create(
        self,
        config: str,
        subject: str,
        seed: int | None = None,
        *,
        config_name: str | None = None,
        library: tuple[bytes, str | None] | None = None,
        prior_from: Sequence[int | str] = (),
    ) -> Session:
        """A new session from a shipped config's name or a config's TOML text, optionally with
        an uploaded gait library (``(bytes, file name)``; see :mod:`gaitpref.console.configs`)
        and warm-started from earlier sessions (``prior_from``: ids or subject codes)."""
        chosen = choose_config(
            config, library_dir=self.library_dir, name=config_name, library=library
        )
        try:
            session = Session.create(
                self.storage,
                chosen.config,
                subject,
                seed=seed,
                library=chosen.library,
                prior_from=prior_from,
            )
        except BaseException:
            discard(chosen.written)  # a refused upload leaves no file behind
            raise
        finally:  # committed or removed: a concurrent upload of the library may go on
            chosen.release()
        self._keep(session)
        return session

    # -- the loop ------------------------------------------------------------------------------
    def answer(
        self,
        session_id: int,
        query_id: int,
        comparisons: Sequence[object],
        suggestions: Sequence[object],
        note: str | None = None,
        feedback: Sequence[object] = (),
    ) -> tuple[Answered, int | None]:
        """Answer ``query_id`` (``feedback``: records of other kinds, such as ratings); a
        non-empty ``note`` is logged right after the answer.  Returns the answer and the id of
        the query pending after it (read under the lock: None when none is yet)."""
        text = (note or "").strip()
        if len(text) > 2000:
            raise InputError("note", "a note has at most 2000 characters")
        try:  # before the answer is written: a note refused after it would leave half a write
            check_printable(check_storable(text, "the note"), "the note")
        except ValueError as exc:
            raise InputError("note", str(exc)) from None
        with self.locked(session_id) as session:
            answered = session.answer(query_id, [*comparisons, *feedback], suggestions)
            if answered.stop_warning is not None:  # the page and the API say "the log says why"
                logger.warning("session %d: %s", session_id, answered.stop_warning)
            if text:
                session.note(f"trial {', '.join(map(str, answered.trials))}: {text}")
            pending = session.pending
            return answered, None if pending is None else pending.id

    def undo(self, session_id: int, expected_query: int | None = None) -> Undone:
        """Take back the last answer; with ``expected_query``, only if that query is pending."""
        with self.locked(session_id) as session:
            if expected_query is not None:
                check_undo_query(session, expected_query)
            before = session.pending
            done = session.trials()
            undone = done[-1].query if done else None
            unproposed = Pending(None, "")
            try:
                pending = session.undo()
            except StorageError as exc:
                # written when the answer is no longer in force as the session booked it (it
                # books a write once it succeeded; the database may be failing: not read again)
                if undone is None or any(t.query == undone for t in session.trials()):
                    raise
                pending, unproposed = None, unwritten(session_id, exc)
            except (NoSafeGaitError, GaitError) as exc:
                # the undo is written, then its query, withdrawn, has no query to take its
                # place (as after an answer, the page and GET .../query say why) - or nothing
                # was written: the log says which
                session.sync()
                if undone is None or any(t.query == undone for t in session.trials()):
                    raise
                pending, unproposed = None, no_query(exc)
            assert undone is not None  # an undo with no answer in force raised above
            return Undone(
                undone_query=undone,
                trials=tuple(t.number for t in done if t.query == undone),
                pending=pending,
                discarded_query=None if before is None else before.id,
                unproposed=unproposed.reason,
                detail=unproposed.detail,
            )

    def acknowledge(self, session_id: int, query_id: int) -> bool:
        """A device controller loaded the gaits of ``query_id``: logged once as a note.

        Returns False when it was acknowledged before.  Refused (409) unless pending.
        """
        with self.locked(session_id) as session:
            pending = session.pending
            if pending is None or pending.id != query_id:
                raise session_query_error(session, query_id)
            text = ack_text(session, pending)
            if any(t == text for _, t in session.notes()):
                return False
            session.note(text)
            return True

    def flag_unsafe(self, session_id: int, trial: int, reason: str) -> bool:
        """The operator's hard stop on an answered trial (``reason`` required); whether it
        withdrew the pending query (it proposed a gait near the flag)."""
        text = reason.strip()
        if not text:
            raise InputError("reason", "say why the trial was unsafe (the reason is required)")
        if len(text) > 2000:
            raise InputError("reason", "a reason has at most 2000 characters")
        with self.locked(session_id) as session:
            return _withdrew(session, lambda: session.flag_unsafe(trial, text))

    def withdraw_unsafe(self, session_id: int, trial: int) -> None:
        with self.locked(session_id) as session:
            session.withdraw_unsafe(trial)

    def note(self, session_id: int, text: str) -> int:
        with self.locked(session_id) as session:
            return session.note(text)

    def exclude(self, session_id: int, trial: int, reason: str, detail: str = "") -> bool:
        """Exclude an answered trial; whether that withdrew the pending query (it proposed a
        gait in the region of avoidance of the model without the trial)."""
        with self.locked(session_id) as session:
            return _withdrew(session, lambda: session.exclude(trial, reason, detail))

    def set_status(self, session_id: int, status: str) -> None:
        with self.locked(session_id) as session:
            if status == session.status:
                return
            if status == "paused":
                session.pause()
            elif status == "finished":
                session.finish()
            elif status == "active":
                session.resume()
            else:
                raise InputError("status", "must be active, paused or finished")

    # -- validation ----------------------------------------------------------------------------
    def start_validation(self, session_id: int) -> ValidationPlan:
        with self.locked(session_id) as session:
            return session.start_validation()

    def rank(
        self,
        session_id: int,
        round_: int,
        ranking: Sequence[str],
        shown: Sequence[str] | None = None,
    ) -> ValidationResult:
        """Record the blind ranking (labels, best first) of the open round ``round_``; with
        ``shown`` (the gaits' names in label order, as a page showed them), only if the round
        still shows those gaits: a flag on a gait it showed draws it again with the same number,
        and a ranking of the gaits walked before must not be booked against the new ones."""
        with self.locked(session_id) as session:
            check_ranking_labels(session, round_, ranking)
            # shown: checked by the session in the turn of the write (Session.answer_validation)
            return session.answer_validation(round_, list(ranking), shown=shown)

    def withdraw_validation(
        self, session_id: int, round_: int, reason: str, undo: bool = False
    ) -> WithdrawnRound:
        """Withdraw the open, unanswered round ``round_`` (``reason`` required); with ``undo``,
        also take back the answer after which the ``[stop]`` rule opened it.  When the undone
        query, withdrawn (a gait flagged or in the region of avoidance since), has no query to
        take its place, the withdrawal and the undo stand, and ``unproposed`` says why."""
        text = reason.strip()
        if not text:
            raise InputError("reason", "say why the round is withdrawn (the reason is required)")
        if len(text) > 2000:
            raise InputError("reason", "a reason has at most 2000 characters")
        with self.locked(session_id) as session:
            rounds = session.validation_rounds()
            opened = next((r for r in rounds if r.round == round_ and r.open), None)
            after = None if opened is None or not undo else opened.opened_after
            trials = tuple(t.number for t in session.trials() if t.query == after)
            unproposed = Pending(None, "")
            try:
                pending = session.withdraw_validation(round_, text, undo=undo)
            except StorageError as exc:  # written when the round is closed as the session booked
                if not undo or session.validation_plan is not None:
                    raise
                pending, unproposed = None, unwritten(session_id, exc)
            except (NoSafeGaitError, GaitError) as exc:  # written, or not: the log says which
                session.sync()
                if session.validation_plan is not None:
                    raise
                pending, unproposed = None, no_query(exc)
            return WithdrawnRound(
                round=round_,
                undone_query=after,
                trials=trials if undo else (),
                pending=pending,
                unproposed=unproposed.reason,
                detail=unproposed.detail,
            )

    # -- export --------------------------------------------------------------------------------
    def export_zip(self, session_id: int, fmt: ExportFormat) -> bytes:
        """The session's export folder (``session export``) as a zip archive.

        Made from a copy of the session opened for it, not the shared one: an export of a long
        session takes its time (the confidence after every answer is worked out again), and the
        answers, pages and figures of that session must not wait for it.
        """
        from gaitpref.sessions.export import export_session

        with (
            Session.open(self.storage, session_id) as session,
            tempfile.TemporaryDirectory() as tmp,
        ):
            folder = Path(tmp) / f"session-{session_id}"
            export_session(session, folder, fmt)
            buf = io.BytesIO()
            with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
                for path in sorted(p for p in folder.rglob("*") if p.is_file()):
                    zf.write(path, f"{folder.name}/{path.relative_to(folder).as_posix()}")
            return buf.getvalue()


def _withdrew(session: Session, act: Callable[[], object]) -> bool:
    """Do ``act`` (a flag, an exclusion); whether it withdrew the pending query."""
    pending = session.pending
    act()
    return pending is not None and session.pending is None


def pending_of(session: Session) -> Pending:
    """The query to run now (issued and logged if new), or why there is none.  A page load:
    after an ask that stopped, with nothing logged since, it says so again rather than asking
    again (``Session.next_query(retry=False)``), so reloads make no gaits; :func:`ask_again`
    is the explicit retry."""
    if session.status != "active":
        return Pending(None, session.status)
    if session.validation_plan is not None:
        return Pending(None, "validation")
    try:
        return Pending(session.next_query(retry=False), "")
    except (NoSafeGaitError, GaitError) as exc:  # say why, propose nothing
        return no_query(exc)


def ask_again(session: Session) -> None:
    """The operator's explicit ask after one that stopped (the trial page's "Ask again"): it
    goes on proposing from the gaits avoided so far.  A stop is logged (the page then shows
    it); an ask that wrote nothing raises its error (no gait may be proposed at all, or the
    generator failed), which the page reports as any refused post."""
    before = session.last_seq
    try:
        session.next_query()
    except NoSafeGaitError:
        # shown by the page only if this ask logged its stop: something was written and the
        # last event is the stop (a writer's events caught up on may have moved last_seq)
        if session.last_seq == before or not session.ask_stopped:
            raise


def no_query(exc: NoSafeGaitError | GaitError) -> Pending:
    """No query, and why: the ask stopped after too many infeasible gaits (``infeasible``: they
    were logged and are avoided), no gait may be proposed (``no-safe``: nothing written), or the
    gait generator failed to make a proposed gait (``no-gait``: an error, not an infeasible
    gait)."""
    if isinstance(exc, InfeasibleProposalsError):
        return Pending(None, "infeasible", str(exc))
    if isinstance(exc, NoSafeGaitError):
        return Pending(None, "no-safe", str(exc))
    return Pending(None, "no-gait", str(exc) or type(exc).__name__)


def unwritten(session_id: int, exc: StorageError) -> Pending:
    """No query, as the database failed to write the one drawn in place of an undone answer's,
    withdrawn (``unwritten``): the undo (and a withdrawal with it) is written, and the next ask
    (the trial page, GET .../query) proposes the query again.  Logged as a warning: the request
    that wrote the undo succeeds."""
    logger.warning(
        "session %d: the undo is written; the query in place of its withdrawn one was not, and "
        "is proposed at the next ask: %s",
        session_id,
        exc,
    )
    return Pending(None, "unwritten", str(exc) or type(exc).__name__)


def ack_text(session: Session, query: SessionQuery) -> str:
    gaits = ", ".join(session.gait_name(a) for a in query.actions)
    return f"device acknowledged query {query.id} (gaits {gaits})"


def check_ranking_labels(session: Session, round_: int, ranking: Sequence[str]) -> None:
    """Refuse (422 naming ``ranking``) a ranking of the open round ``round_`` that does not name
    each of its labels once."""
    plan = session.validation_plan
    if plan is not None and plan.round == round_:
        labels = [str(r).upper() for r in ranking]
        if sorted(labels) != sorted(plan.labels):
            raise InputError(
                "ranking",
                f"name each of {', '.join(plan.labels)} exactly once, best first; "
                f"got {', '.join(labels) or 'nothing'}",
            )


def check_undo_query(session: Session, expected_query: int) -> None:
    """Refuse (409) an undo asked while ``expected_query`` was pending if another is now."""
    pending = session.pending
    if pending is None or pending.id != expected_query:
        now = "no query is" if pending is None else f"query {pending.id} is"
        raise SessionStateError(
            f"the undo was asked while query {expected_query} was pending, but now "
            f"{now} pending (another tab answered or undid first); nothing was undone"
        )


def session_query_error(session: Session, query_id: int) -> Exception:
    """The session API's own refusal for a query that is not pending."""
    from gaitpref.loop.cospar import QueryError

    pending = session.pending
    now = "none is pending" if pending is None else f"the pending query is {pending.id}"
    answered = any(t.query == query_id for t in session.trials())
    what = "was already answered" if answered else "is not the pending query"
    return QueryError(f"query {query_id} {what} ({now})")
