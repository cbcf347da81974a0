"""Warm starts: a new session's model includes earlier sessions' answers (``loop/warm.py``).

``Session.create(..., prior_from=[session ids or subject codes])`` resolves the earlier sessions
(:func:`resolve_prior`: a code means every session of that subject), refuses any whose grid is
not the new config's, and records each one's log up to its last event, hashed
(:class:`~gaitpref.sessions.events.PriorSession`), with the shared fraction ``rho`` learned from
them, in the ``created`` event and the session's meta.  Every time the session is built
(:func:`prepare_state`) the earlier sessions are replayed from their logs up to the recorded
event (each with its own warm start, if it had one), their hashes compared, and their
preferences in force (after exclusions) enter the new subject's model, one subject per code.
Earlier sessions are only read: nothing is written to them, and they may go on afterwards (the
hash covers the log up to the recorded event only).  A changed log is a
:class:`~gaitpref.errors.ReplayError` naming the session.

A warm start made now carries every registered kind's terms in force (preferences, ties when the
new config models them, ratings given on the new config's rating scale; ``loop/warm.py``,
:class:`~gaitpref.loop.warm.Earlier`) and
records ``prior_terms = "all"``; one recorded without it carried preferences only and is rebuilt
so, so that it replays as it was written.  Likewise a warm start made now re-learns the new
subject's share every ``prior_relearn_every`` answers (``loop/warm.py``, a ``share_refit`` event
each time); one recorded without it holds ``rho`` fixed at creation, as it was run.
"""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import pydantic

from gaitpref.config import ExperimentConfig
from gaitpref.errors import PriorFromError, ReplayError
from gaitpref.loop.warm import (
    RELEARN_EVERY,
    SHARE_GATE,
    Earlier,
    WarmStart,
    warm_data,
    warm_start,
    warm_terms,
)
from gaitpref.sessions.events import PriorSession
from gaitpref.sessions.replay import replay
from gaitpref.sessions.state import SessionState
from gaitpref.sessions.stored_config import config_of, gait_cache_of
from gaitpref.space import Space
from gaitpref.storage import (
    EventRecord,
    SessionNotFoundError,
    SessionRecord,
    Storage,
    StorageError,
)
from gaitpref.storage.base import check_subject

if TYPE_CHECKING:
    from gaitpref.gaits.gait_cache import GaitCache


#: The most distinct (gait, earlier subject) pairs a new warm start's earlier sessions may visit:
#: each answer of the new session refits the population model over them (and the share's
#: hypotheses), dense in their number; 1,501 took 6.1 s an answer (and 1.0 s for the confidence
#: after it, then drawn with BLAS's default threads) on two cores
#: (``benchmarks/results/warm.md``).  Checked when a session is created; sessions recorded with
#: more replay as they were.
MAX_PRIOR_NODES = 2000
#: The most earlier sessions a new warm start may read (a subject code counts each of the
#: subject's sessions): every opening of the new session replays each of them from its log.
MAX_PRIOR_SESSIONS = 256


