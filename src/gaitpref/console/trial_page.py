"""What the trial page shows, gathered from a session (read-only)."""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from gaitpref.console import views
from gaitpref.console.present import ratings_by_trial
from gaitpref.console.service import Pending
from gaitpref.errors import NoSafeGaitError
from gaitpref.plots.trials import on_a_grid
from gaitpref.sessions import preference_learned
from gaitpref.sessions.gaits import NOT_MADE
from gaitpref.sessions.records import SuggestionRecord
from gaitpref.sessions.session import Session
from gaitpref.space import Space

#: the trials the trial page lists with their forms, newest first (and as many of its notes and of
#: its gaits that could not be made); the rest are behind "show all" (``?trials=all``): every row
#: has two forms, about 1.8 kB, and the page is sent again after every answer (762 kB at 400
#: trials before the cut, benchmarks/results/long.md)
RECENT_TRIALS = 20


@dataclass(frozen=True)
class ChronoRow:
    """One trial of the chronology: what ran, what was said about it."""

    trial: int
    query: int
    gait: views.GaitView
    compared: tuple[str, ...]
    suggested: tuple[str, ...]
    excluded: str | None
    rating: str | None = None  # the category it was rated
    unsafe: str | None = None  # the unsafe flag's reason


def _outcome_text(first: int, second: int, outcome: str, trial: int) -> str:
    """A comparison as seen from ``trial`` (one of ``first``/``second``)."""
    other = second if trial == first else first
    if outcome == "none":
        return f"= trial {other} (no preference)"
    won = (outcome == "first") == (trial == first)
    return f"> trial {other}" if won else f"< trial {other}"


def _edge(space: Space, s: SuggestionRecord) -> str:
    """What the chronology adds to a suggestion that went past the edge of its feature's
    range: back to the same gait (not modelled), or clipped to the edge."""
    if s.target is None:
        return " (already at the edge of its range)"
    f = space.features[space.feature_number(s.feature)]
    value = float(space.point(s.action)[space.feature_number(s.feature)])
    return " (clipped at the edge of its range)" if f.move_clipped(value, s.move) else ""


def chronology(session: Session) -> list[ChronoRow]:
    """The trials in force, newest first, with their comparisons and suggestions."""
    space = session.space
    compared: dict[int, list[str]] = {}
    for c in session.comparisons():
        if c.undone:
            continue
        for t in {c.first_trial, c.second_trial}:
            text = _outcome_text(c.first_trial, c.second_trial, c.outcome, t)
            compared.setdefault(t, []).append(text + (" [excluded]" if c.excluded else ""))
    suggested: dict[int, list[str]] = {}
    words = {f.name: views.move_words(f) for f in space.features}
    for s in session.suggestions():
        if s.undone:
            continue
        text = f"{views.pretty(s.feature)}: {words[s.feature][s.move]}"
        suggested.setdefault(s.trial, []).append(text + _edge(space, s))
    rated = ratings_by_trial(session)
    unsafe = session.unsafe_flags()
    rows = [
        ChronoRow(
            t.number,
            t.query,
            views.gait_view(space, t.action, trial=t.number, gait_id=session.gait_name(t.action)),
            tuple(compared.get(t.number, ())),
            tuple(suggested.get(t.number, ())),
            t.excluded,
            rated.get(t.number),
            unsafe[t.number][1] if t.number in unsafe else None,
        )
        for t in session.trials()
    ]
    return list(reversed(rows))


def figure_alt(session: Session, trials: int, best: str | None, learned: bool) -> str:
    """The posterior figure's text alternative: what it plots, the gait it stars (``best``, as
    the page states it) and what its shading and marks mean, in words rather than colours."""
    space = session.space
    names = [views.pretty(f.name) for f in space.features]
    over = " and ".join(names) if len(names) <= 2 else f"{len(names)} features"
    where = "over" if on_a_grid(space) else "at the tried gaits of"
    text = f"The model's utility {where} {over} after {trials} trial{'s' if trials != 1 else ''}"
    if not learned:
        text += "; no preference learned yet, no gait starred"
    elif best is not None:
        text += f"; the best so far, {best}, is starred"
    else:
        text += "; no gait may be recommended, none starred"
    if on_a_grid(space) and (session.config.safety.avoid or session.unsafe_flags()):
        text += (
            "; gaits in the region of avoidance are shaded grey and hatched, gaits flagged unsafe "
            "are marked X and the gaits near them hatched the other way (1-D) or ringed by a "
            "dashed line (2-D)"
        )
    return text + "."


