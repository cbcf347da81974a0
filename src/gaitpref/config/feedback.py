"""The ``[feedback.rating]`` and ``[safety]`` tables: ordinal ratings and the region of avoidance.

    [feedback.rating]                        # optional: ask for a rating after each trial
    labels = ["very bad", "bad", "okay", "good"]   # worst first, 2 to 10 categories
    # thresholds = [-0.05, 0.0, 0.05]       # optional: K - 1 increasing (default: the
    #                                        # prior predictive's quantiles: all equally likely)
    # noise = 0.02                           # optional: rating noise (default: [model].noise)

    [safety]                                 # optional
    avoid = ["very bad"]                     # the worst categories to keep away from (a prefix
                                             # of the labels); needs [feedback.rating]
    lambda = 1.0                             # avoided when mu + lambda sd < the threshold above
    unsafe_radius = 0.1                      # a flagged gait's neighbourhood (fraction of each
                                             # feature's range; 0: the gait alone)

ROIAL (Li, Tucker et al., ICRA 2021) for both; ``model/ordinal.py`` and ``loop/safety.py`` for
the maths.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gaitpref.config.schema import FEEDBACK, RATING, SAFETY, check_table
from gaitpref.config.specs import fail
from gaitpref.loop.safety import Safety
from gaitpref.model.ordinal import Ordinal


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


def parse_safety(raw: object, ordinal: Ordinal | None) -> Safety:
    """The settings of ``[safety]`` (no region of avoidance when ``avoid`` is empty)."""
    safety: dict[str, Any]
    safety, _ = check_table(raw, "safety", SAFETY)
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
    return Safety(len(avoid), safety["lambda"], safety["unsafe_radius"])


__all__ = ["parse_rating", "parse_safety"]
