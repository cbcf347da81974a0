"""gated-eubo's exploration burst (``sparring_from``, ``sparring_until``): inside the window
each new action is a posterior sample's argmax, as self-sparring's; outside it the strategy is
unchanged."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import PreferenceGP, Space, SquaredExponential
from gaitpref.model.posterior import Posterior
from gaitpref.strategies import AskContext, GatedEubo, SelfSparring, make_strategy


def _posterior(space: Space, kernel: SquaredExponential) -> Posterior:
    rng = np.random.default_rng(5)
    w, l = rng.integers(0, len(space), 30), rng.integers(0, len(space), 30)
    keep = w != l
    return PreferenceGP(space, kernel, 0.02).posterior(w[keep], l[keep])


def _context(post: Posterior, buffer: tuple[int, ...], trial: int, seed: int) -> AskContext:
    return AskContext(post, 1, buffer, trial, np.random.default_rng(seed))


def test_inside_the_window_it_is_self_sparring_outside_it_gated_eubo(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = _posterior(small_space, small_kernel)
    # a buffered gait the posterior does not favour: the gate rarely fires, EUBO challenges
    buffer = (int(np.argsort(post.mean)[len(small_space) // 3]),)
    burst = GatedEubo(sparring_from=4, sparring_until=7)
    inside_differs = False
    for seed in range(30):
        sparring = SelfSparring().propose(_context(post, buffer, 5, seed))
        gated = GatedEubo().propose(_context(post, buffer, 5, seed))
        for trial in (4, 5, 6):  # the trials after the first 4, up to trial 7
            assert burst.propose(_context(post, buffer, trial, seed)) == sparring
        for trial in (0, 3, 7, 50):
            expected = GatedEubo().propose(_context(post, buffer, trial, seed))
            assert burst.propose(_context(post, buffer, trial, seed)) == expected
        inside_differs |= sparring != gated
    assert inside_differs  # the window changes the choice, not only its label


def test_off_by_default_and_unless_the_window_has_trials(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = _posterior(small_space, small_kernel)
    buffer = (int(np.argsort(post.mean)[len(small_space) // 3]),)
    assert (GatedEubo().sparring_from, GatedEubo().sparring_until) == (0, 0)
    for seed in range(10):
        for trial in (0, 5, 20):
            plain = GatedEubo().propose(_context(post, buffer, trial, seed))
            for empty in (
                GatedEubo(sparring_from=5, sparring_until=5),
                GatedEubo(sparring_from=20, sparring_until=0),  # a config's way to turn it off
            ):
                assert empty.propose(_context(post, buffer, trial, seed)) == plain


def test_the_window_respects_the_region_of_interest(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = _posterior(small_space, small_kernel)
    allowed = np.zeros(len(small_space), dtype=bool)
    allowed[::3] = True
    burst = GatedEubo(sparring_from=0, sparring_until=10)
    for seed in range(20):
        context = AskContext(post, 1, (1,), 2, np.random.default_rng(seed), allowed)
        (x,) = burst.propose(context)
        assert allowed[x]


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"sparring_from": -1}, "sparring_from"),
        ({"sparring_until": 2.5}, "sparring_until"),
        ({"sparring_from": True}, "sparring_from"),
    ],
)
def test_bad_settings_name_themselves(settings: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        GatedEubo(**settings)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=message):
        make_strategy("gated-eubo", **settings)