def log_sha256(events: Sequence[EventRecord]) -> str:
    """Hash of a log: each event's sequence number, kind, payload version and payload."""
    rows = [[e.seq, e.kind, e.version, e.payload] for e in events]
    text = json.dumps(rows, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


class TypedId(int):
    """A session id typed as bare digits (``--prior-from 7``, the console's field): it keeps the
    text, so that :func:`resolve_prior` can refuse digits that are also a subject's code
    (``01``: session 1 or subject ``01``?) instead of warm-starting from the wrong data."""

    text: str

    def __new__(cls, text: str) -> TypedId:
        made = super().__new__(cls, int(text))
        made.text = text
        return made


def read_prior_from(items: Iterable[str]) -> list[int | str]:
    """Typed ``prior_from`` items (the CLI's repeated ``--prior-from``, the console's field):
    each item may hold several, separated by commas or spaces; ``session:7`` is a session id and
    ``subject:01`` a subject code, whatever they look like; bare digits (0-9) are a session id
    (refused by :func:`resolve_prior` where they are also a subject's code), anything else a
    subject code.  ValueError names an item that is none of these."""
    out: list[int | str] = []
    for item in items:
        for token in re.split(r"[,\s]+", item.strip()):
            if not token:
                continue
            kind, colon, rest = token.partition(":")
            if colon and kind.lower() == "session":
                if not (rest.isascii() and rest.isdigit()):
                    raise ValueError(f"prior_from: {_shown(token)}: a session id is digits (0-9)")
                out.append(int(rest))
                continue
            if colon and kind.lower() == "subject":
                token = rest
            elif token.isascii() and token.isdigit():  # not another script's digits
                out.append(TypedId(token))
                continue
            try:
                out.append(check_subject(token))
            except StorageError:
                raise ValueError(
                    f"prior_from: {_shown(token)} is neither a session id nor a subject code "
                    "(letters, digits, '-', '_' and '.')"
                ) from None
    return out


def _shown(text: str) -> str:
    """``text`` quoted for a message, cut to 80 characters (a field may hold megabytes)."""
    return repr(text) if len(text) <= 80 else repr(text[:80]) + "..."


def check_prior_from(prior_from: object) -> list[int | str]:
    """``prior_from`` as a list of session ids and subject codes; PriorFromError for anything
    else, such as one code given as a string (it was read a character at a time: ``"S01"``
    named subjects ``S``, ``0`` and ``1``), a number or a mapping.  None: no warm start."""
    if prior_from is None:
        return []
    if isinstance(prior_from, str | bytes | Mapping) or not isinstance(prior_from, Iterable):
        raise PriorFromError(
            f"prior_from: expected a list of session ids or subject codes, got {prior_from!r}"
            + (f" (for one, [{prior_from!r}])" if isinstance(prior_from, str | int) else "")
        )
    items: list[int | str] = []
    for item in prior_from:
        if isinstance(item, np.integer):  # a NumPy id is an id
            item = int(item)
        if isinstance(item, bool) or not isinstance(item, int | str):
            raise PriorFromError(f"prior_from: expected session ids or subject codes, got {item!r}")
        items.append(item)
    return items


def grid_difference(earlier: Space, new: Space) -> str:
    """How the earlier session's grid differs from the new one's ("": the same grid: the same
    features, values and units; how an operator words a coactive move may differ)."""
    if [f.name for f in earlier] != [f.name for f in new]:
        return f"features {[f.name for f in earlier]}, not {[f.name for f in new]}"
    for a, b in zip(earlier, new, strict=True):
        if a.continuous != b.continuous:
            return f"{a.name} is {'' if a.continuous else 'not '}continuous"
        if a.values != b.values:
            return (
                f"{a.name} takes {len(a.values)} values {a.values[0]:g}..{a.values[-1]:g}, not "
                f"{len(b.values)} values {b.values[0]:g}..{b.values[-1]:g}"
            )
        if a.unit != b.unit:
            return f"{a.name} is in {a.unit!r}, not {b.unit!r}"
    return ""


def resolve_prior(
    storage: Storage, config: ExperimentConfig, prior_from: Sequence[int | str]
) -> list[SessionRecord]:
    """The earlier sessions named by ids or subject codes, by id, each once;
    :class:`~gaitpref.errors.PriorFromError` (a ValueError) names an unknown one or one whose
    grid differs from ``config``'s.  An item named again is not looked up again (a form's
    field may repeat one a hundred thousand times)."""
    found: dict[int, SessionRecord] = {}
    for item in dict.fromkeys(prior_from):
        if isinstance(item, bool) or not isinstance(item, int | str):
            raise PriorFromError(f"prior_from: expected session ids or subject codes, got {item!r}")
        if isinstance(item, TypedId) and storage.list_sessions(item.text):
            raise PriorFromError(
                f"prior_from: {item.text!r} is both session id {int(item)} and a subject's code; "
                f"write session:{int(item)} or subject:{item.text}"
            )
        if isinstance(item, int):
            try:
                records = [storage.get_session(item)]
            except SessionNotFoundError:
                raise PriorFromError(f"prior_from: there is no session {item}") from None
        else:
            records = storage.list_sessions(item)
            if not records:
                hint = _no_sessions_hint(storage, item)
                raise PriorFromError(f"prior_from: subject {item!r} has no sessions{hint}")
        for record in records:
            differs = grid_difference(config_of(record).space, config.space)
            if differs:
                raise PriorFromError(
                    f"prior_from: session {record.id} (subject {record.subject}) was run on "
                    f"another grid (config {record.config_name!r}: {differs}); a warm start "
                    "needs the same" + _by_id_instead(item, records, config)
                )
            found[record.id] = record
            if len(found) > MAX_PRIOR_SESSIONS:
                raise PriorFromError(
                    f"prior_from: names more than {MAX_PRIOR_SESSIONS} sessions (a subject code "
                    "counts each of the subject's sessions); a warm start reads at most "
                    f"{MAX_PRIOR_SESSIONS}, each replayed whenever the new session is opened"
                )
    return [found[k] for k in sorted(found)]


def _no_sessions_hint(storage: Storage, code: str) -> str:
    """A hint for a subject code that has no sessions: the session it names when it is digits
    given as text (``"7"`` from a JSON body or a Python list), or the subjects whose code is it
    in other letter case (codes are matched exactly: ``s01`` is not ``S01``); "" for none."""
    if code.isascii() and code.isdigit():  # digits given as text: a session id meant?
        try:
            storage.get_session(int(code))
        except SessionNotFoundError:
            return ""
        return f" (a text is a subject code: for session {int(code)}, give the number)"
    like = [s.code for s in storage.list_subjects() if s.code.casefold() == code.casefold()]
    shown = ", ".join(map(repr, like))
    return "" if not like else f" (codes match letter case: did you mean {shown}?)"


def _by_id_instead(
    item: int | str, records: Sequence[SessionRecord], config: ExperimentConfig
) -> str:
    """For a subject code whose sessions were run on several grids: which of them a warm start
    could read, named by id (a subject seen in two protocols could not be named at all)."""
    if isinstance(item, int):
        return ""
    same = [r.id for r in records if not grid_difference(config_of(r).space, config.space)][
        :MAX_PRIOR_SESSIONS
    ]
    if not same:
        return f" (none of subject {item}'s sessions was run on this grid)"
    ids = ", ".join(map(str, same))
    return (
        f" (subject {item} names every session of the subject; those run on this grid can be "
        f"named by session id instead: {ids})"
    )


def recorded_prior(record: SessionRecord) -> list[PriorSession]:
    """The earlier sessions ``record``'s warm start read, as its row records them (none: no
    warm start); :class:`~gaitpref.errors.ReplayError` naming the session when the row holds
    something else (it was edited outside gaitpref)."""
    raw = record.meta.get("prior_from")
    if not raw:
        return []
    try:
        if not isinstance(raw, list):
            raise TypeError(type(raw).__name__)
        return [PriorSession.model_validate(p) for p in raw]
    except (TypeError, pydantic.ValidationError):
        shown = repr(raw)
        shown = shown if len(shown) <= 200 else shown[:200] + "..."
        raise ReplayError(
            f"session {record.id}: its warm start's prior_from in the session's row is not "
            f"what gaitpref writes (a list of earlier sessions with their log hashes): {shown}; "
            "the database was altered"
        ) from None


def new_warm_start(
    storage: Storage,
    config: ExperimentConfig,
    prior_from: Sequence[int | str],
    seed: int,
    memo: Replayed | None = None,
) -> tuple[list[PriorSession], float]:
    """What a new session's warm start from ``prior_from`` records: the earlier sessions
    (:func:`resolve_prior`, :func:`describe_prior`) and ``rho`` (:func:`make_warm_start`).
    ``memo`` receives the earlier sessions replayed (:data:`Replayed`), so that building the
    new session's state right after reads them from it instead of replaying them again.

    :class:`~gaitpref.errors.PriorFromError` also when an earlier session, or one its own warm
    start read, cannot be rebuilt from the database (its log or row altered, its config no longer
    parses, its gait library gone): the message names it and says why, as opening it would
    (:class:`~gaitpref.errors.ReplayError`); the new session is not created.
    A config on the line path (continuous features, a grid past the limit, ``subspace =
    "line"``) is refused first, naming ``prior_from``: the loop takes no warm start there (it
    was the loop's :class:`~gaitpref.errors.QueryError`, which the CLI called "answer refused"
    and the console a stale query, 409).
    """
    if config.subspace == "line":
        raise PriorFromError(
            f"prior_from: warm starts from earlier subjects need the full grid; config "
            f"{config.name!r} runs on the line path (continuous features, or a grid past the "
            'limit, or subspace = "line"), which takes none: start the session without '
            "prior_from (nothing was created)"
        )
    try:
        prior = describe_prior(storage, resolve_prior(storage, config, prior_from))
        return prior, make_warm_start(storage, config, prior, seed, memo).rho
    except ReplayError as exc:
        raise PriorFromError(
            "prior_from: an earlier session cannot be rebuilt from the database, so no warm "
            f"start can be made from it (nothing was created): {exc}"
        ) from None


def describe_prior(storage: Storage, records: Sequence[SessionRecord]) -> list[PriorSession]:
    """What the ``created`` event records of each earlier session: its log hashed as it is now."""
    out = []
    for record in records:
        events = storage.events(record.id)
        last = events[-1].seq if events else 0
        out.append(
            PriorSession(
                session=record.id, subject=record.subject, last_seq=last, sha256=log_sha256(events)
            )
        )
    return out


def _categories(config: ExperimentConfig) -> tuple[str, ...] | None:
    return None if config.ordinal is None else tuple(config.ordinal.categories)


#: What a build has replayed of the earlier sessions it reads, by what was recorded of each (id,
#: subject, last event, hash): the terms in force then and the rating scale.  A session whose
#: earlier sessions were themselves warm-started (a subject's sessions, each warm-started from
#: the subject) reads each once, not once per path to it (2**k replays for a chain of k).
Replayed = dict[PriorSession, tuple[Earlier, tuple[str, ...] | None]]


def _which(prior: PriorSession) -> str:
    return (
        f"session {prior.session} (subject {prior.subject}), which this session's warm start read,"
    )


def _record_of(storage: Storage, prior: PriorSession) -> SessionRecord:
    try:
        return storage.get_session(prior.session)
    except SessionNotFoundError:
        raise ReplayError(
            f"{_which(prior)} is not in this database; the warm start cannot be rebuilt"
        ) from None


def _replayed(storage: Storage, prior: PriorSession, memo: Replayed) -> None:
    """Replay ``prior`` (its log checked against the recorded hash) into ``memo``."""
    if prior in memo:
        return
    which = _which(prior)
    record = _record_of(storage, prior)
    events = [e for e in storage.events(prior.session) if e.seq <= prior.last_seq]
    if log_sha256(events) != prior.sha256:
        raise ReplayError(
            f"{which} has changed since (its log up to event {prior.last_seq} no longer matches "
            "the hash recorded at creation); the warm start cannot be rebuilt"
        )
    try:
        state = prepare_state(storage, record, memo=memo)
        replay(state, events)
    except ReplayError as exc:  # its own log, or its row, no longer replays: say whose it is
        raise ReplayError(f"{which} does not replay from its log as stored: {exc}") from None
    loop = state.loop
    memo[prior] = (Earlier(loop.preferences, loop.ties, loop.singles), _categories(state.config))


def _read_in_order(storage: Storage, prior: Sequence[PriorSession], memo: Replayed) -> None:
    """Replay ``prior`` and every earlier session their own warm starts read, each once, oldest
    first: each one's own earlier sessions are then already in ``memo`` (they were created
    before it), so the replays never nest (a subject's long chain of warm-started sessions
    would otherwise recurse once per session)."""
    seen: set[PriorSession] = set()
    stack = [p for p in prior if p not in memo]
    while stack:
        p = stack.pop()
        if p in seen or p in memo:
            continue
        seen.add(p)
        stack.extend(recorded_prior(_record_of(storage, p)))
    for p in sorted(seen, key=lambda p: (p.session, p.last_seq)):
        _replayed(storage, p, memo)


def _earlier_terms(
    storage: Storage,
    prior: PriorSession,
    scale: tuple[str, ...] | None = None,
    memo: Replayed | None = None,
) -> Earlier:
    """The terms in force in an earlier session after its recorded event, replayed; its
    single-action terms (ratings) only when its rating scale is ``scale``, the new one's."""
    memo = {} if memo is None else memo
    _replayed(storage, prior, memo)
    terms, categories = memo[prior]
    if scale is not None and categories == scale:
        return terms
    return Earlier(terms.preferences, terms.ties, ())


def earlier_subjects(
    storage: Storage,
    prior: Sequence[PriorSession],
    config: ExperimentConfig | None = None,
    memo: Replayed | None = None,
) -> list[Earlier]:
    """The earlier sessions' terms, one :class:`Earlier` per subject code (in order of first
    id); ratings only from sessions rated on ``config``'s scale (None: no ratings).  ``memo``:
    what this build has already replayed (:data:`Replayed`)."""
    scale = None if config is None else _categories(config)
    memo = {} if memo is None else memo
    _read_in_order(storage, prior, memo)
    by_subject: dict[str, list[Earlier]] = {}
    for p in prior:
        by_subject.setdefault(p.subject, []).append(_earlier_terms(storage, p, scale, memo))
    return [
        Earlier(
            [x for e in group for x in e.preferences],
            [x for e in group for x in e.ties],
            [x for e in group for x in e.singles],
        )
        for group in by_subject.values()
    ]


def make_warm_start(
    storage: Storage,
    config: ExperimentConfig,
    prior: Sequence[PriorSession],
    seed: int,
    memo: Replayed | None = None,
) -> WarmStart:
    """The warm start of a new session, every term carried, ``rho`` learned from the earlier
    subjects; :class:`~gaitpref.errors.PriorFromError` when their terms visit more than
    :data:`MAX_PRIOR_NODES` (gait, subject) pairs.  ``memo``: :data:`Replayed`."""
    loop = config.make_loop(seed=seed)
    groups = earlier_subjects(storage, prior, config, memo)
    model_ties = loop.learning.ties == "model"
    data, singles = warm_terms(loop.context(), model_ties, groups)
    parts = [data.first, data.second] + ([] if singles is None else [singles.actions])
    nodes = int(np.unique(np.concatenate(parts)).size)
    if nodes > MAX_PRIOR_NODES:
        raise PriorFromError(
            f"prior_from: the earlier sessions' answers visit {nodes} (gait, subject) pairs; a "
            f"warm start takes at most {MAX_PRIOR_NODES} (every answer of the new session "
            "refits them all, at a cost growing with the cube of their number): name fewer "
            "sessions or subjects"
        )
    return warm_start(
        config.space, loop.hyper, loop.prior, groups,
        context=loop.context(), model_ties=model_ties,
    )  # fmt: skip


def _relearning(record: SessionRecord) -> dict[str, Any]:
    """How the warm start re-learns the new subject's share, as recorded: absent (recorded
    before), ``rho`` held; else the subject starts alone, re-learned every so many answers."""
    every = record.meta.get("prior_relearn_every")
    if every is None:
        return {}
    gate = record.meta.get("prior_share_gate")
    if isinstance(every, bool) or not isinstance(every, int) or not isinstance(gate, float):
        raise ReplayError(
            f"session {record.id}: its warm start's prior_relearn_every ({every!r}) or "
            f"prior_share_gate ({gate!r}) is not what was written"
        )
    return {"share": 0.0, "relearn_every": every, "gate": gate}


def prepare_state(
    storage: Storage,
    record: SessionRecord,
    config: ExperimentConfig | None = None,
    gait_cache: GaitCache | None = None,
    *,
    memo: Replayed | None = None,
) -> SessionState:
    """A fresh state for ``record`` (its parsed ``config``, if at hand), with its warm start
    when it has one (not yet replayed); gaits made on demand come from ``gait_cache`` (default:
    the database's, ``stored_config.gait_cache_of``); ``memo``: the earlier sessions this build
    has replayed already (:data:`Replayed`)."""
    config = config_of(record) if config is None else config
    cache = gait_cache if gait_cache is not None else gait_cache_of(storage, config)
    state = SessionState(
        config, record.seed, record.meta.get("gait_ids"), gait_cache=cache, row=record
    )
    prior = recorded_prior(record)
    if prior:
        later = [p.session for p in prior if p.session >= record.id]
        if later:  # only a row edited outside gaitpref: a warm start reads sessions made before
            raise ReplayError(
                f"session {record.id}: its warm start names session {later[0]}, not made before "
                "it; the database was altered"
            )
        groups = earlier_subjects(storage, prior, config, memo)
        rho = record.meta.get("prior_rho")
        if not isinstance(rho, float):
            raise ReplayError(f"session {record.id}: its warm start's rho is missing")
        relearn = _relearning(record)
        if record.meta.get("prior_terms") == "all":
            loop = state.loop
            terms = warm_terms(loop.context(), loop.learning.ties == "model", groups)
            warm = WarmStart(terms[0], rho, len(groups), terms[1], **relearn)
        else:  # recorded before warm starts carried every term: preferences only
            prefs = [g.preferences for g in groups]
            warm = WarmStart(warm_data(config.space, prefs), rho, len(groups), **relearn)
        state.loop.warm_start(warm)
    return state


__all__ = [
    "MAX_PRIOR_NODES",
    "MAX_PRIOR_SESSIONS",
    "RELEARN_EVERY",
    "SHARE_GATE",
    "check_prior_from",
    "describe_prior",
    "earlier_subjects",
    "grid_difference",
    "log_sha256",
    "make_warm_start",
    "new_warm_start",
    "prepare_state",
    "read_prior_from",
    "recorded_prior",
    "resolve_prior",
]
