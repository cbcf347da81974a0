"""One simulated CoSpar experiment: a loop, a simulated user, optional coactive feedback.

A *trial* is one executed action (the paper's Fig. 4 x-axis): ``n = 2`` gives 75 iterations of 2
trials for 150 trials.  The score of a trial is the normalised objective of its action,
``(f - min f) / (max f - min f)`` (flipped for ``minimize``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gaitpref.loop.cospar import CoSpar
from gaitpref.model.posterior import Posterior
from gaitpref.simulate.users import GradientCoactive, SimulatedUser
from gaitpref.space import FloatArray, IntArray


@dataclass(frozen=True)
class SimulationResult:
    """Per-trial executed actions and their normalised objective, and the final model."""

    actions: IntArray
    normalized_objective: FloatArray
    posterior: Posterior
    argmax_normalized_objective: float  # of the final posterior mean's argmax

    @property
    def posterior_argmax(self) -> int:
        """Grid index of the final posterior mean's argmax."""
        return self.posterior.argmax

    def to_json(self) -> dict[str, object]:
        return {
            "trials": int(self.actions.size),
            "actions": self.actions.tolist(),
            "normalized_objective": self.normalized_objective.tolist(),
            "posterior_argmax": self.posterior_argmax,
            "posterior_argmax_normalized_objective": self.argmax_normalized_objective,
        }


def run_simulation(
    loop: CoSpar,
    user: SimulatedUser,
    trials: int,
    coactive: GradientCoactive | None = None,
    progress: Callable[[int], None] | None = None,
) -> SimulationResult:
    """Run ``loop`` against ``user`` until ``trials`` actions have been executed.

    ``progress`` is called with the number of trials done after every iteration.
    """
    if trials < 1:
        raise ValueError(f"trials must be >= 1, got {trials}")
    executed: list[int] = []
    while len(executed) < trials:
        query = loop.ask()
        suggestions = [] if coactive is None else coactive.suggest_all(query.actions)
        loop.tell(query, user.answer(query), suggestions)
        executed.extend(query.actions)
        if progress is not None:
            progress(min(len(executed), trials))
    actions = np.asarray(executed[:trials], dtype=np.intp)
    posterior = loop.posterior
    return SimulationResult(
        actions=actions,
        normalized_objective=user.normalized(actions),
        posterior=posterior,
        argmax_normalized_objective=float(user.normalized([posterior.argmax])[0]),
    )
