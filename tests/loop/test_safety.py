"""The region of avoidance and unsafe flags (``loop/safety.py``): no strategy ever proposes an
avoided gait or one near a flagged gait, and an empty region of interest proposes nothing."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray
from scipy.special import ndtr

from gaitpref import CoSpar, Feature, Space, SquaredExponential
from gaitpref.errors import NoSafeGaitError
from gaitpref.feedback import Comparison, Rating
from gaitpref.loop import Safety
from gaitpref.loop.safety import near
from gaitpref.model.ordinal import Ordinal
from gaitpref.pointset import PointSet
from gaitpref.strategies import STRATEGIES, make_strategy

SPACE = Space(
    [
        Feature.linspace("length", 0.08, 0.18, 9, unit="m"),
        Feature.linspace("duration", 0.85, 1.15, 7, unit="s"),
    ]
)
KERNEL = SquaredExponential(lengthscale=(0.03, 0.08), variance=0.005, jitter=1e-7)
SCALE = Ordinal(["very bad", "bad", "okay", "good"], noise=0.02)


def _loop(strategy: str, n: int, buffer: int, safety: Safety, seed: int) -> CoSpar:
    return CoSpar(
        SPACE,
        KERNEL,
        0.02,
        n=n,
        buffer=buffer,
        seed=seed,
        strategy=make_strategy(strategy),
        ordinal=SCALE,
        safety=safety,
    )


@settings(max_examples=25)
@given(
    strategy=st.sampled_from(STRATEGIES),
    n=st.integers(1, 3),
    buffer=st.integers(0, 2),
    lam=st.floats(0.0, 2.0),
    risk=st.one_of(st.none(), st.sampled_from([0.3, 0.35, 0.5, 0.8])),
    cautious=st.one_of(st.none(), st.sampled_from([0.3, 0.6, 0.9])),
    radius=st.sampled_from([0.0, 0.1, 0.3]),
    seed=st.integers(0, 10_000),
    flags=st.lists(st.integers(0, len(SPACE) - 1), max_size=3),
    start=st.lists(st.integers(0, len(SPACE) - 1), max_size=3, unique=True),
    reach=st.one_of(st.none(), st.sampled_from([0.5, 1.0, 2.0])),
    frontier=st.one_of(st.none(), st.sampled_from([0.5, 0.9, 1.0])),
)
def test_no_strategy_proposes_an_avoided_or_flagged_gait(
    strategy: str,
    n: int,
    buffer: int,
    lam: float,
    risk: float | None,
    cautious: float | None,
    radius: float,
    seed: int,
    flags: list[int],
    start: list[int],
    reach: float | None,
    frontier: float | None,
) -> None:
    cautious = cautious if risk is not None else None
    if frontier is not None and cautious is not None and frontier <= cautious:
        frontier = None  # refused: nothing would be left to explore (test_safety_cautious.py)
    safety = Safety(
        avoid=1,
        lam=lam,
        unsafe_radius=radius,
        risk=risk,
        cautious=cautious,
        start=tuple(start),
        reach=reach,
        frontier=frontier,
    )
    loop = _loop(strategy, n, buffer, safety, seed)
    for a in flags:
        loop.flag_unsafe(a)
    rng = np.random.default_rng(seed)
    truth = rng.normal(0, 0.07, len(SPACE))
    for _ in range(6):
        allowed = loop.allowed()
        if allowed is not None and not allowed.any():
            with pytest.raises(NoSafeGaitError):
                loop.ask()
            return
        banned = near(SPACE, loop.unsafe, radius) if loop.unsafe else np.zeros(len(SPACE), bool)
        avoided = _avoided(loop, lam, risk, cautious, banned, safety.start, reach, frontier)
        done = loop.executed
        first = [a for a in start if a not in done and not (banned | avoided)[a]]
        q = loop.ask()
        if len(done) < len(start):  # the declared-safe gaits first, unless flagged or avoided
            assert q.actions[: min(n, len(first))] == tuple(first[:n])
        for a in q.actions:
            assert not banned[a], f"{strategy} proposed {a}, near an unsafe flag"
            assert not avoided[a], f"{strategy} proposed {a}, in the region of avoidance"
        answers: list[object] = [Rating(a, 1 if truth[a] < -0.05 else 3) for a in set(q.actions)]
        seen: set[frozenset[int]] = set()
        for a in q.actions:
            for b in q.buffer:
                if a != b and frozenset((a, b)) not in seen:
                    seen.add(frozenset((a, b)))
                    answers.append(Comparison(a, b, "first" if truth[a] > truth[b] else "second"))
        loop.tell(q, answers)


def _avoided(
    loop: CoSpar,
    lam: float,
    risk: float | None,
    cautious: float | None = None,
    banned: NDArray[np.bool_] | None = None,
    start: tuple[int, ...] = (),
    reach: float | None = None,
    frontier: float | None = None,
) -> NDArray[np.bool_]:
    """The region of avoidance, written out: ROIAL's bound or the probability of a "very bad"
    rating, with the posterior's thresholds; with ``cautious``, while a gait away from the
    ``banned`` ones is known-safe (by its ratings, or in ``start`` and under ``risk``), every
    gait neither known-safe nor possibly better than all of them (and, with ``reach``, within
    ``reach`` lengthscales of one of them, and with ``frontier``, with ``p`` at most
    ``frontier`` times an unrated gait's)."""
    post = loop.posterior
    scale = post.ordinal if post.ordinal is not None else SCALE
    t1 = scale.thresholds_for(KERNEL.variance)[0]
    mean, var = np.asarray(post.mean), np.asarray(post.variance)
    if risk is None:
        out: NDArray[np.bool_] = mean + lam * np.sqrt(var) < t1
        return out
    p = ndtr((t1 - mean) / np.sqrt(scale.noise**2 + var))
    if cautious is not None:
        unrated = ndtr(t1 / np.sqrt(scale.noise**2 + KERNEL.variance + KERNEL.jitter))
        known = p <= min(cautious * unrated, risk)
        known[list(start)] |= p[list(start)] <= risk
        pool = known & ~(np.zeros_like(known) if banned is None else banned)
        if pool.any():  # unexplored gaits only if mu + sd (explore = 1) beats every pool gait's
            upper = mean + np.sqrt(var)
            better = (p <= risk) & (upper > upper[pool].max())
            if reach is not None:
                scaled = SPACE.points / np.array([0.03, 0.08])  # KERNEL's lengthscales
                d = np.linalg.norm(scaled[:, None, :] - scaled[None, pool, :], axis=2)
                better &= d.min(axis=1) <= reach
            if frontier is not None:
                better &= p <= frontier * unrated
            return np.asarray(~(known | better))
    return np.asarray(p > risk)


def test_rating_everything_worst_empties_the_region_and_nothing_is_proposed() -> None:
    loop = _loop("self-sparring", 1, 1, Safety(avoid=1, lam=0.0), 0)
    for _ in range(40):
        q = loop.ask()
        loop.tell(q, [Rating(q.actions[0], "very bad")])
        allowed = loop.allowed()
        if allowed is not None and not allowed.any():
            break
    else:
        pytest.fail("the region of interest never emptied")
    before = loop.rng.bit_generator.state
    with pytest.raises(NoSafeGaitError, match="nothing was proposed"):
        loop.ask()
    assert loop.pending is None and loop.rng.bit_generator.state == before


def test_unsafe_radius_and_unflag() -> None:
    loop = _loop("eubo", 1, 1, Safety(unsafe_radius=0.25), 1)
    loop.flag_unsafe(31)
    banned = near(SPACE, {31}, 0.25)
    assert banned[31] and banned.sum() > 1 and not banned.all()
    allowed = loop.allowed()
    assert allowed is not None and np.array_equal(allowed, ~banned)
    loop.unflag_unsafe(31)
    assert loop.allowed() is None


def test_near_scales_by_the_features_ranges_not_the_points_present() -> None:
    """On a point set the radius is the same fraction of each feature's range as on the grid,
    however little of the range the points present span."""
    pts = PointSet(SPACE, [[0.10, 1.0], [0.12, 1.0], [0.10, 1.06], [0.13, 1.0]])
    banned = near(pts, [0], 0.25)
    span = np.array([0.10, 0.30])  # dense reference: each feature divided by its declared range
    d = np.sqrt((((pts.points - pts.points[0]) / span) ** 2).sum(axis=1))
    assert np.array_equal(banned, d <= 0.25)
    assert banned.tolist() == [True, True, True, False]


def test_bad_safety_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="rating scale"):
        CoSpar(SPACE, KERNEL, 0.02, safety=Safety(avoid=1))
    with pytest.raises(ValueError, match="leaves nothing"):
        CoSpar(SPACE, KERNEL, 0.02, ordinal=SCALE, safety=Safety(avoid=4))
    with pytest.raises(ValueError, match="unsafe_radius"):
        Safety(unsafe_radius=2.0)


def test_a_flag_is_described_as_what_it_removes() -> None:
    """The terminal and the CLI said "its gait and its neighbours" with no radius."""
    assert Safety().flag_effect() == "its gait will not be proposed again"
    assert Safety(unsafe_radius=0.25).flag_effect() == (
        "its gait and the gaits within unsafe_radius = 0.25 of it will not be proposed again"
    )


def test_a_flag_without_a_radius_on_a_continuous_feature_says_close_gaits_may_come() -> None:
    """On a continuous feature "its gait will not be proposed again" held for that point alone:
    the line path proposed a gait 0.04 of the ranges from it at the next trial."""
    said = Safety().flag_effect(continuous=True)
    assert said.startswith("its gait will not be proposed again, but gaits however close")
    assert "[safety] unsafe_radius" in said
    assert Safety(unsafe_radius=0.1).flag_effect(continuous=True) == (
        Safety(unsafe_radius=0.1).flag_effect()
    )
