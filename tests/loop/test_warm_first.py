"""A warm start's first trial (``Learning.warm_first``): the earlier subjects' recommendation
with ``"recommended"``, the strategy's pick (the cold loop's, the new subject starting alone)
with ``"strategy"``, and the strategy's again where the population says nothing (``rho = 0``)."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref.errors import QueryError
from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.learning import Learning
from gaitpref.loop.safety import Safety
from gaitpref.loop.warm import WarmStart, warm_data
from gaitpref.simulate.users import SimulatedUser
from tests.loop.test_warm import KERNEL, SPACE, UTILITY, _earlier

BEST = int(np.argmax(UTILITY))  # the earlier subjects' best gait (x = 0.7)


def _loop(first: str, rho: float = 0.8, safety: Safety | None = None) -> CoSpar:
    learning = Learning(share="average", warm_first=first)  # type: ignore[arg-type]
    loop = CoSpar(SPACE, KERNEL, 0.1, n=1, buffer=1, seed=4, learning=learning, safety=safety)
    warm = WarmStart(warm_data(SPACE, _earlier()), rho, 2, share=0.0, relearn_every=1, gate=0.0)
    loop.warm_start(warm)
    return loop


def _cold_first() -> tuple[int, ...]:
    return CoSpar(SPACE, KERNEL, 0.1, n=1, buffer=1, seed=4).ask().actions


def _population_argmax(loop: CoSpar, allowed: np.ndarray | None = None) -> int:
    assert loop.warm is not None
    mean = np.asarray(loop._posterior_sharing(loop.warm.rho).mean)
    return int(np.argmax(np.where(allowed, mean, -np.inf) if allowed is not None else mean))


def test_the_first_trial_is_the_earlier_subjects_recommendation() -> None:
    loop = _loop("recommended")
    first = loop.ask()
    assert first.actions == (_population_argmax(loop),)
    assert abs(first.actions[0] - BEST) <= 1  # where the earlier subjects' answers point
    assert first.actions != _cold_first()  # not what the new subject alone would start with
    user = SimulatedUser(SPACE, UTILITY, np.random.default_rng(1), noise=0.0)
    loop.tell(first, user.answer(first))
    second = loop.ask()  # from then on the strategy chooses, comparing with the buffered first
    assert second.buffer == first.actions
    loop.undo()
    assert loop.ask() == first  # derived again, the same gait


@pytest.mark.parametrize(("first", "rho"), [("strategy", 0.8), ("recommended", 0.0)])
def test_otherwise_the_first_trial_is_the_strategys_as_cold(first: str, rho: float) -> None:
    assert _loop(first, rho).ask().actions == _cold_first()


def test_the_recommendation_keeps_off_gaits_flagged_unsafe() -> None:
    safety = Safety(unsafe_radius=0.1)
    loop = _loop("recommended", safety=safety)
    loop.flag_unsafe(BEST)
    allowed = loop.allowed()
    assert allowed is not None and not allowed[BEST]
    (action,) = loop.ask().actions
    assert allowed[action] and abs(SPACE.points[action, 0] - SPACE.points[BEST, 0]) > 0.1
    assert action == _population_argmax(loop, allowed)


def test_a_warm_start_after_the_first_answer_is_still_refused() -> None:
    loop = _loop("recommended")
    q = loop.ask()
    loop.tell(q, [])
    with pytest.raises(QueryError, match="before the first query"):
        loop.warm_start(WarmStart(warm_data(SPACE, _earlier()), 0.8, 2))
