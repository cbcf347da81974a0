"""CoSpar with earlier subjects' answers: rho = 0 changes nothing, the order of calls is checked."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import Feature, Space, SquaredExponential
from gaitpref.errors import QueryError
from gaitpref.feedback import Preference
from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.warm import WarmStart, warm_data
from gaitpref.simulate.users import SimulatedUser

SPACE = Space([Feature.linspace("x", 0.0, 1.0, 30)])
KERNEL = SquaredExponential(0.15, 1.0, 1e-6)
UTILITY = -((SPACE.points[:, 0] - 0.7) ** 2)


def _earlier() -> list[list[Preference]]:
    rng = np.random.default_rng(0)
    out = []
    for _ in range(2):
        prefs = []
        for _ in range(15):
            i, j = rng.choice(30, 2, replace=False)
            w, l_ = (i, j) if UTILITY[i] > UTILITY[j] else (j, i)
            prefs.append(Preference(int(w), int(l_), 0.1, "comparison", 1))
        out.append(prefs)
    return out


def _drive(loop: CoSpar, answers: int) -> None:
    user = SimulatedUser(SPACE, UTILITY, np.random.default_rng(1), noise=0.05)
    for _ in range(answers):
        q = loop.ask()
        loop.tell(q, user.answer(q))


def test_rho_zero_is_the_cold_loop_and_rho_one_starts_where_the_others_ended() -> None:
    cold = CoSpar(SPACE, KERNEL, 0.1, n=2, seed=4)
    zero = CoSpar(SPACE, KERNEL, 0.1, n=2, seed=4)
    zero.warm_start(WarmStart(warm_data(SPACE, _earlier()), 0.0, 2))
    assert np.allclose(zero.posterior.mean, 0.0, atol=1e-12)
    _drive(cold, 6)
    _drive(zero, 6)
    assert zero.executed == cold.executed
    assert np.allclose(zero.posterior.mean, cold.posterior.mean, rtol=0, atol=1e-8)
    shared = CoSpar(SPACE, KERNEL, 0.1, n=2, seed=4)
    shared.warm_start(WarmStart(warm_data(SPACE, _earlier()), 0.9, 2))
    assert abs(shared.posterior.argmax - int(np.argmax(UTILITY))) <= 2


def test_a_warm_start_comes_before_the_first_query() -> None:
    loop = CoSpar(SPACE, KERNEL, 0.1, n=2, seed=4)
    loop.ask()
    with pytest.raises(QueryError, match="before the first query"):
        loop.warm_start(WarmStart(warm_data(SPACE, _earlier()), 0.5, 2))
