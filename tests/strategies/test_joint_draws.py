"""Each strategy says the most joint samples one ask draws (``joint_draws``), which a new
session checks against the sampling budget (``config/draws.py``): here it is what their asks
actually draw at most, in every kind of context (and at the first query, exactly)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from gaitpref import Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.model.posterior import Posterior
from gaitpref.strategies import STRATEGIES, joint_draws, make_strategy
from tests.strategies.contexts import ask_context

SPACE = Space([Feature.linspace("a", 0, 1, 7), Feature.linspace("b", 0, 1, 5)])
POST = PreferenceGP(SPACE, SquaredExponential((0.3, 0.4), 0.005, 1e-7), 0.02).posterior(
    [0, 5, 9, 20], [3, 8, 30, 2]
)
SETTINGS: list[tuple[str, dict[str, Any], str | None]] = [
    *[(name, {}, None) for name in STRATEGIES],
    ("plausible-eubo", {"samples": 50, "gates": 7}, "samples"),
    ("gated-eubo", {"gates": 9}, "gates"),
    ("gated-eubo", {"gates": 2, "sparring_from": 10, "sparring_until": 100}, "n"),  # 3 > 2
]


@pytest.mark.parametrize(("name", "settings", "setting"), SETTINGS)
def test_joint_draws_is_the_largest_draw_an_ask_makes(
    name: str, settings: dict[str, Any], setting: str | None, monkeypatch: pytest.MonkeyPatch
) -> None:
    sizes: list[int] = []
    original = Posterior.argmax_samples

    def counted(self: Posterior, rng: np.random.Generator, size: int, *args: Any) -> Any:
        sizes.append(size)
        return original(self, rng, size, *args)

    monkeypatch.setattr(Posterior, "argmax_samples", counted)
    strategy = make_strategy(name, **settings)
    for n in (1, 3):
        sizes.clear()
        for buffer in ((), (4,)):
            for trial in (0, 50):
                strategy.propose(ask_context(POST, n, buffer, seed=trial + n, trial=trial))
        said, by = joint_draws(strategy, n)
        assert max(sizes, default=0) <= said, (n, sizes)
        if n == 1:  # every strategy's first query of a session draws its most
            assert max(sizes, default=0) == said, sizes
        if setting is not None and n == 3:
            assert by == setting


def test_a_strategy_that_does_not_say_is_taken_to_draw_n() -> None:
    class Custom:
        name = "custom"

        def propose(self, context: object) -> tuple[int, ...]:
            return (0,)

    assert joint_draws(Custom(), 5) == (5, "n")
