"""gated-eubo's local challenger early (``early_scale``, ``early_trials``) and the loop's
rescaled posterior it chooses on (``AskContext.rescaled``, ``CoSpar._rescaled``)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import pytest

from gaitpref import CoSpar, PreferenceGP, Space, SquaredExponential
from gaitpref.model.posterior import Posterior
from gaitpref.simulate.users import SimulatedUser
from gaitpref.strategies import AskContext, Eubo, GatedEubo


def _data(space: Space, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    w, l = rng.integers(0, len(space), 24), rng.integers(0, len(space), 24)
    keep = w != l
    return w[keep], l[keep]


def _fit(space: Space, kernel: SquaredExponential, seed: int) -> Posterior:
    w, l = _data(space, seed)
    return PreferenceGP(space, kernel, 0.02).posterior(w, l)


def _halved(kernel: SquaredExponential) -> SquaredExponential:
    scales = tuple(0.5 * v for v in kernel.lengthscales(2))
    return dataclasses.replace(kernel, lengthscale=scales)


def _context(
    post: Posterior,
    buffer: tuple[int, ...],
    trial: int,
    seed: int,
    rescaled: Callable[[float], Posterior] | None = None,
) -> AskContext:
    return AskContext(post, 1, buffer, trial, np.random.default_rng(seed), None, rescaled)


def _refuses(factor: float) -> Posterior:
    raise AssertionError("the rescaled posterior was not to be asked for")


def test_off_by_default_and_after_the_early_trials(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = _fit(small_space, small_kernel, 1)
    buffer = (int(np.argsort(post.mean)[len(small_space) // 2]),)
    for seed in range(8):
        plain = GatedEubo().propose(_context(post, buffer, 3, seed))
        # early_scale 1 (the default) never refits; past early_trials neither
        assert GatedEubo().propose(_context(post, buffer, 3, seed, _refuses)) == plain
        late = GatedEubo(early_scale=0.5, early_trials=3)
        assert late.propose(_context(post, buffer, 3, seed, _refuses)) == plain
        # a loop that offers no rescaled posterior (the line path): the plain choice
        assert GatedEubo(early_scale=0.5).propose(_context(post, buffer, 0, seed)) == plain


def test_early_the_challenger_is_eubo_on_the_rescaled_posterior_and_the_gate_the_loops(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = _fit(small_space, small_kernel, 2)
    local = _fit(small_space, _halved(small_kernel), 2)  # an independent fit at half the scale
    asked: list[float] = []

    def rescaled(factor: float) -> Posterior:
        asked.append(factor)
        return local

    buffer = (int(post.argmax),)
    strategy = GatedEubo(early_scale=0.5, early_trials=20)
    repeats = challenges = 0
    for seed in range(40):
        (x,) = strategy.propose(_context(post, buffer, 5, seed, rescaled))
        gate = int(post.argmax_samples(np.random.default_rng(seed), 1)[0])
        if gate in buffer:  # the gate reads the loop's own posterior
            assert x == buffer[0]
            repeats += 1
            continue
        challenges += 1
        expected = Eubo().propose(_context(local, buffer, 5, seed))[0]
        assert x == expected
    assert repeats > 0 and challenges > 0
    assert set(asked) == {0.5}
    # and the halved posterior's challenger is not the configured one's everywhere
    plain = {GatedEubo().propose(_context(post, (b,), 5, 0))[0] for b in range(len(small_space))}
    halved = {
        strategy.propose(_context(post, (b,), 5, 0, rescaled))[0] for b in range(len(small_space))
    }
    assert plain != halved


def test_the_loops_rescaled_posterior_is_a_fit_at_the_scaled_lengthscale(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    loop = CoSpar(small_space, small_kernel, 0.02, n=1, buffer=1, seed=3)
    utility = np.sin(3.0 * small_space.points).sum(axis=1)
    user = SimulatedUser(small_space, utility, np.random.default_rng(4))
    for _ in range(10):
        query = loop.ask()
        loop.tell(query, list(user.answer(query)))
    prefs = [p for a in loop.answers for p in a.preferences]
    assert len(prefs) >= 5
    winners = np.array([p.winner for p in prefs])
    losers = np.array([p.loser for p in prefs])
    reference = PreferenceGP(small_space, _halved(small_kernel), 0.02).posterior(winners, losers)
    rescaled = loop._rescaled(0.5)
    assert np.allclose(rescaled.mean, reference.mean, rtol=1e-6, atol=1e-9)
    assert not np.allclose(rescaled.mean, loop.posterior.mean, rtol=1e-3)
    assert loop._rescaled(1.0) is loop.posterior
    with pytest.raises(ValueError, match="lengthscale factor"):
        loop._rescaled(0.0)


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"early_scale": 0.0}, "early_scale"),
        ({"early_scale": True}, "early_scale"),
        ({"early_scale": 1e4}, "early_scale"),
        ({"early_trials": -1}, "early_trials"),
        ({"early_trials": 2.5}, "early_trials"),
    ],
)
def test_bad_settings_name_themselves(settings: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        GatedEubo(**settings)  # type: ignore[arg-type]
