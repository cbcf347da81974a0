"""Information gain (``strategies/bald.py``, ``strategies/infogain.py``): BALD against Monte Carlo
and exact quadrature, the region of interest, informative choices, replay, configs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import entr, ndtr

from gaitpref import CoSpar, Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.config import parse_config
from gaitpref.feedback import Comparison, Rating
from gaitpref.model.ordinal import Ordinal
from gaitpref.model.posterior import Posterior
from gaitpref.strategies import (
    STRATEGIES,
    InformationGain,
    SelfSparring,
    make_strategy,
)
from gaitpref.strategies.bald import (
    covariance_with_reference,
    information_against,
    preference_information,
    rating_information,
    variance_at,
)
from gaitpref.strategies.infogain import candidate_pool
from tests.strategies.contexts import ask_context

SCALE = Ordinal(["very bad", "bad", "okay", "good"], noise=0.02)
NOISE = 0.02
LN2 = np.log(2.0)


def _h(p: np.ndarray, axis: int = -1) -> np.ndarray:
    out: np.ndarray = np.sum(entr(p), axis=axis) / LN2
    return out


def _posterior(
    space: Space, kernel: SquaredExponential, ordinal: Ordinal | None, seed: int = 0
) -> Posterior:
    rng = np.random.default_rng(seed)
    w, l = rng.integers(0, len(space), 12), rng.integers(0, len(space), 12)
    keep = w != l
    ratings = [
        (int(a), int(k)) for a, k in zip(rng.integers(0, len(space), 4), [1, 2, 3, 4], strict=True)
    ]
    gp = PreferenceGP(space, kernel, NOISE, ordinal=ordinal)
    return gp.posterior(w[keep], l[keep], ratings=ratings if ordinal else None)


def _monte_carlo(post: Posterior, ref: int, draws: int, seed: int) -> np.ndarray:
    """``I(answers; f)`` for every action against ``ref`` from joint posterior samples."""
    f = post.sample(np.random.default_rng(seed), draws)  # draws x A
    p = ndtr((f - f[:, [ref]]) / (np.sqrt(2.0) * NOISE))
    both = np.stack([p, 1.0 - p], axis=-1)
    info = _h(both.mean(axis=0)) - _h(both).mean(axis=0)
    if post.ordinal is not None:
        t = np.concatenate([[-np.inf], post.ordinal.thresholds_for(post.kernel.variance), [np.inf]])
        probs = np.diff(ndtr((t[None, None, :] - f[:, :, None]) / post.ordinal.noise), axis=2)
        info = info + _h(probs.mean(axis=0)) - _h(probs).mean(axis=0)
    out: np.ndarray = info
    return out


@pytest.mark.parametrize("ordinal", [None, SCALE], ids=["preference", "preference+rating"])
def test_bald_matches_a_monte_carlo_mutual_information(
    small_space: Space, small_kernel: SquaredExponential, ordinal: Ordinal | None
) -> None:
    post = _posterior(small_space, small_kernel, ordinal)
    ref = 17
    actions = np.arange(len(small_space), dtype=np.intp)
    bald = information_against(post, actions, ref, np.asarray(post.mean), np.asarray(post.variance))
    mc = _monte_carlo(post, ref, 40_000, seed=1)
    # comparing the reference with itself tells nothing; rating it still does
    alone = (
        0.0
        if ordinal is None
        else rating_information(
            ordinal, small_kernel.variance, post.mean[[ref]], post.variance[[ref]]
        )[0]
    )
    assert bald[ref] == pytest.approx(alone, abs=1e-9) and mc[ref] == pytest.approx(alone, abs=0.01)
    # Houlsby's approximation of h(Phi) is within ~0.01 bits; MC error ~0.005 bits
    assert np.max(np.abs(bald - mc)) < 0.03, np.max(np.abs(bald - mc))
    assert np.ptp(mc) > 0.3  # the test has something to tell apart
    assert mc[int(np.argmax(bald))] > np.max(mc) - 0.03  # BALD's choice is (near) the best


def test_preference_information_against_exact_quadrature() -> None:
    for m, v in [(0.0, 0.01), (0.05, 0.01), (0.0, 1e-4), (0.03, 4e-4), (-0.1, 0.003)]:
        d = np.linspace(m - 10 * np.sqrt(v), m + 10 * np.sqrt(v), 100_001)
        pdf = np.exp(-((d - m) ** 2) / (2 * v)) / np.sqrt(2 * np.pi * v)
        z = d / (np.sqrt(2.0) * NOISE)
        cond = (entr(ndtr(z)) + entr(ndtr(-z))) / LN2
        zp = m / np.sqrt(2 * NOISE**2 + v)
        exact = (entr(ndtr(zp)) + entr(ndtr(-zp))) / LN2 - np.sum(cond * pdf) * (d[1] - d[0])
        assert preference_information(m, v, NOISE) == pytest.approx(exact, abs=0.005)
    # no uncertainty left: no information; the probit's own noise alone tells nothing
    assert preference_information(0.0, 0.0, NOISE) == pytest.approx(0.0, abs=1e-12)


def test_rating_information_against_exact_quadrature() -> None:
    sv = 0.005
    t = np.concatenate([[-np.inf], SCALE.thresholds_for(sv), [np.inf]])
    mus = np.array([0.0, 0.05, -0.1, 0.0, 0.0, 0.031, 0.2])
    variances = np.array([0.005, 0.003, 0.001, 1e-5, 0.02, 1e-9, 0.05])
    exact = []
    for m, v in zip(mus, variances, strict=True):
        f = np.linspace(m - 10 * np.sqrt(v), m + 10 * np.sqrt(v), 400_001)
        pdf = np.exp(-((f - m) ** 2) / (2 * v)) / np.sqrt(2 * np.pi * v)
        p = np.diff(ndtr((t[None, :] - f[:, None]) / SCALE.noise), axis=1)
        step = f[1] - f[0]
        exact.append(_h((p * pdf[:, None]).sum(0) * step) - np.sum(_h(p) * pdf) * step)
    got = rating_information(SCALE, sv, mus, variances)
    assert np.allclose(got, exact, atol=3e-4)
    assert got[4] > got[0] > got[3]  # more uncertain utilities: more to learn from a rating


def test_covariances_and_variances_match_the_dense_posterior(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    post = _posterior(small_space, small_kernel, SCALE, seed=3)
    cov = post.covariance()
    idx = np.array([0, 4, 11, 30], dtype=np.intp)
    assert np.allclose(covariance_with_reference(post, idx, 9), cov[idx, 9], atol=1e-12)
    assert np.allclose(variance_at(post, idx), np.diag(cov)[idx], atol=1e-12)


@settings(max_examples=40)
@given(
    n=st.integers(1, 4),
    buffer=st.lists(st.integers(0, 34), max_size=2, unique=True),
    region=st.lists(st.booleans(), min_size=35, max_size=35),
    rated=st.booleans(),
    seed=st.integers(0, 1000),
)
def test_never_outside_the_region_and_never_a_reference(
    n: int, buffer: list[int], region: list[bool], rated: bool, seed: int
) -> None:
    space = Space([Feature.linspace("a", 0, 1, 7), Feature.linspace("b", 0, 1, 5)])
    kernel = SquaredExponential((0.3, 0.4), 0.005, 1e-7)
    post = _posterior(space, kernel, SCALE if rated else None, seed)
    allowed = np.array(region)
    if not allowed.any():
        with pytest.raises(ValueError, match="allowed allows no action"):  # the context's check
            ask_context(post, n, tuple(buffer), seed, allowed)
        return
    picks = InformationGain().propose(ask_context(post, n, tuple(buffer), seed, allowed))
    assert len(picks) == n and all(allowed[a] for a in picks)
    fresh = [a for a in np.flatnonzero(allowed) if a not in buffer]
    if len(fresh) >= n:  # enough new allowed actions: no reference, no repeat
        assert len(set(picks)) == n and not set(picks) & set(buffer)


def test_large_grids_screen_candidates_and_respect_the_region() -> None:
    space = Space([Feature.linspace("a", 0, 1, 80), Feature.linspace("b", 0, 1, 60)])
    assert len(space) > 4096
    kernel = SquaredExponential(0.15, 0.005, 1e-7)
    rng = np.random.default_rng(4)
    corner = np.flatnonzero((space.points[:, 0] < 0.3) & (space.points[:, 1] < 0.3))
    w, l = rng.choice(corner, 60), rng.choice(corner, 60)
    post = PreferenceGP(space, kernel, NOISE, ordinal=SCALE).posterior(
        w[w != l], l[w != l], ratings=[(int(corner[0]), 2)]
    )
    allowed = space.points[:, 0] > 0.1  # a band is out of the region
    pool, mean, var = candidate_pool(post, np.flatnonzero(allowed), 32, np.random.default_rng(0))
    assert pool.size <= 64 and np.all(allowed[pool])
    assert np.allclose(mean, np.asarray(post.mean)[pool])
    assert np.allclose(var, np.asarray(post.variance)[pool], atol=1e-12)
    best = np.flatnonzero(allowed)[np.argmax(np.asarray(post.mean)[allowed])]
    assert best in pool  # the highest mean is a candidate
    assert np.max(var) > 0.99 * np.max(np.asarray(post.variance)[allowed])  # so is the widest
    picks = InformationGain(candidates=32).propose(ask_context(post, 3, (int(w[0]),), 0, allowed))
    assert len(set(picks)) == 3 and all(allowed[a] for a in picks)


def _corner_posterior(seed: int) -> tuple[Space, Posterior, int]:
    space = Space([Feature.linspace("a", 0, 1, 12), Feature.linspace("b", 0, 1, 12)])
    kernel = SquaredExponential(0.2, 0.01, 1e-7)
    rng = np.random.default_rng(seed)
    corner = np.flatnonzero((space.points[:, 0] <= 0.3) & (space.points[:, 1] <= 0.3))
    truth = -np.sum(space.points**2, axis=1)  # best in the corner
    a, b = rng.choice(corner, 40), rng.choice(corner, 40)
    keep = a != b
    w = np.where(truth[a] > truth[b], a, b)[keep]
    l = np.where(truth[a] > truth[b], b, a)[keep]
    post = PreferenceGP(space, kernel, NOISE).posterior(w, l)
    return space, post, int(corner[np.argmax(truth[corner])])


def test_after_data_in_one_corner_it_asks_away_from_it() -> None:
    far_ig: list[float] = []
    far_ss: list[float] = []
    var_ig: list[float] = []
    var_ss: list[float] = []
    widest = []
    for seed in range(12):
        space, post, best = _corner_posterior(seed)
        var = np.asarray(post.variance)
        widest.append(float(np.max(var)))
        for strategy, far, vs in (
            (InformationGain(), far_ig, var_ig),
            (SelfSparring(), far_ss, var_ss),
        ):
            (x,) = strategy.propose(ask_context(post, 1, (best,), seed))
            far.append(float(np.linalg.norm(space.points[x] - space.points[best])))
            vs.append(float(var[x]))
    assert np.mean(far_ig) > np.mean(far_ss) + 0.1, (np.mean(far_ig), np.mean(far_ss))
    assert np.mean(var_ig) > 0.99 * np.mean(widest) > np.mean(var_ss) + 0.001


def test_no_buffer_starts_at_the_largest_variance_or_most_informative_rating(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    plain = _posterior(small_space, small_kernel, None, seed=5)
    (x,) = InformationGain().propose(ask_context(plain, 1, (), 0))
    assert x == int(np.argmax(plain.variance))
    rated = _posterior(small_space, small_kernel, SCALE, seed=5)
    values = rating_information(SCALE, small_kernel.variance, rated.mean, rated.variance)
    first, second = InformationGain().propose(ask_context(rated, 2, (), 0))
    assert first == int(np.argmax(values)) and second != first
    prior = PreferenceGP(small_space, small_kernel, NOISE).prior()  # all tied: at random
    starts = {InformationGain().propose(ask_context(prior, 1, (), s))[0] for s in range(10)}
    assert len(starts) > 3


def _run(seed: int, strategy: str = "information-gain") -> list[tuple[int, ...]]:
    space = Space([Feature.linspace("a", 0, 1, 9), Feature.linspace("b", 0, 1, 7)])
    kernel = SquaredExponential(0.25, 0.005, 1e-7)
    loop = CoSpar(
        space,
        kernel,
        NOISE,
        n=1,
        buffer=1,
        seed=seed,
        ordinal=SCALE,
        strategy=make_strategy(strategy),
    )
    truth = np.sin(3 * space.points[:, 0]) * 0.1 - 0.05 * space.points[:, 1]
    cuts = np.quantile(truth, [0.25, 0.5, 0.75])
    proposals = []
    for _ in range(12):
        q = loop.ask()
        proposals.append(q.actions)
        answers: list[object] = [
            Rating(a, 1 + int(np.searchsorted(cuts, truth[a]))) for a in q.actions
        ]
        for a in q.actions:
            for b in q.buffer:
                if a != b:
                    answers.append(Comparison(a, b, "first" if truth[a] > truth[b] else "second"))
        loop.tell(q, answers)
    return proposals


def test_same_seed_same_proposals() -> None:
    assert _run(3) == _run(3)
    assert len({a for (a,) in _run(3)}) >= 10  # it explores rather than repeating


BASE = """
[space.x]
min = 0.0
max = 1.0
num = 11

