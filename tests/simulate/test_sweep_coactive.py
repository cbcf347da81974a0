"""The paper's simulated coactive feedback against hand-computed cases (edges included)."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref.config import load_config
from gaitpref.loop.cospar import Query
from gaitpref.simulate.users import GradientCoactive, SimulatedUser
from gaitpref.space import Feature, Move, Space

# A 4 x 5 grid on [0, 1]^2 with f[i, j] = i^2 + g[j].  By hand (numpy.gradient: one-sided at the
# edges, central inside, in grid-index units):
#   d/di: rows 0..3 -> 1, (4-0)/2 = 2, (9-1)/2 = 4, 9-4 = 5
#   d/dj: g = 0, 3, 3, 1, -4 -> 3, (3-0)/2 = 1.5, (1-3)/2 = -1, (-4-3)/2 = -3.5, -4-1 = -5
# Percentiles of |gradient| over the 20 points (linear interpolation, position p (20 - 1)):
#   x: 1,2,4,5 five times each -> 50th (pos 9.5) = (2+4)/2 = 3, 75th (pos 14.25) = 4.25
#   y: 1,1.5,3,3.5,5 four times each -> 50th (pos 9.5) = 3, 75th (pos 14.25) = 3.5 (both
#   sorted[14] and sorted[15] are 3.5)
# Moves: small 0.3, big 0.6 of the range; x values k/3, y values k/4.
G = np.array([0.0, 3.0, 3.0, 1.0, -4.0])


def small_space() -> Space:
    return Space(
        [
            Feature.linspace("x", 0, 1, 4, coactive=(0.3, 0.6)),
            Feature.linspace("y", 0, 1, 5, coactive=(0.3, 0.6)),
        ]
    )


def objective() -> np.ndarray:
    out: np.ndarray = np.arange(4.0)[:, None] ** 2 + G[None, :]
    return out


def flat(i: int, j: int) -> int:
    return 5 * i + j


def test_gradient_and_thresholds_by_hand() -> None:
    c = GradientCoactive(small_space(), objective())
    gx = c.gradient[:, 0].reshape(4, 5)
    gy = c.gradient[:, 1].reshape(4, 5)
    np.testing.assert_allclose(gx, np.repeat([[1.0], [2.0], [4.0], [5.0]], 5, axis=1))
    np.testing.assert_allclose(gy, np.tile([3.0, 1.5, -1.0, -3.5, -5.0], (4, 1)))
    np.testing.assert_allclose(c.thresholds, [[3.0, 3.0], [4.25, 3.5]])


@pytest.mark.parametrize(
    ("point", "expected"),
    [
        # y dominates (|-5| > 1), above its 75th: big move down: 1 - 0.6 = 0.4 -> 0.5 (j = 2)
        ((0, 4), ((0, 2), "y", "-big")),
        # y dominates (3.5 > 2), above its 50th, equal to (not above) its 75th: small down,
        # 0.75 - 0.3 = 0.45 -> 0.5
        ((1, 3), ((1, 2), "y", "-small")),
        # x dominates (4 > 1), between 3 and 4.25: small up: 2/3 + 0.3 -> 1 (i = 3)
        ((2, 2), ((3, 2), "x", "+small")),
        # x dominates (2 > 1.5) but is not above its own 50th percentile (3): no feedback
        ((1, 1), None),
        # x dominates (5 > 3.5), big move up from the last row clips back: no feedback
        ((3, 3), None),
    ],
)
def test_suggestions_by_hand(
    point: tuple[int, int], expected: tuple[tuple[int, int], str, Move] | None
) -> None:
    c = GradientCoactive(small_space(), objective())
    s = c.suggest(flat(*point))
    if expected is None:
        assert s is None
        return
    (ti, tj), feature, move = expected
    assert s is not None
    assert (s.action, s.feature, s.move) == (flat(*point), feature, move)
    assert small_space().coactive_move(s.action, s.feature, s.move) == flat(ti, tj)


def test_minimize_flips_the_direction() -> None:
    c = GradientCoactive(small_space(), objective(), minimize=True)
    s = c.suggest(flat(1, 3))  # gradient of -f: (-2, 3.5): small move up, 0.75 + 0.3 -> 1
    assert s is not None and (s.feature, s.move) == ("y", "+small")
    assert small_space().coactive_move(s.action, s.feature, s.move) == flat(1, 4)


def test_synthetic_2d_moves_are_two_and_three_cells_and_clip_at_edges() -> None:
    space = load_config("synthetic-2d").space
    i = np.ravel_multi_index((10, 10), space.shape)
    assert space.coactive_move(int(i), "x", "+small") == i + 2 * 30
    assert space.coactive_move(int(i), "x", "-big") == i - 3 * 30
    assert space.coactive_move(int(i), "y", "+big") == i + 3
    edge = int(np.ravel_multi_index((28, 0), space.shape))
    assert space.coactive_move(edge, "x", "+big") == edge + 30  # clipped to the last row
    assert space.coactive_move(edge, "y", "-small") is None  # clips back onto itself


def test_user_compares_each_pair_once_when_a_query_repeats_an_action() -> None:
    space = small_space()
    user = SimulatedUser(space, objective(), np.random.default_rng(0))
    comps = user.answer(Query(1, (3, 7, 3), ()))
    assert [(c.first, c.second) for c in comps] == [(3, 7)]
    assert comps[0].outcome == (
        "first" if objective().ravel()[3] > objective().ravel()[7] else "second"
    )
