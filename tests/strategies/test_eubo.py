"""EUBO in closed form, the covariances it needs, and the strategies built on it."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from scipy.stats import norm

from gaitpref import CoSpar, PreferenceGP, Space, SquaredExponential
from gaitpref.model.posterior import Posterior
from gaitpref.strategies import (
    STRATEGIES,
    AskContext,
    ConfidentEubo,
    Eubo,
    GatedEubo,
    SelfSparring,
    Switch,
    make_strategy,
)
from gaitpref.strategies.base import MAX_CANDIDATES
from gaitpref.strategies.eubo import (
    best_pair,
    covariance_among,
    covariance_with,
    eubo_against,
    eubo_pair,
)


def _posterior(space: Space, kernel: SquaredExponential, seed: int = 0) -> Posterior:
    rng = np.random.default_rng(seed)
    w, l = rng.integers(0, len(space), 30), rng.integers(0, len(space), 30)
    keep = w != l
    return PreferenceGP(space, kernel, 0.02).posterior(w[keep], l[keep])


def test_eubo_pair_is_the_textbook_formula_and_a_monte_carlo_mean() -> None:
    rng = np.random.default_rng(1)
    mx, my, vx, vy, c = 0.3, 0.1, 0.04, 0.09, 0.02
    s = np.sqrt(vx + vy - 2 * c)
    d = mx - my
    textbook = mx * norm.cdf(d / s) + my * norm.cdf(-d / s) + s * norm.pdf(d / s)
    assert eubo_pair(mx, my, vx, vy, c) == pytest.approx(textbook, rel=1e-13)
    draws = rng.multivariate_normal([mx, my], [[vx, c], [c, vy]], 200_000)
    assert eubo_pair(mx, my, vx, vy, c) == pytest.approx(draws.max(axis=1).mean(), abs=2e-3)
    # symmetric, never below the larger mean, equal to it with no uncertainty
    assert eubo_pair(my, mx, vy, vx, c) == pytest.approx(textbook, rel=1e-13)
    assert eubo_pair(1.0, 2.0, 0.5, 0.5, 0.5) == 2.0
    assert np.all(eubo_pair(np.array([-50.0, 50.0]), 0.0, 1e-6, 1e-6, 0.0) >= [0.0, 50.0])


def test_covariances_match_the_dense_posterior_covariance(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = _posterior(small_space, small_kernel)
    cov = post.covariance()
    scale = np.max(np.abs(cov))
    for y in (0, 7, 34):
        assert np.allclose(covariance_with(post, y), cov[:, y], atol=1e-10 * scale)
    idx = np.array([3, 9, 20, 21], dtype=np.intp)
    assert np.allclose(covariance_among(post, idx), cov[np.ix_(idx, idx)], atol=1e-10 * scale)
    prior = PreferenceGP(small_space, small_kernel, 0.02).prior()
    assert np.allclose(covariance_with(prior, 4), small_kernel.dense(small_space)[:, 4])


def test_eubo_against_and_best_pair_agree_with_brute_force(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = _posterior(small_space, small_kernel, 3)
    mu, cov = np.asarray(post.mean), post.covariance()
    var = np.diag(cov)
    ref = 11
    brute = [eubo_pair(mu[x], mu[ref], var[x], var[ref], cov[x, ref]) for x in range(len(mu))]
    assert np.allclose(eubo_against(post, ref), brute, rtol=1e-10)
    cands = np.arange(len(small_space), dtype=np.intp)
    x, y, value = best_pair(post, cands)
    full = eubo_pair(mu[:, None], mu[None, :], var[:, None], var[None, :], cov)
    np.fill_diagonal(full, -np.inf)
    assert x != y and value == pytest.approx(full.max(), rel=1e-10)


def _context(post: Posterior, n: int, buffer: tuple[int, ...], trial: int = 5) -> AskContext:
    return AskContext(post, n, buffer, trial, np.random.default_rng(0))


def test_eubo_never_proposes_a_buffered_action_and_restricts_pairs_to_candidates(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = _posterior(small_space, small_kernel, 5)
    best = post.argmax
    for strategy in (Eubo(), ConfidentEubo(beta=0.5)):
        (x,) = strategy.propose(_context(post, 1, (best,)))
        assert x != best
        a, b = strategy.propose(_context(post, 2, (best,)))
        assert len({a, b, best}) == 3
    # with no buffer and n = 2: the best pair among the top-k candidates by mu + 2 sd
    top = np.argsort(-(np.asarray(post.mean) + 2 * np.asarray(post.std)))[:4]
    pair = Eubo(candidates=4).propose(_context(post, 2, ()))
    assert set(pair) <= set(top.tolist()) and pair[0] != pair[1]


def test_the_gate_repeats_the_buffered_action_only_when_a_sample_says_so(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = _posterior(small_space, small_kernel, 6)
    repeats = 0
    for seed in range(40):
        context = AskContext(post, 1, (post.argmax,), 50, np.random.default_rng(seed))
        sample = int(post.argmax_samples(np.random.default_rng(seed), 1)[0])
        (x,) = GatedEubo().propose(context)
        if sample == post.argmax:
            assert x == post.argmax
            repeats += 1
        else:
            assert x == Eubo().propose(_context(post, 1, (post.argmax,)))[0]
    assert 0 < repeats < 40


def test_switch_uses_early_then_late(small_space: Space, small_kernel: SquaredExponential) -> None:
    post = _posterior(small_space, small_kernel, 7)
    switch = Switch(trials=10)
    assert switch.propose(_context(post, 1, (0,), trial=9)) == Eubo().propose(
        _context(post, 1, (0,), trial=9)
    )
    assert switch.propose(_context(post, 1, (0,), trial=10)) == SelfSparring().propose(
        _context(post, 1, (0,), trial=10)
    )


@pytest.mark.parametrize("name", STRATEGIES)
def test_every_strategy_runs_the_loop_deterministically_and_never_locks_in(
    small_space: Space, small_kernel: SquaredExponential, name: str
) -> None:
    objective = np.sin(7 * small_space.points[:, 0]) + np.cos(3 * small_space.points[:, 1])

    def run() -> list[int]:
        loop = CoSpar(small_space, small_kernel, 0.02, n=1, buffer=1, seed=3,
                      strategy=make_strategy(name))  # fmt: skip
        for _ in range(40):
            q = loop.ask()
            (x,) = q.actions
            comps = [(x, b, "first" if objective[x] > objective[b] else "second")
                     for b in q.buffer if b != x]  # fmt: skip
            loop.tell(q, comps)
        return loop.executed

    first, second = run(), run()
    assert first == second
    # lock-in would repeat one action to the end: the last 15 trials hold several actions
    if name != "self-sparring":
        assert len(set(first[-15:])) > 1


def test_unknown_strategy_names_the_known_ones() -> None:
    with pytest.raises(ValueError, match="strategies are self-sparring, eubo"):
        make_strategy("ucb")


def test_the_eubo_helpers_take_grid_indices(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = _posterior(small_space, small_kernel)
    size = len(small_space)
    # -1 read the last gait's mean and variance (and failed in the kernel), silently in part
    for reference in (-1, size, 2.5, True):
        with pytest.raises((IndexError, TypeError), match="action index"):
            eubo_against(post, reference)  # type: ignore[arg-type]
    with pytest.raises(IndexError, match=r"candidates\[1\] = -1 is off the grid"):
        best_pair(post, np.array([0, -1]))
    with pytest.raises(TypeError, match="candidates must hold integer grid indices"):
        covariance_among(post, np.array([0.0, 1.0]))
    many = np.zeros(MAX_CANDIDATES + 1, dtype=np.intp)  # c x c: 10**6 asked for 8 TB
    with pytest.raises(ValueError, match=f"at most {MAX_CANDIDATES} candidates"):
        best_pair(post, many)
    three: Any = np.int64(3)
    assert np.array_equal(eubo_against(post, three), eubo_against(post, 3))