[space.y]
min = 0.0
max = 1.0
num = 9

[model]
lengthscale = 0.2
signal_variance = 0.005
noise = 0.02

[cospar]
strategy = "information-gain"

[cospar.strategy_settings]
candidates = 16

[feedback.rating]
labels = ["very bad", "bad", "okay", "good"]

[safety]
avoid = ["very bad"]
lambda = 1.0
"""


def test_a_config_selecting_it_parses_and_its_loop_runs() -> None:
    cfg = parse_config(BASE)
    loop = cfg.make_loop()
    assert loop.strategy == InformationGain(candidates=16)
    assert "information-gain" in STRATEGIES
    for k in range(6):
        allowed = loop.allowed()
        q = loop.ask()
        assert allowed is None or all(allowed[a] for a in q.actions)
        answers: list[object] = [Rating(a, 1 if k % 2 else 4) for a in q.actions]
        answers += [Comparison(a, b, "first") for a in q.actions for b in q.buffer if a != b]
        loop.tell(q, answers)
    assert len(loop.executed) == 6 and len(loop.preferences) >= 4
    with pytest.raises(Exception, match="candidates"):
        parse_config(BASE.replace("candidates = 16", "candidates = 1"))


@pytest.mark.parametrize("bad", [1, 0, True, 2.5])
def test_bad_candidates_are_refused(bad: object) -> None:
    with pytest.raises(ValueError, match="candidates must be an integer >= 2"):
        InformationGain(candidates=bad)  # type: ignore[arg-type]


def _rating_accuracy(strategy: str, seed: int, trials: int = 30) -> float:
    """Share of gaits whose most likely predicted rating is their true category."""
    space = Space([Feature.linspace("a", 0, 1, 12), Feature.linspace("b", 0, 1, 12)])
    kernel = SquaredExponential(0.2, 0.005, 1e-6)
    rng = np.random.default_rng(seed)
    centres = rng.uniform(0, 1, (4, 2))
    truth = np.sum(
        rng.normal(0, 1, 4)[None, :]
        * np.exp(-np.sum((space.points[:, None, :] - centres[None]) ** 2, axis=2) / 0.08),
        axis=1,
    )
    cuts = np.quantile(truth, [0.25, 0.5, 0.75])
    category = 1 + np.searchsorted(cuts, truth, side="right")
    loop = CoSpar(
        space, kernel, NOISE, n=1, buffer=1, seed=seed, ordinal=Ordinal(4, noise=0.02),
        strategy=make_strategy(strategy),
    )  # fmt: skip
    for _ in range(trials):
        q = loop.ask()
        answers: list[object] = [Rating(a, int(category[a])) for a in q.actions]
        answers += [
            Comparison(a, b, "first" if truth[a] > truth[b] else "second")
            for a in q.actions
            for b in q.buffer
            if a != b
        ]
        loop.tell(q, answers)
    probs = loop.posterior.rating_probabilities(np.arange(len(space)))
    return float(np.mean(1 + np.argmax(probs, axis=1) == category))


def test_it_maps_the_ratings_better_than_self_sparring() -> None:
    """ROIAL's use of it: after 30 rated trials the predicted rating is right more often."""
    infogain = np.array([_rating_accuracy("information-gain", s) for s in range(4)])
    sparring = np.array([_rating_accuracy("self-sparring", s) for s in range(4)])
    assert np.all(infogain > sparring) and infogain.mean() > sparring.mean() + 0.07
