"""The line path draws another line when no point of one may be proposed, and raises
NoSafeGaitError, naming the lines tried, only when none of ``LINE_DRAWS`` has such a point."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import NDArray

from gaitpref import Feature, Space, SquaredExponential
from gaitpref.errors import NoSafeGaitError
from gaitpref.loop.line import LineCoSpar
from gaitpref.loop.lines import LINE_DRAWS, Line, LineSettings, redraw_rule
from gaitpref.loop.safety import Safety
from gaitpref.pointset import PointSet

KERNEL = SquaredExponential(0.3, 1.0, 1e-6)
SEGMENT = Space([Feature.interval("x", 0.0, 1.0)])
UNIT = Space([Feature.interval("x", 0.0, 1.0), Feature.interval("y", 0.0, 1.0)])


def _loop(domain: Space, **settings: object) -> LineCoSpar:
    return LineCoSpar(domain, KERNEL, 0.05, n=1, buffer=1, seed=6, **settings)  # type: ignore[arg-type]


def _one_trial(loop: LineCoSpar) -> int:
    q = loop.ask()
    loop.tell(q, [])
    return q.actions[0]


def test_the_redraws_follow_the_rule_then_random_directions_then_random_points() -> None:
    rules = [redraw_rule(LineSettings(10, "coordinate"), d) for d in range(LINE_DRAWS)]
    assert rules[0] == (LineSettings(10, "coordinate"), True)
    assert [r.direction for r, _ in rules] == ["coordinate"] * 4 + ["random"] * 8
    assert [best for _, best in rules] == [True] * 8 + [False] * 4


def test_avoiding_the_whole_space_raises_naming_the_lines_tried() -> None:
    loop = _loop(SEGMENT)
    a = _one_trial(loop)
    loop.avoid(a, 1.0)  # the whole segment
    state = loop.rng.bit_generator.state
    with pytest.raises(NoSafeGaitError, match=f"any of the {LINE_DRAWS} lines tried .*avoided"):
        loop.ask()
    assert loop.rng.bit_generator.state == state and loop.pending is None  # nothing moved


def test_an_unsafe_flag_over_the_whole_space_raises_naming_the_lines_tried() -> None:
    loop = _loop(SEGMENT, safety=Safety(unsafe_radius=1.0))
    loop.flag_unsafe(_one_trial(loop))  # the whole segment
    with pytest.raises(NoSafeGaitError, match=r"lines tried .*flagged unsafe \(1 flagged\)"):
        loop.ask()


@pytest.mark.parametrize(("seed", "covered"), [(5, 4), (6, 1)])
def test_a_line_with_every_point_avoided_is_drawn_again_from_the_generator(
    seed: int, covered: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Coordinate lines through the one trial's point ``a``, avoided with a radius that covers
    the whole line along one axis but not along the other: the ask draws lines until one has
    a point that may be proposed (after 4 covered ones, a random direction), the same in a loop
    with the same seed and history (what replay relies on)."""
    drawn: list[tuple[int, bool]] = []  # (seed, covered) of each line drawn
    on_line = LineCoSpar._on_line

    def watched(self: LineCoSpar, line: Line) -> tuple[PointSet, NDArray[np.bool_]]:
        space, allowed = on_line(self, line)
        drawn.append((line.seed, not allowed.any()))
        return space, allowed

    monkeypatch.setattr(LineCoSpar, "_on_line", watched)
    queries = []
    for _ in range(2):
        loop = LineCoSpar(
            UNIT, KERNEL, 0.05, n=1, buffer=1, seed=seed, line=LineSettings(20, "coordinate")
        )
        a = _one_trial(loop)
        x, y = loop.space.points[a]
        radius = float(min(max(x, 1 - x), max(y, 1 - y)))
        loop.avoid(a, radius)
        drawn.clear()
        q = loop.ask()
        assert [c for _, c in drawn] == [True] * covered + [False]
        assert q.line is not None and q.line.seed == drawn[-1][0]
        for p in q.points:
            assert np.hypot(p[0] - x, p[1] - y) > radius
        queries.append(q)
    a_query, b_query = queries
    assert a_query.points == b_query.points
    assert a_query.line is not None and b_query.line is not None
    np.testing.assert_array_equal(a_query.line.points, b_query.line.points)


def test_a_line_with_fewer_points_than_n_is_drawn_again() -> None:
    """On a small discrete domain a line snaps to few grid points (through a corner: one); with
    n = 2 the strategy's context refused such a line and the ask failed (123 of 200 seeds on a
    2 x 2 grid within three asks): another line is drawn instead."""
    domain = Space([Feature("a", [0.0, 1.0]), Feature("b", [0.0, 1.0])])
    kernel = SquaredExponential(0.3, 1.0, 1e-6)
    for seed in range(40):
        loop = LineCoSpar(domain, kernel, 0.1, n=2, seed=seed)
        for _ in range(3):
            q = loop.ask()
            assert len(q.actions) == 2
            first, second = q.actions
            loop.tell(q, [(first, second, "first")] if first != second else [])
    with pytest.raises(ValueError, match="none of the 12 lines tried holds n = 4 points"):
        LineCoSpar(domain, kernel, 0.1, n=4).ask()  # no line covers the four corners
    with pytest.raises(ValueError, match="must be at most the grid's size, 4, got 5"):
        LineCoSpar(domain, kernel, 0.1, n=5)
