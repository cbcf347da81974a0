"""The ``[stop]`` table: when a session has learnt enough and moves to blind validation.

    [stop]                     # optional: no table, no rule
    confidence = 0.9           # stop once P(the recommended gait is within tolerance of the
                               # best) reaches this (optional)
    max_trials = 30            # or after this many executed trials (optional)
    tolerance = 0.05           # a fraction of the utility's range (default 0.05)
    samples = 2000             # posterior samples behind the probability (default 2000; on
                               # large grids fewer: StopRule.samples_for)

``loop/stopping.py`` computes the probability and the expected regret of stopping now.
"""

from __future__ import annotations

from gaitpref.config.schema import STOP, check_table
from gaitpref.loop.stopping import StopRule


def parse_stop(raw: object) -> tuple[StopRule, frozenset[str]]:
    """The stopping rule of ``[stop]`` (inactive when neither ``confidence`` nor
    ``max_trials`` is given) and the keys left to their defaults (``"stop.samples"``)."""
    stop, defaulted = check_table(raw, "stop", STOP)
    rule = StopRule(stop["confidence"], stop["max_trials"], stop["tolerance"], stop["samples"])
    return rule, frozenset(f"stop.{k}" for k in defaulted)


__all__ = ["parse_stop"]
