"""The ``[feedback.rating]`` and ``[safety]`` tables: ordinal ratings and the region of avoidance.

    [feedback.rating]                        # optional: ask for a rating after each trial
    labels = ["very bad", "bad", "okay", "good"]   # worst first, 2 to 10 categories
    # thresholds = [-0.05, 0.0, 0.05]       # optional: K - 1 increasing (default: the
    #                                        # prior predictive's quantiles: all equally likely)
    # noise = 0.02                           # optional: rating noise (default: [model].noise)

    [safety]                                 # optional
    avoid = ["very bad"]                     # the worst categories to keep away from (a prefix
                                             # of the labels); needs [feedback.rating]
    # risk = 0.35                            # avoided when P(an avoided rating) > risk
                                             # (default: avoid / K + 0.1)
    # lambda = 1.0                           # instead of risk: ROIAL's bound, avoided when
                                             # mu + lambda sd < the threshold above
    # cautious = 0.6                         # with risk: while some gait's P(an avoided rating)
                                             # is at most this share of an unrated gait's,
                                             # propose only such known-safe gaits ... (0: off)
    # explore = 1.0                          # ... and unexplored ones whose mu + explore sd
                                             # beats every known-safe gait's ...
    # reach = 1.0                            # ... within reach lengthscales of a known-safe
                                             # gait (default: anywhere)
    # frontier = 0.9                         # ... and only where P(an avoided rating) is at
                                             # most frontier x an unrated gait's (above
                                             # cautious; default: off)
    unsafe_radius = 0.1                      # a flagged gait's neighbourhood (fraction of each
                                             # feature's range; 0: the gait alone)
    # start = [{step_length = 0.12, step_duration = 0.9}]   # gaits the operator declares safe
                                             # (feature values, gait ids of a library, or
                                             # action indices): executed first, known-safe

ROIAL (Li, Tucker et al., ICRA 2021) for both; ``model/ordinal.py`` and ``loop/safety.py`` for
the maths.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from gaitpref.config.schema import (
    DEFAULTS_VERSION,
    FEEDBACK,
    RATING,
    SAFETY,
    check_table,
    defaults_for,
)
from gaitpref.config.specs import clipped, fail, shown
from gaitpref.errors import GaitLibraryError
from gaitpref.loop.safety import Safety, default_risk
from gaitpref.model.ordinal import Ordinal
from gaitpref.space import Space

if TYPE_CHECKING:
    from gaitpref.gaits.library import GaitLibrary


def parse_rating(raw: object, noise: float) -> Ordinal | None:
    """The rating scale of ``[feedback.rating]`` (None without one)."""
    feedback, _ = check_table(raw, "feedback", FEEDBACK)
    if feedback["rating"] is None:
        return None
    rating, _ = check_table(feedback["rating"], "feedback.rating", RATING)
    labels: tuple[str, ...] = rating["labels"]
    thresholds = rating["thresholds"]
    if thresholds is not None:
        if len(thresholds) != len(labels) - 1:
            fail(
                "feedback.rating",
                "thresholds",
                f"must hold {len(labels) - 1} numbers (one between each pair of the "
                f"{len(labels)} labels), got {len(thresholds)}",
            )
        if np.any(np.diff(thresholds) <= 0):
            fail("feedback.rating", "thresholds", f"must increase, got {thresholds}")
    return Ordinal(labels, thresholds, rating["noise"] if rating["noise"] is not None else noise)


def parse_safety(
    raw: object,
    ordinal: Ordinal | None,
    defaults: str = DEFAULTS_VERSION,
    space: Space | None = None,
    library: GaitLibrary | None = None,
) -> tuple[Safety, frozenset[str]]:
    """The settings of ``[safety]`` (no region of avoidance when ``avoid`` is empty) with the
    defaults of version ``defaults``, and the keys that left the rule to them (``safety.risk``).

    ``start`` names gaits of ``space``, the grid (None: the line path, which takes none), by
    feature values, ``library``'s gait ids or action indices."""
    safety: dict[str, Any]
    safety, defaulted = check_table(raw, "safety", SAFETY, defaults_for(defaults, "safety"))
    avoid: tuple[str, ...] = tuple(safety["avoid"])
    if avoid:
        if ordinal is None:
            fail("safety", "avoid", "needs a [feedback.rating] table with the labels it names")
        if avoid != ordinal.categories[: len(avoid)]:
            fail(
                "safety",
                "avoid",
                "must be the worst labels of [feedback.rating], in order (e.g. "
                f"{list(ordinal.categories[:1])}), got {list(avoid)}",
            )
        if len(avoid) >= ordinal.size:
            fail("safety", "avoid", "must leave at least one category to propose")
    risk = _risk(safety, defaulted, len(avoid), ordinal)
    cautious = _cautious(safety, defaulted, risk)
    relied = {"safety.risk"} if avoid and {"lambda", "risk"} <= defaulted else set()
    if cautious is not None and "cautious" in defaulted:
        relied.add("safety.cautious")
    start = _start(safety["start"], space, library)
    return Safety(
        len(avoid),
        safety["lambda"],
        safety["unsafe_radius"],
        risk,
        cautious,
        safety["explore"],
        start,
        safety["reach"],
        safety["frontier"],
    ), frozenset(relied)


