"""The region's cautious level (``[safety] cautious``, ``loop/safety.py``): while some gait is
known-safe (its probability of an avoided rating at most ``cautious`` times an unrated gait's),
only known-safe gaits are proposed; when none is, the single-level ``risk`` rule applies."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import NDArray
from scipy.special import ndtr

from gaitpref import CoSpar, Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.errors import NoSafeGaitError
from gaitpref.feedback import Rating
from gaitpref.loop import Safety
from gaitpref.loop.line import LineCoSpar, on_points
from gaitpref.loop.lines import LineSettings
from gaitpref.model.ordinal import Ordinal
from gaitpref.model.posterior import Posterior

SPACE = Space([Feature.linspace("x", 0.0, 1.0, 41)])
KERNEL = SquaredExponential(lengthscale=0.1, variance=1e-4, jitter=1e-8)
LABELS = ["very bad", "bad", "okay", "good"]
SCALE = Ordinal(LABELS, noise=0.01)  # as the model noise: the default
SHARP = Ordinal(LABELS, noise=0.005)  # a subject whose ratings are worth more
CAUTIOUS = Safety(avoid=1, risk=0.35, cautious=0.6)
SINGLE = Safety(avoid=1, risk=0.35)


def _rated(ratings: list[tuple[int, str]], scale: Ordinal = SCALE) -> Posterior:
    return PreferenceGP(SPACE, KERNEL, 0.01, ordinal=scale).posterior([], [], ratings=ratings)


def _allowed(safety: Safety, post: Posterior, **kw: object) -> NDArray[np.bool_]:
    allowed = safety.allowed(post, post.ordinal, (), **kw)  # type: ignore[arg-type]
    assert allowed is not None
    return allowed


def _p_worst(post: Posterior) -> NDArray[np.float64]:
    assert post.ordinal is not None
    t1 = post.ordinal.thresholds_for(KERNEL.variance)[0]
    var = np.asarray(post.variance)
    return np.asarray(ndtr((t1 - np.asarray(post.mean)) / np.sqrt(post.ordinal.noise**2 + var)))


def test_one_good_rating_allows_its_neighbours_and_not_the_far_unrated_gaits() -> None:
    for scale in (SCALE, SHARP):
        post = _rated([(20, "good")], scale)
        allowed = _allowed(CAUTIOUS, post)
        idx = np.flatnonzero(allowed)  # one interval around the rated gait
        assert np.array_equal(idx, np.arange(idx[0], idx[-1] + 1)) and idx[0] < 20 < idx[-1]
        assert 3 <= idx.size < 20 and not allowed[[0, 5, 35, 40]].any()
        assert _allowed(SINGLE, post).all()  # the single-level rule lets every gait through
        # known-safe: an avoided rating at most 0.6 times as likely as at a gait with no data
        p = _p_worst(post)
        np.testing.assert_array_equal(allowed, p <= 0.6 * p[0])
        assert p[0] == pytest.approx(0.25, abs=0.01)  # far from the rating: the prior's quarter


def test_unexplored_gaits_stay_allowed_while_they_might_beat_every_known_safe_one() -> None:
    post = _rated([(20, "okay")], SHARP)  # known-safe, but only "okay"
    p = _p_worst(post)
    known = p <= 0.6 * p[0]
    assert known[[19, 20, 21]].all() and not known[[0, 5, 35, 40]].any()
    upper = np.asarray(post.mean) + np.asarray(post.std)
    assert upper[0] > upper[known].max()  # an unrated gait's mu + sd beats the okay gait's
    assert _allowed(CAUTIOUS, post).all()
    strict = Safety(avoid=1, risk=0.35, cautious=0.6, explore=0.0)  # the means alone
    assert np.array_equal(_allowed(strict, post), known)
    # after a "good" rating no unrated gait's bound reaches the good gait's (test above); with
    # a "very bad" rating elsewhere besides, its neighbourhood stays out too
    post = _rated([(20, "good"), (5, "very bad")])
    allowed = _allowed(Safety(avoid=1, risk=0.35, cautious=0.6, explore=2.0), post)
    assert allowed[20] and not allowed[[0, 5, 10, 40]].any()


def test_with_nothing_known_safe_the_risk_rule_decides() -> None:
    # "okay" at the default rating noise leaves the gait near the prior's 0.25: not known-safe
    okay = _rated([(20, "okay")])
    assert np.array_equal(_allowed(CAUTIOUS, okay), _allowed(SINGLE, okay))
    # only "very bad" ratings: nothing is known-safe, the fallback avoids the rated gaits alone
    worst = _rated([(3, "very bad"), (4, "very bad"), (30, "very bad")])
    fallback = _allowed(CAUTIOUS, worst)
    assert np.array_equal(fallback, _allowed(SINGLE, worst))
    assert not fallback[[3, 4, 30]].any() and fallback[[15, 20, 40]].all()


def test_known_safe_gaits_the_loop_may_not_propose_do_not_count() -> None:
    post = _rated([(20, "good")])
    safe = _allowed(CAUTIOUS, post)
    elsewhere = ~safe  # e.g. a line's points, or gaits that cannot be made: none known-safe
    assert np.array_equal(_allowed(CAUTIOUS, post, within=elsewhere), _allowed(SINGLE, post))
    flagged = CAUTIOUS.allowed(post, SCALE, np.flatnonzero(safe).tolist())
    assert flagged is not None and np.array_equal(flagged, _allowed(SINGLE, post) & elsewhere)


def test_the_loop_stays_among_known_safe_gaits_and_an_empty_region_proposes_nothing() -> None:
    loop = CoSpar(SPACE, KERNEL, 0.01, n=1, buffer=1, seed=3, ordinal=SCALE, safety=CAUTIOUS)
    q = loop.ask()
    loop.tell(q, [Rating(q.actions[0], "good")])
    known = _allowed(CAUTIOUS, loop.posterior)
    allowed = loop.allowed()
    assert not known.all() and allowed is not None and np.array_equal(allowed, known)
    for _ in range(5):
        q = loop.ask()
        assert known[q.actions[0]]
        loop.tell(q, [Rating(q.actions[0], "good")])
        known = _allowed(CAUTIOUS, loop.posterior)
    loop = CoSpar(SPACE, KERNEL, 0.01, n=1, buffer=1, seed=3, ordinal=SCALE, safety=CAUTIOUS)
    for _ in range(200):
        allowed = loop.allowed()
        if allowed is not None and not allowed.any():
            break
        q = loop.ask()
        loop.tell(q, [Rating(q.actions[0], "very bad")])
    else:
        pytest.fail("the region of interest never emptied")
    with pytest.raises(NoSafeGaitError, match="nothing was proposed"):
        loop.ask()
    assert loop.pending is None


def test_bad_cautious_levels_are_refused() -> None:
    with pytest.raises(ValueError, match="cautious needs the risk rule"):
        Safety(avoid=1, lam=1.0, cautious=0.5)
    for bad in (0.0, 1.0, float("nan")):
        with pytest.raises(ValueError, match="cautious must be a fraction"):
            Safety(avoid=1, risk=0.35, cautious=bad)
    with pytest.raises(ValueError, match="explore must be a finite number >= 0"):
        Safety(avoid=1, risk=0.35, cautious=0.5, explore=-1.0)


def test_the_line_path_proposes_only_what_the_cautious_rule_allows_on_its_line() -> None:
    domain = Space([Feature.interval("x", 0.0, 1.0), Feature.interval("y", 0.0, 1.0)])
    kernel = SquaredExponential(0.2, 1e-4, 1e-8)
    loop = LineCoSpar(
        domain, kernel, 0.01, n=1, buffer=1, seed=4, ordinal=SCALE, safety=CAUTIOUS,
        line=LineSettings(40),
    )  # fmt: skip
    restricted = 0
    for trial in range(8):
        q = loop.ask()
        assert q.line is not None
        space, line_ids = loop.space.extended(q.line.points)
        on_line = np.zeros(len(space), dtype=bool)
        on_line[line_ids] = True
        post = on_points(loop.posterior, space)
        allowed = CAUTIOUS.allowed(post, SCALE, (), on_line)
        assert allowed is not None
        chosen = space.find(list(q.points[0]))
        assert chosen is not None and allowed[chosen] and on_line[chosen]
        restricted += int(not allowed[line_ids].all())
        loop.tell(q, [Rating(q.actions[0], "good" if trial % 3 else "okay")])
    assert restricted  # the cautious level did leave some of a line's points out


def test_a_declared_start_gait_is_known_safe_until_its_ratings_say_otherwise() -> None:
    declared = Safety(avoid=1, risk=0.35, cautious=0.6, start=(20,))
    prior = PreferenceGP(SPACE, KERNEL, 0.01, ordinal=SCALE).prior()
    known = declared.known_safe(prior, SCALE)
    assert known is not None and np.flatnonzero(known).tolist() == [20]
    # before any rating only the start gait: no unrated gait's mu + sd beats its own
    assert np.flatnonzero(_allowed(declared, prior)).tolist() == [20]
    assert _allowed(CAUTIOUS, prior).all()  # undeclared: the risk rule lets every gait through
    # one "okay" (not known-safe by the ratings alone: test above) keeps it known-safe
    okay = _rated([(20, "okay")])
    assert CAUTIOUS.known_safe(okay, SCALE) is not None
    assert not CAUTIOUS.known_safe(okay, SCALE)[20]  # type: ignore[index]
    assert declared.known_safe(okay, SCALE)[20]  # type: ignore[index]
    # rated "very bad" until the risk rule avoids it: no longer known-safe, nor proposed
    worst = _rated([(20, "very bad"), (20, "very bad")])
    assert not _allowed(SINGLE, worst)[20]
    assert not declared.known_safe(worst, SCALE)[20]  # type: ignore[index]
    assert not _allowed(declared, worst)[20]
    assert Safety(avoid=1, risk=0.35).known_safe(okay, SCALE) is None  # no cautious level


def test_reach_keeps_unexplored_gaits_near_the_known_safe_ones() -> None:
    okay = _rated([(20, "okay")], SHARP)  # the unexplored gaits' mu + sd beat it: all allowed
    assert _allowed(Safety(avoid=1, risk=0.35, cautious=0.6, start=(20,)), okay).all()
    near_start = Safety(avoid=1, risk=0.35, cautious=0.6, start=(20,), reach=1.0)
    allowed = np.flatnonzero(_allowed(near_start, okay))
    known = near_start.known_safe(okay, SCALE)
    assert known is not None
    # within one lengthscale (0.1: 4 grid steps of 0.025) of a known-safe gait
    lo, hi = np.flatnonzero(known)[[0, -1]]
    assert allowed.tolist() == list(range(lo - 4, hi + 5))
    with pytest.raises(ValueError, match="reach"):
        Safety(avoid=1, risk=0.35, cautious=0.6, reach=-1.0)


def test_frontier_keeps_unexplored_gaits_where_the_ratings_speak_for_them() -> None:
    okay = _rated([(20, "okay")], SHARP)  # the unexplored gaits' mu + sd beat it: all allowed
    assert _allowed(Safety(avoid=1, risk=0.35, cautious=0.6, start=(20,)), okay).all()
    frontier = Safety(avoid=1, risk=0.35, cautious=0.6, start=(20,), frontier=0.9)
    allowed = _allowed(frontier, okay)
    p = _p_worst(okay)
    t1 = SHARP.thresholds_for(KERNEL.variance)[0]
    unrated = float(ndtr(t1 / np.sqrt(SHARP.noise**2 + KERNEL.variance + KERNEL.jitter)))
    # the declared gait, and the others only where the rating lowered P("very bad") below
    # 0.9 x an unrated gait's (about 0.25: far from the rating)
    expected = p <= 0.9 * unrated
    expected[20] = True
    np.testing.assert_array_equal(allowed, expected)
    idx = np.flatnonzero(allowed)  # one interval around the rated gait, far gaits left out
    assert np.array_equal(idx, np.arange(idx[0], idx[-1] + 1)) and idx[0] < 20 < idx[-1]
    assert not allowed[[0, 5, 35, 40]].any()
    # every gait it allows the setting without it allows too (it only narrows)
    loose = _allowed(Safety(avoid=1, risk=0.35, cautious=0.6, start=(20,), reach=1.0), okay)
    both = Safety(avoid=1, risk=0.35, cautious=0.6, start=(20,), reach=1.0, frontier=0.9)
    assert not (_allowed(both, okay) & ~loose).any() and not (_allowed(both, okay) & ~allowed).any()
    for bad in (0.0, 1.5, float("nan"), 0.6, 0.5):  # at or under cautious: nothing to explore
        with pytest.raises(ValueError, match="frontier"):
            Safety(avoid=1, risk=0.35, cautious=0.6, frontier=bad)


def test_the_loop_walks_the_start_gaits_first() -> None:
    safety = Safety(avoid=1, risk=0.35, cautious=0.6, start=(30, 7))
    loop = CoSpar(SPACE, KERNEL, 0.01, n=1, buffer=1, seed=3, ordinal=SCALE, safety=safety)
    walked = []
    for _ in range(3):
        q = loop.ask()
        walked.append(q.actions[0])
        loop.tell(q, [Rating(q.actions[0], "okay")])
    assert walked[:2] == [30, 7] and walked[2] not in (30, 7)
    loop.undo()
    loop.undo()
    assert loop.ask().actions == (7,)  # undone: the start gait again
    # n = 2: the start gait and the strategy's choice, compared with it as with the buffer
    pair = CoSpar(SPACE, KERNEL, 0.01, n=2, buffer=0, seed=3, ordinal=SCALE, safety=safety)
    q = pair.ask()
    assert q.actions == (30, 7)
    pair.tell(q, [Rating(30, "good"), Rating(7, "good")])
    one = CoSpar(SPACE, KERNEL, 0.01, n=2, seed=3, ordinal=SCALE, safety=Safety(start=(12,)))
    q = one.ask()
    assert q.actions[0] == 12 and q.actions[1] != 12
    # a flagged start gait is skipped
    flagged = CoSpar(SPACE, KERNEL, 0.01, n=1, buffer=1, seed=3, ordinal=SCALE, safety=safety)
    flagged.flag_unsafe(30)
    assert flagged.ask().actions == (7,)
    with pytest.raises(IndexError):
        CoSpar(SPACE, KERNEL, 0.01, safety=Safety(start=(41,)))
    with pytest.raises(ValueError, match="line path"):
        LineCoSpar(SPACE, KERNEL, 0.01, ordinal=SCALE, safety=safety, line=LineSettings(5))
