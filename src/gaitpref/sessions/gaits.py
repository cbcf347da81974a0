"""A session's proposals with gaits made on demand: an infeasible gait never reaches the subject.

With ``[gaits] generator`` (issue 13, item 4) every action a query proposes gets its gait before
the query is logged (``gaitpref.gaits.on_demand``: this session's gait, else the cached one, else
a new one warm-started from the nearest feasible gait made so far, within ``[gaits]
max_iterations`` solver iterations, so that no gait costs more than that).  A gait that cannot be
made is logged as ``gait_infeasible`` with the solver's reason; the loop then never proposes it,
nor the actions within ``[gaits].avoid_radius`` of it (:meth:`~gaitpref.loop.CoSpar.avoid`, the
unsafe-flag neighbourhood of ``loop/safety.py``), and proposes again with the same random state
(:meth:`~gaitpref.loop.CoSpar.avoid` withdraws the proposal).  Each gait new to the session is
logged as ``gait_made``.  Replay derives the same batch and checks it event by event
(``replay.py``): the cache only makes that fast, and a missing entry is made again.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from gaitpref.config import ExperimentConfig
from gaitpref.loop import CoSpar, Query
from gaitpref.sessions import events as log
from gaitpref.storage import NewEvent

if TYPE_CHECKING:
    from gaitpref.gaits.on_demand import MadeGait, OnDemandGaits


def propose_with_gaits(
    loop: CoSpar, gaits: OnDemandGaits, config: ExperimentConfig
) -> tuple[list[NewEvent], Query]:
    """The events of the gaits made for the loop's next feasible proposal, and the proposal.

    Terminates: each round takes at least one more action out of the proposals, and an empty
    choice raises :class:`~gaitpref.errors.NoSafeGaitError` from ``ask``.
    """
    assert config.generator is not None
    radius = config.generator.avoid_radius
    events: list[NewEvent] = []
    while True:
        query = loop.ask()
        space = loop.space  # the grid, or the line path's points (which the ask may extend)
        bad = []
        for action in dict.fromkeys(query.actions):  # each distinct action once, in order
            made, new = gaits.get(space.point(action))
            if made.feasible:
                if new:
                    events.append(log.new_event(_made(action, made, space.values_of(action))))
                continue
            bad.append(action)
            events.append(log.new_event(_infeasible(action, made, space.values_of(action), radius)))
        if not bad:
            return events, query
        for action in bad:
            loop.avoid(action, radius)


def _made(action: int, made: MadeGait, values: dict[str, float]) -> log.GaitMade:
    return log.GaitMade(
        action=action,
        gait_id=made.gait_id,
        key=made.key,
        values=values,
        cot=float(made.gait.cot),
        warm_start=made.warm_start,
    )


def _infeasible(
    action: int, made: MadeGait, values: dict[str, float], radius: float
) -> log.GaitInfeasible:
    return log.GaitInfeasible(
        action=action,
        gait_id=made.gait_id,
        key=made.key,
        radius=radius,
        values=values,
        reason=made.gait.message,
        warm_start=made.warm_start,
    )


__all__ = ["propose_with_gaits"]
