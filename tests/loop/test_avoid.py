"""``CoSpar.avoid``: a proposal whose gait cannot be made takes itself and its neighbourhood out of
every later query (gaits on demand); a pending query that proposes one is withdrawn and proposed
again from the same random state, so that a session replays it."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import CoSpar, Feature, Space, SquaredExponential
from gaitpref.errors import NoSafeGaitError
from gaitpref.loop.safety import near
from gaitpref.strategies import STRATEGIES, make_strategy

SPACE = Space(
    [
        Feature.linspace("length", 0.08, 0.18, 9, unit="m"),
        Feature.linspace("duration", 0.85, 1.15, 7, unit="s"),
    ]
)
KERNEL = SquaredExponential(lengthscale=(0.03, 0.08), variance=0.005, jitter=1e-7)


def _loop(strategy: str, seed: int = 3) -> CoSpar:
    return CoSpar(SPACE, KERNEL, 0.02, n=2, buffer=1, seed=seed, strategy=make_strategy(strategy))


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_no_strategy_proposes_near_an_avoided_action(strategy: str) -> None:
    loop = _loop(strategy)
    banned = np.zeros(len(SPACE), dtype=bool)
    for _ in range(6):
        q = loop.ask()
        assert not any(banned[a] for a in q.actions)
        a = q.actions[0]
        withdrawn = loop.avoid(a, 0.2)
        assert withdrawn and loop.pending is None
        banned |= near(SPACE, [a], 0.2)
        allowed = loop.allowed()
        assert allowed is not None and np.array_equal(allowed, ~banned)


def test_a_withdrawn_proposal_is_made_again_from_the_same_random_state() -> None:
    live = _loop("self-sparring", seed=11)
    first = live.ask()
    live.avoid(first.actions[0], 0.1)
    again = live.ask()
    # a loop that knew beforehand proposes exactly what the live one proposes after withdrawing
    known = _loop("self-sparring", seed=11)
    known.avoid(first.actions[0], 0.1)
    assert known.ask().actions == again.actions
    assert first.actions[0] not in again.actions


def test_avoiding_away_from_the_pending_query_keeps_it() -> None:
    loop = _loop("self-sparring")
    q = loop.ask()
    far = next(a for a in range(len(SPACE)) if not near(SPACE, q.actions, 0.1)[a])
    assert loop.avoid(far, 0.0) is False and loop.pending is q


def test_avoiding_everything_proposes_nothing_and_radius_is_checked() -> None:
    loop = _loop("self-sparring")
    loop.avoid(0, 1.0)  # a corner: the unit disc around it misses the far corner
    assert loop.allowed() is not None and loop.allowed().sum() > 0  # type: ignore[union-attr]
    loop.avoid(len(SPACE) - 1, 1.0)
    assert loop.allowed() is not None and not loop.allowed().any()  # type: ignore[union-attr]
    with pytest.raises(NoSafeGaitError, match="avoided"):
        loop.ask()
    with pytest.raises(ValueError, match="radius"):
        loop.avoid(0, 1.5)