def _start(
    gaits: list[str | int | dict[str, float]], space: Space | None, library: GaitLibrary | None
) -> tuple[int, ...]:
    """The action indices of ``[safety].start``, each checked against the grid."""
    if not gaits:
        return ()
    if space is None:
        fail("safety", "start", "names gaits of a grid; the line path (subspace = 'line') has none")
    out: list[int] = []
    for k, gait in enumerate(gaits, start=1):
        where = f"gait {k} ({shown(gait)})"
        if isinstance(gait, str):
            if library is None:
                fail("safety", "start", f"{where}: a gait id needs a [gaits] library")
            try:
                index = library.index_of_id(gait)
            except GaitLibraryError as exc:
                fail("safety", "start", f"{where}: {exc}")
        elif isinstance(gait, int):
            if gait >= len(space):
                fail("safety", "start", f"{where}: the grid's actions are 0..{len(space) - 1}")
            index = gait
        else:
            index = _at(gait, space, where)
        if index in out:
            fail("safety", "start", f"{where} is the same gait as gait {out.index(index) + 1}")
        out.append(index)
    return tuple(out)


def _at(values: dict[str, float], space: Space, where: str) -> int:
    """The grid action with these feature values (each a grid value, within 1e-6 of its range)."""
    names = set(space.names)
    if set(values) != names:
        wrong = sorted(set(values) - names) or sorted(names - set(values))
        what = "unknown feature" if set(values) - names else "missing feature"
        fail(
            "safety",
            "start",
            f"{where}: {what} {shown(wrong[0])} (features: "
            f"{', '.join(clipped(n) for n in space.names)})",
        )
    idx = []
    for f in space.features:
        v = values[f.name]
        k = int(np.argmin(np.abs(f.array - v)))
        if abs(f.values[k] - v) > 1e-6 * max(f.span, 1e-12):
            near = ", ".join(f"{x:g}" for x in sorted(f.array[np.argsort(np.abs(f.array - v))[:2]]))
            fail(
                "safety",
                "start",
                f"{where}: {f.name} = {v:g} is not a grid value (nearest: {near})",
            )
        idx.append(k)
    return int(np.ravel_multi_index(tuple(idx), space.shape))


def _cautious(
    safety: dict[str, Any], defaulted: frozenset[str], risk: float | None
) -> float | None:
    """The ``risk`` rule's cautious level (None: none, the single-level rule): the default's
    (0.6 since defaults version 0.4) with a region of avoidance under ``risk``, or the one given."""
    cautious = float(safety["cautious"])
    given = "cautious" not in defaulted
    if given and cautious >= 1:
        fail("safety", "cautious", f"must be below 1 (0: no cautious level), got {cautious:g}")
    if given and cautious > 0 and not safety["avoid"]:
        fail("safety", "cautious", 'needs a region of avoidance (avoid = ["..."])')
    if given and cautious > 0 and risk is None:
        fail("safety", "cautious", "needs the risk rule, not ROIAL's bound (lambda)")
    if cautious == 0 or not safety["avoid"] or risk is None:
        for key in ("explore", "reach", "frontier"):
            if key not in defaulted:
                fail("safety", key, "is a setting of the cautious level, which is off here")
        return None
    frontier = safety["frontier"]
    if frontier is not None and frontier <= cautious:
        fail(
            "safety",
            "frontier",
            f"must exceed cautious ({cautious:g}), got {frontier:g}: a gait under frontier x an "
            "unrated gait's probability is known-safe already, so nothing would be left to "
            "explore",
        )
    return cautious


def _risk(
    safety: dict[str, Any], defaulted: frozenset[str], avoid: int, ordinal: Ordinal | None
) -> float | None:
    """The region's ``risk`` (None: ROIAL's bound with ``lambda``, given or the old default)."""
    if "lambda" not in defaulted:
        if "risk" not in defaulted:
            fail("safety", "risk", "give either risk or lambda (ROIAL's bound), not both")
        return None
    risk: float | str | None = safety["risk"]
    if risk is None or not avoid or ordinal is None:
        return None
    if risk == "auto":
        auto = default_risk(avoid, ordinal.size)
        if auto >= 1:
            fail(
                "safety",
                "avoid",
                f"avoids {avoid} of {ordinal.size} categories: the default risk (avoid / K + "
                f"0.1 = {auto:g}) is not below 1; give [safety] risk, or avoid fewer",
            )
        return auto
    prior = avoid / ordinal.size
    if ordinal.thresholds is None and float(risk) <= prior:
        fail(
            "safety",
            "risk",
            f"must exceed {prior:g}, the probability of an avoided rating before any data "
            f"(else every gait is avoided before the first rating), got {risk}",
        )
    return float(risk)


__all__ = ["parse_rating", "parse_safety"]
