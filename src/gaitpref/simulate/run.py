"""One simulated CoSpar experiment: a loop, a simulated user, optional coactive feedback and
optional ordinal ratings (``raters.py``).

A *trial* is one executed action (the paper's Fig. 4 x-axis): ``n = 2`` gives 75 iterations of 2
trials for 150 trials.  The score of a trial is the normalised objective of its action,
``(f - min f) / (max f - min f)`` (flipped for ``minimize``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gaitpref.checks import is_count
from gaitpref.feedback import Rating
from gaitpref.limits import MAX_TRIALS
from gaitpref.loop.cospar import CoSpar
from gaitpref.model.posterior import Posterior
from gaitpref.simulate.raters import OrdinalRater
from gaitpref.simulate.users import GradientCoactive, SimulatedUser
from gaitpref.space import FloatArray, IntArray


@dataclass(frozen=True)
class SimulationResult:
    """Per-trial executed actions and their normalised objective, and the final model."""

    actions: IntArray
    normalized_objective: FloatArray
    posterior: Posterior
    argmax_normalized_objective: float  # of the final posterior mean's argmax (recommended)
    ratings: IntArray | None = None  # per trial, when a rater rated (1 = worst category)
    recommended: int | None = None  # the action scored by argmax_normalized_objective

    @property
    def posterior_argmax(self) -> int:
        """Grid index of the final posterior mean's argmax: the recommendation, the action
        :attr:`argmax_normalized_objective` scores.  With ``[model] hyper = "average"`` it is
        the argmax of the mixture mean over the lengthscale hypotheses
        (:meth:`CoSpar.mixture_mean`), which may differ from :attr:`posterior`'s own argmax
        (the MAP kernel's); before, this named the latter while the score was the former's."""
        return self.posterior.argmax if self.recommended is None else self.recommended

    def to_json(self) -> dict[str, object]:
        return {
            "trials": int(self.actions.size),
            "actions": self.actions.tolist(),
            "normalized_objective": self.normalized_objective.tolist(),
            "posterior_argmax": self.posterior_argmax,
            "posterior_argmax_normalized_objective": self.argmax_normalized_objective,
            **({} if self.ratings is None else {"ratings": self.ratings.tolist()}),
        }


def run_simulation(
    loop: CoSpar,
    user: SimulatedUser,
    trials: int,
    coactive: GradientCoactive | None = None,
    progress: Callable[[int], None] | None = None,
    rater: OrdinalRater | None = None,
) -> SimulationResult:
    """Run ``loop`` against ``user`` until ``trials`` actions have been executed (at most
    :data:`~gaitpref.limits.MAX_TRIALS`).

    ``rater`` also rates every executed action (the loop needs a rating scale with as many
    categories: another scale, or none, is refused before the first trial).
    ``progress`` is called with the number of trials done after every iteration.
    """
    if not is_count(trials) or not 1 <= trials <= MAX_TRIALS:  # 10**12 ran until memory ran out
        raise ValueError(f"trials must be an integer >= 1 and at most {MAX_TRIALS}, got {trials!r}")
    if rater is not None:  # a rater of 2 categories on a scale of 4 rated every gait "very bad"
        scale = loop.gp.ordinal
        if scale is None or scale.size != rater.categories:
            has = "no rating scale" if scale is None else f"{scale.size} categories"
            raise ValueError(
                f"the rater gives {rater.categories} categories ({rater.categories - 1} "
                f"quantiles), but the loop has {has}: give its [feedback.rating] one label more "
                "than the quantiles"
            )
    executed: list[int] = []
    rated: list[int] = []
    while len(executed) < trials:
        query = loop.ask()
        suggestions = [] if coactive is None else coactive.suggest_all(query.actions)
        answers: list[object] = list(user.answer(query))
        if rater is not None:
            ratings = {r.action: int(r.label) for r in rater.rate_all(query.actions)}
            answers += [Rating(a, k) for a, k in ratings.items()]
            rated.extend(ratings[a] for a in query.actions)
        loop.tell(query, answers, suggestions)
        executed.extend(query.actions)
        if progress is not None:
            progress(min(len(executed), trials))
    actions = np.asarray(executed[:trials], dtype=np.intp)
    posterior = loop.posterior
    best = _recommended(loop)
    return SimulationResult(
        actions=actions,
        normalized_objective=user.normalized(actions),
        posterior=posterior,
        argmax_normalized_objective=float(user.normalized([best])[0]),
        ratings=None if rater is None else np.asarray(rated[:trials], dtype=np.intp),
        recommended=best,
    )


def _recommended(loop: CoSpar) -> int:
    """The recommended action: the posterior mean's argmax (the mixture's, when the loop
    averages over lengthscale hypotheses)."""
    if not loop.hypotheses:
        return int(loop.posterior.argmax)
    return int(np.argmax(loop.mixture_mean()))
