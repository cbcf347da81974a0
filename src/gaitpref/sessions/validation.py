"""Blind validation of a learned preference model (the paper's protocol).

Section "Learning Preferences between Step Lengths": after the trials, "three points along the
utility model's posterior mean were selected: the maximum, mean, and minimum.  The user walked in
the exoskeleton with each of these step lengths in a randomized ordering, and gave a blind
ranking of the three".  Here:

- *maximum* / *minimum*: the actions with the highest / lowest posterior mean (lowest index among
  exact ties);
- *mean*: among the other actions, the one whose posterior mean is closest to the average of the
  posterior mean over the grid (lowest index among ties);
- the order of presentation is a uniformly random permutation drawn with the caller's generator;
  the gaits are labelled ``A, B, C`` in that order, so a label says nothing about a role;
- the subject's ranking (best first) *agrees* when it is ``max, mean, min``; Kendall's tau
  compares the two rankings (1: identical, -1: reversed).

Notation: ``mean`` is the posterior mean over the ``A`` actions; roles are ``"max"``,
``"mean"``, ``"min"`` and their model order is ``ROLES``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import combinations

import numpy as np
from numpy.typing import ArrayLike

ROLES: tuple[str, str, str] = ("max", "mean", "min")
LABELS: tuple[str, str, str] = ("A", "B", "C")


@dataclass(frozen=True)
class BlindGait:
    """One validation gait as shown: a label and the action to run (no role)."""

    label: str
    action: int


@dataclass(frozen=True)
class ValidationPlan:
    """A round of blind validation: the gaits in the order they are presented."""

    round: int
    gaits: tuple[BlindGait, ...]

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(g.label for g in self.gaits)


@dataclass(frozen=True)
class ValidationResult:
    """A round unblinded: the subject's ranking against the model's."""

    round: int
    ranking: tuple[str, ...]  # the subject's, best first (labels)
    model_ranking: tuple[str, ...]  # labels ordered max, mean, min
    roles: dict[str, str]  # label -> role
    actions: dict[str, int]  # label -> action
    posterior_mean: dict[str, float]  # label -> posterior mean when the round started
    agrees: bool
    kendall_tau: float


def validation_actions(
    mean: ArrayLike, candidates: Sequence[int] | None = None
) -> tuple[int, int, int]:
    """The actions at the maximum, the mean and the minimum of the posterior mean (among
    ``candidates`` when given: the gaits that may be shown, i.e. made if made on demand and
    none near a gait flagged unsafe or in the region of avoidance)."""
    mu = np.asarray(mean, dtype=np.float64).ravel()
    if candidates is not None:
        among = np.asarray(candidates, dtype=np.intp)
        if among.size < 3:
            raise ValueError(
                f"blind validation needs at least 3 gaits; {among.size} may be shown (made so "
                "far, and none near a gait flagged unsafe or in the region of avoidance)"
            )
        best, middle, worst = validation_actions(mu[among])
        return int(among[best]), int(among[middle]), int(among[worst])
    if mu.size < 3:
        raise ValueError(  # a grid's gaits, or on the line path the points so far (no grid)
            f"blind validation needs at least 3 gaits; the model holds {mu.size}"
        )
    best, worst = int(np.argmax(mu)), int(np.argmin(mu))
    if mu[best] == mu[worst]:
        raise ValueError(
            "the posterior mean is flat (no preference has been learned yet): nothing to validate"
        )
    distance = np.abs(mu - mu.mean())
    distance[[best, worst]] = np.inf
    return best, int(np.argmin(distance)), worst


def blind_plan(
    round_: int,
    mean: ArrayLike,
    rng: np.random.Generator,
    candidates: Sequence[int] | None = None,
) -> tuple[ValidationPlan, dict[str, str]]:
    """A plan with a random order, and the hidden label -> role map."""
    actions = dict(zip(ROLES, validation_actions(mean, candidates), strict=True))
    order = [ROLES[int(k)] for k in rng.permutation(len(ROLES))]
    plan = ValidationPlan(
        round_,
        tuple(BlindGait(label, actions[role]) for label, role in zip(LABELS, order, strict=True)),
    )
    return plan, dict(zip(LABELS, order, strict=True))


def check_ranking(ranking: Sequence[str] | str, labels: Sequence[str]) -> tuple[str, ...]:
    """A ranking (best first) as a tuple of labels: each label exactly once."""
    items = (
        tuple(ranking.upper())
        if isinstance(ranking, str)
        else tuple(str(r).upper() for r in ranking)
    )
    if sorted(items) != sorted(labels):
        raise ValueError(
            f"a ranking names each of {', '.join(labels)} exactly once, best first "
            f"(e.g. {''.join(labels)}); got {''.join(items) or 'nothing'}"
        )
    return items


def kendall_tau(first: Sequence[str], second: Sequence[str]) -> float:
    """Kendall's tau between two rankings of the same items (no ties): in [-1, 1]."""
    if sorted(first) != sorted(second) or len(set(first)) != len(first):
        raise ValueError("kendall_tau needs two rankings of the same distinct items")
    n = len(first)
    if n < 2:
        return 1.0
    pos = {item: k for k, item in enumerate(second)}
    concordant = sum(1 for i, j in combinations(range(n), 2) if pos[first[i]] < pos[first[j]])
    pairs = n * (n - 1) // 2
    return (2 * concordant - pairs) / pairs


def unblind(
    plan: ValidationPlan,
    roles: Mapping[str, str],
    values: Mapping[str, float],
    ranking: Sequence[str] | str,
) -> ValidationResult:
    """Compare the subject's ``ranking`` with the model's and reveal the roles.

    ``values``: label -> posterior mean of its action when the round was planned.
    """
    labels = plan.labels
    subject = check_ranking(ranking, labels)
    by_role = {role: label for label, role in roles.items()}
    model = tuple(by_role[r] for r in ROLES)
    return ValidationResult(
        round=plan.round,
        ranking=subject,
        model_ranking=model,
        roles=dict(roles),
        actions={g.label: g.action for g in plan.gaits},
        posterior_mean={label: float(values[label]) for label in labels},
        agrees=subject == model,
        kendall_tau=kendall_tau(subject, model),
    )