def trial_context(
    session: Session, pending: Pending, *, all_trials: bool = False
) -> dict[str, Any]:
    """Everything ``trial.html`` renders: ``chronology`` is every trial in force (what the page
    says is derived from it: the flash, the last trial's flag), ``listed`` the rows the page
    lists, the last :data:`RECENT_TRIALS` unless ``all_trials``."""
    space = session.space
    query = pending.query
    actions: list[views.GaitView] = []
    buffer: list[views.GaitView] = []
    if query is not None:
        actions = [
            views.gait_view(space, a, trial=t, gait_id=session.gait_name(a))
            for a, t in zip(query.actions, query.trials, strict=True)
        ]
        buffer = [
            views.gait_view(space, a, trial=t, gait_id=session.gait_name(a))
            for a, t in zip(query.buffer, query.buffer_trials, strict=True)
        ]
    post = session.posterior()
    mean = np.asarray(post.mean)  # the marginal sd is left to the figure: it costs O(A m^2)
    best = session.recommended()  # among the gaits that may be proposed, as the confidence's
    spec = session.config.generator
    trials = session.trials()
    learned = preference_learned(mean)  # as session show says it
    sure = None
    if learned:
        with contextlib.suppress(NoSafeGaitError):  # no gait left to recommend: none stated
            sure = session.confidence()
    ordinal = session.config.ordinal
    categories = ordinal.categories if ordinal is not None else ()
    unsafe = session.unsafe_flags()
    last = [t for t in trials if t.query == trials[-1].query] if trials else []
    # the session refuses to undo an answer whose trial was excluded or flagged since
    undoable = bool(last) and not any(t.excluded or t.number in unsafe for t in last)
    rows = chronology(session)
    # "Flag trial N unsafe" beside the undo: the last trial's, unless flagged (or finished)
    flaggable = session.status != "finished"
    flag_last = rows[0] if rows and flaggable and rows[0].unsafe is None else None
    # newest first, cut as the trials are (every one with ?trials=all)
    notes, infeasible = list(reversed(session.notes())), list(reversed(session.infeasible_gaits()))
    return {
        "session": session,
        "status": session.status,
        "reason": pending.reason,
        "reason_detail": pending.detail,
        "query": query,
        "actions": actions,
        "buffer": buffer,
        "comparisons": views.comparison_groups(actions, buffer),
        "comparison_notes": views.comparison_notes(actions, buffer),
        "suggestions": views.suggestion_groups(space, actions),
        "ratings": views.rating_groups(categories, actions),
        "categories": categories,
        "unsafe": unsafe,
        "undoable": undoable,
        "undo_key": views.undo_key(space),
        # the undo takes back the last answer's whole query (n > 1: several trials)
        "undo_say": "Take back the answer to "
        + (
            f"trial {last[0].number} ({session.gait_name(last[0].action)})"
            if len(last) == 1
            else f"trials {', '.join(str(t.number) for t in last)}, one query"
        ),
        "infeasible": infeasible if all_trials else infeasible[:RECENT_TRIALS],
        "infeasible_count": len(infeasible),
        "multi": len(actions) > 1,
        "chronology": rows,
        "listed": rows if all_trials else rows[:RECENT_TRIALS],
        "all_trials": all_trials,
        "recent_trials": RECENT_TRIALS,
        "flag_last": flag_last,
        # its shortcut, shown (on its button, in the list) only where the button is
        "flag_key": None if flag_last is None else views.FLAG_KEY,
        "notes": notes if all_trials else notes[:RECENT_TRIALS],
        "notes_count": len(notes),
        "best": None
        if best is None
        else views.gait_view(space, best, gait_id=session.gait_name(best)),
        "best_mean": None if best is None else float(mean[best]),
        "best_not_made": None if best is None or session.gait_made(best) is not False else NOT_MADE,
        "no_best": session.no_recommendation() if best is None else None,
        # gaits made on demand, [gaits] recommend = "made": the best is among the gaits made
        "made_only": spec is not None and spec.recommends_made,
        "learned": learned,
        "confidence": None if sure is None else sure.sentence(session.gait_name(sure.recommended)),
        "regret": None if sure is None else sure.relative_regret,
        "stop_blocked": session.stop_blocked(),
        # a round is open: why the [stop] rule says stop, if it does (it opened the round, or
        # would have), so that the operator is told why validation comes now
        "stop_reason": session.stop_reason() if pending.reason == "validation" else None,
        "prior_from": [p["session"] for p in session.record.meta.get("prior_from", [])],
        "trials_done": len(trials),
        "figure_url": f"/sessions/{session.id}/posterior.png?v={session.last_seq}",
        "figure_alt": figure_alt(
            session, len(trials), None if best is None else session.gait_name(best), learned
        ),
        "suggestion_keys": views.suggestion_shortcuts(space),
    }
