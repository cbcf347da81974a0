"""The line path (issue 13): point sets, lines, and LineCoSpar against the full grid."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import CoSpar, Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.loop.learning import Learning
from gaitpref.loop.line import LineCoSpar, on_points
from gaitpref.loop.lines import LineSettings, draw_line, line_points
from gaitpref.pointset import PointSet, empty_points
from gaitpref.strategies import STRATEGIES, make_strategy

KERNEL = SquaredExponential((0.3, 0.5, 0.4), 1.0, 1e-6)


@pytest.fixture
def grid() -> Space:
    return Space(
        [
            Feature.linspace("a", 0.0, 1.0, 4),
            Feature.linspace("b", 0.0, 2.0, 3),
            Feature.linspace("c", -1.0, 1.0, 5),
        ]
    )


def _grid_data(grid: Space) -> tuple[np.ndarray, np.ndarray]:
    """A full-grid loop's preferences (winners, losers) on the grid's indices."""
    utility = -np.sum((grid.points - np.array([0.7, 1.2, 0.2])) ** 2, axis=1)
    loop = CoSpar(grid, KERNEL, 0.05, n=1, buffer=1, seed=4)
    for _ in range(14):
        q = loop.ask()
        a = q.actions[0]
        comps = [(a, b, "first" if utility[a] > utility[b] else "second") for b in q.buffer]
        loop.tell(q, [c for c in comps if c[0] != c[1]], [(a, "a", "+small")])
    winners = np.array([p.winner for p in loop.preferences])
    losers = np.array([p.loser for p in loop.preferences])
    return winners, losers


def test_lines_through_every_grid_point_give_the_full_grid_posterior(grid: Space) -> None:
    winners, losers = _grid_data(grid)
    full = PreferenceGP(grid, KERNEL, 0.05).posterior(winners, losers)
    visited = np.unique(np.concatenate([winners, losers]))
    table = PointSet(grid, grid.points[visited])
    local = {int(g): k for k, g in enumerate(visited)}
    on_table = PreferenceGP(table, KERNEL, 0.05).posterior(
        [local[int(w)] for w in winners], [local[int(v)] for v in losers]
    )
    covered = np.zeros(len(grid), dtype=bool)
    for a in range(len(grid)):
        for feature in range(grid.ndim):
            v = np.zeros(grid.ndim)
            v[feature] = 1.0
            points = line_points(grid, grid.points[a], v, 20)
            space, ids = table.extended(points)
            post = on_points(on_table, space)
            rows = [grid.index(p) for p in points]
            covered[rows] = True
            np.testing.assert_allclose(post.mean[ids], full.mean[rows], atol=1e-9)
            np.testing.assert_allclose(post.variance[ids], full.variance[rows], atol=1e-9)
            np.testing.assert_allclose(
                post.covariance()[np.ix_(ids, ids)],
                full.covariance()[np.ix_(rows, rows)],
                atol=1e-9,
            )
    assert covered.all()


def test_a_line_loop_on_a_grid_matches_the_full_grid_model(grid: Space) -> None:
    utility = -np.sum((grid.points - np.array([0.7, 1.2, 0.2])) ** 2, axis=1)
    loop = LineCoSpar(grid, KERNEL, 0.05, n=1, buffer=1, seed=2, line=LineSettings(10))
    for _ in range(12):
        q = loop.ask()
        assert q.line is not None
        on_line = {tuple(p) for p in q.line.points.tolist()}
        assert all(p in on_line for p in q.points)  # chosen along the line
        a = q.actions[0]
        ua = utility[grid.index(loop.space.points[a])]
        comps = [
            (a, b, "first" if ua > utility[grid.index(loop.space.points[b])] else "second")
            for b in q.buffer
            if b != a
        ]
        loop.tell(q, comps, [(a, "c", "-big")])
    to_grid = [grid.index(p) for p in loop.space.points]
    winners = [to_grid[p.winner] for p in loop.preferences]
    losers = [to_grid[p.loser] for p in loop.preferences]
    full = PreferenceGP(grid, KERNEL, 0.05).posterior(winners, losers)
    np.testing.assert_allclose(loop.posterior.mean, full.mean[to_grid], atol=1e-8)
    np.testing.assert_allclose(loop.posterior.variance, full.variance[to_grid], atol=1e-8)


def test_the_point_engine_draws_from_the_prior_covariance(grid: Space) -> None:
    table = PointSet(grid, grid.points[::3])
    post = PreferenceGP(table, KERNEL, 0.05).prior()
    engine = post.engine
    root_t = engine.root_t  # type: ignore[union-attr]
    plain = KERNEL.dense(table) - KERNEL.jitter * np.eye(len(table))
    np.testing.assert_allclose(root_t.T @ root_t, plain, atol=1e-10)
    np.testing.assert_allclose(KERNEL.dense(table), KERNEL.dense(grid)[::3, ::3], atol=1e-14)


def test_coactive_moves_stay_fractions_of_the_range() -> None:
    domain = Space([Feature.interval("x", 0.0, 2.0), Feature.linspace("y", 0.0, 1.0, 6)])
    table = PointSet(domain, [[1.0, 0.4], [1.9, 1.0]])
    np.testing.assert_allclose(table.move_target(0, "x", "+small"), [1.2, 0.4])  # type: ignore[arg-type]
    np.testing.assert_allclose(table.move_target(0, "x", "-big"), [0.6, 0.4])  # type: ignore[arg-type]
    np.testing.assert_allclose(table.move_target(1, "x", "+big"), [2.0, 1.0])  # type: ignore[arg-type]
    assert table.move_target(1, "y", "+big") is None  # clipped back to the same point
    np.testing.assert_allclose(table.move_target(0, "y", "+big"), [1.0, 0.6])  # type: ignore[arg-type]
    np.testing.assert_allclose(table.move_target(1, "y", "-big"), [1.9, 0.8])  # type: ignore[arg-type]
    with pytest.raises(LookupError, match="not in the point set"):
        table.coactive_move(0, "x", "+small")
    bigger, ids = table.extended([[1.2, 0.4], [1.0, 0.4]])
    assert ids.tolist() == [2, 0] and bigger.coactive_move(0, "x", "+small") == 2


def test_a_point_set_holds_numbers_and_finds_points_by_their_numbers() -> None:
    domain = Space([Feature.interval("x", 0.0, 2.0), Feature.linspace("y", 0.0, 1.0, 6)])
    # NaN passed the range check and was stored as a point
    with pytest.raises(ValueError, match="x: points must be numbers"):
        PointSet(domain, [[np.nan, 0.4]])
    table = PointSet(domain, [[1.0, 0.4], [1.9, 1.0]])
    # NaN found row 0 before; an unknown name was ignored
    with pytest.raises(ValueError, match="x = nan is not a value"):
        table.index([np.nan, 1.0])
    with pytest.raises(KeyError, match="unknown features"):
        table.index({"x": 1.9, "y": 1.0, "z": 0.0})
    assert table.index({"x": 1.9, "y": 1.0}) == 1
    with pytest.raises(TypeError, match="feature must be a name or a number"):
        table.move_target(0, True, "+small")
    # a flat list of four numbers was two points; a row of three a NumPy reshape error
    for bad in ([0.1, 0.2, 0.3, 0.4], [[0.1, 0.2, 0.3]]):
        with pytest.raises(ValueError, match="points must be rows of 2 values"):
            PointSet(domain, bad)
        with pytest.raises(ValueError, match="points must be rows of 2 values"):
            table.extended(bad)
    assert len(PointSet(domain, [])) == 0
    # an empty set's range read "0..-1"
    with pytest.raises(IndexError, match=r"not in the point table \(it has no points yet\)"):
        empty_points(domain).check_index(0)


def test_lines_span_the_box_and_pass_through_the_origin() -> None:
    domain = Space([Feature.interval(f"x{k}", -1.0, 3.0) for k in range(5)])
    for rule in ("random", "coordinate"):
        line = draw_line(domain, LineSettings(30, rule), 7, np.full(5, 0.5))
        pts = line.points
        assert any(np.array_equal(p, np.full(5, 0.5)) for p in pts)
        assert pts.min() >= -1.0 and pts.max() <= 3.0
        assert np.isclose(pts.min(), -1.0) or np.isclose(pts.max(), 3.0)  # reaches the box
        steps = np.diff(pts, axis=0)  # collinear: every step parallel to the direction
        v = np.array(line.direction) * 4.0
        cross = steps[:, :, None] * v[None, None, :] - steps[:, None, :] * v[None, :, None]
        assert np.abs(cross).max() < 1e-9
    again = draw_line(domain, LineSettings(30), 7, np.full(5, 0.5))
    assert np.array_equal(
        again.points, draw_line(domain, LineSettings(30), 7, np.full(5, 0.5)).points
    )


def test_a_star_is_its_first_line_and_random_lines_through_the_same_origin() -> None:
    domain = Space([Feature.interval(f"x{k}", -1.0, 3.0) for k in range(5)])
    origin = np.array([0.0, 1.0, 2.0, 0.5, -0.5])
    one = draw_line(domain, LineSettings(30, "coordinate"), 7, origin)
    star = draw_line(domain, LineSettings(30, "coordinate", 4), 7, origin)
    assert star.direction == one.direction and star.origin == one.origin
    assert np.array_equal(star.points[: len(one.points)], one.points)  # the first line first
    assert len(star.others) == 3 and len(np.unique(star.points, axis=0)) == len(star.points)
    assert sum(np.array_equal(p, origin) for p in star.points) == 1  # the origin once
    for v in star.others:
        assert np.isclose(np.linalg.norm(v), 1.0)
        w = np.array(v) * 4.0  # in the features' units (every range is 4)
        rest = star.points[len(one.points) :] - origin
        on = np.abs(rest[:, :, None] * w[None, None, :] - rest[:, None, :] * w[None, :, None])
        assert (on.max(axis=(1, 2)) < 1e-9).sum() >= 29  # this line's points, but the origin
    assert star.to_json()["others"] == [list(v) for v in star.others]
    assert "others" not in one.to_json()
    for bad in (0, 65, True, 2.0):
        with pytest.raises(ValueError, match="lines per query must be an integer from 1 to 64"):
            LineSettings(30, "random", bad)  # type: ignore[arg-type]


def test_a_star_query_may_be_chosen_on_any_of_its_lines() -> None:
    domain = Space([Feature.interval(f"x{k}", 0.0, 1.0) for k in range(6)])
    loop = LineCoSpar(
        domain,
        SquaredExponential(0.3, 1.0, 1e-6),
        0.05,
        seed=3,
        strategy=make_strategy("eubo"),
        line=LineSettings(20, "random", 4),
    )
    off_first = 0
    for _ in range(12):
        q = loop.ask()
        assert q.line is not None and len(q.line.others) == 3
        on_star = {tuple(p) for p in q.line.points.tolist()}
        origin, v = np.array(q.line.origin), np.array(q.line.direction)
        first = {tuple(p) for p in line_points(domain, origin, v, 20).tolist()}
        assert all(p in on_star for p in q.points)
        off_first += any(p not in first for p in q.points)
        loop.tell(q, [(q.actions[0], b, "first") for b in q.buffer if b != q.actions[0]])
    assert off_first > 0  # the star is used: some queries leave the first line


@pytest.mark.parametrize("strategy", STRATEGIES)
def test_every_strategy_chooses_along_the_line(strategy: str) -> None:
    domain = Space([Feature.interval(f"x{k}", 0.0, 1.0) for k in range(4)])
    kernel = SquaredExponential(0.3, 1.0, 1e-6)
    runs = []
    for _ in range(2):
        loop = LineCoSpar(
            domain, kernel, 0.05, n=2, buffer=1, seed=5, strategy=make_strategy(strategy)
        )
        chosen = []
        for _ in range(5):
            q = loop.ask()
            assert q.line is not None
            on_line = {tuple(p) for p in q.line.points.tolist()}
            assert all(p in on_line for p in q.points)
            pairs = {(a, b) for a in q.actions for b in q.buffer if a != b}
            comps = [(a, b, "first") for a, b in sorted(pairs)]
            loop.tell(q, comps)
            chosen.append(q.points)
        runs.append(chosen)
    assert runs[0] == runs[1]  # deterministic from the seed


def test_hyperparameters_are_fitted_on_continuous_data() -> None:
    domain = Space([Feature.interval(f"x{k}", 0.0, 1.0) for k in range(3)])
    loop = LineCoSpar(
        domain,
        SquaredExponential(0.5, 1.0, 1e-6),
        0.05,
        n=1,
        buffer=1,
        seed=1,
        learning=Learning(fit="evidence", refit_every=4),
    )
    for _ in range(12):
        q = loop.ask()
        a = q.actions[0]
        comps = []
        for b in q.buffer:
            fa, fb = (np.sin(6 * loop.space.points[i, 0]) for i in (a, b))
            comps.append((a, b, "first" if fa > fb else "second"))
        loop.tell(q, [c for c in comps if c[0] != c[1]], [(a, "x1", "+small")])
    assert len(loop.refits) == 3
    assert all(np.isfinite(r.after.lengthscale).all() for r in loop.refits)
    assert any(r.accepted and r.after != r.before for r in loop.refits)


def test_undo_and_a_failed_tell_leave_the_table_as_it_was() -> None:
    domain = Space([Feature.interval("x", 0.0, 1.0), Feature.interval("y", 0.0, 1.0)])
    loop = LineCoSpar(domain, SquaredExponential(0.3, 1.0, 1e-6), 0.05, n=1, buffer=1, seed=3)
    q = loop.ask()
    loop.tell(q, [])
    q = loop.ask()
    size = len(loop.space)
    with pytest.raises(Exception, match="outcome"):
        loop.tell(q, [(q.actions[0], q.buffer[0], "maybe")], [(q.actions[0], "x", "+big")])
    assert len(loop.space) == size
    loop.tell(q, [(q.actions[0], q.buffer[0], "first")], [(q.actions[0], "x", "+big")])
    assert len(loop.space) == size + 1  # the suggested point joined the table
    nxt = loop.ask()
    loop.undo()
    assert len(loop.space) == size and loop.pending == q
    loop.tell(q, [(q.actions[0], q.buffer[0], "first")], [(q.actions[0], "x", "+big")])
    assert loop.ask() == nxt and nxt.points == loop.pending.points


def test_an_empty_point_set_is_the_prior() -> None:
    domain = Space([Feature.interval("x", 0.0, 1.0)])
    empty = empty_points(domain)
    assert len(empty) == 0 and PreferenceGP(empty, KERNEL_1D, 0.05).prior().mean.size == 0


KERNEL_1D = SquaredExponential(0.3, 1.0)


def test_a_grid_past_memory_runs_on_lines_with_a_clear_message_for_the_full_grid() -> None:
    from gaitpref import ConfigError
    from gaitpref.config import parse_config

    space = "".join(f"[space.f{k}]\nmin = 0.0\nmax = 1.0\nnum = 10\n" for k in range(8))
    model = "[model]\nlengthscale = 0.3\nsignal_variance = 1.0\nnoise = 0.05\nfit = 'fixed'\n"
    cfg = parse_config(space + model)  # 10^8 gaits: no grid holds them
    assert cfg.subspace == "line" and cfg.space.grid_size == 10**8
    loop = cfg.make_loop()
    for _ in range(3):
        q = loop.ask()
        assert all(v in np.linspace(0.0, 1.0, 10) for p in q.points for v in p)  # on the grid
        loop.tell(q, [(q.actions[0], b, "first") for b in q.buffer if b != q.actions[0]])
    with pytest.raises(ConfigError, match=r"\[space.f6\].num: the grid would have 10000000 or"):
        parse_config(space + model + "[cospar]\nsubspace = 'grid'\n")
    huge = Space([Feature.linspace(f"f{k}", 0.0, 1.0, 10) for k in range(8)])
    with pytest.raises(ValueError, match=r"100,000,000 actions.*LineCoSpar"):
        CoSpar(huge, SquaredExponential(0.3, 1.0), 0.05)
    with pytest.raises(ValueError, match=r"x are continuous: use gaitpref.loop.line.LineCoSpar"):
        CoSpar(Space([Feature.interval("x", 0.0, 1.0)]), SquaredExponential(0.3, 1.0), 0.05)


def test_an_avoided_point_and_its_neighbourhood_leave_every_later_line() -> None:
    domain = Space([Feature.interval("x", 0.0, 1.0), Feature.interval("y", 0.0, 2.0)])
    loop = LineCoSpar(domain, SquaredExponential(0.3, 1.0, 1e-6), 0.05, n=1, buffer=1, seed=6)
    q = loop.ask()
    loop.tell(q, [])
    q = loop.ask()
    bad = q.actions[0]
    centre = loop.space.points[bad] / np.array([1.0, 2.0])
    assert loop.avoid(bad, 0.2)  # the pending query proposed it: withdrawn
    assert loop.pending is None and len(loop.space) == 1  # its point left the table
    for _ in range(8):
        q = loop.ask()
        for p in q.points:
            assert np.linalg.norm(np.array(p) / np.array([1.0, 2.0]) - centre) > 0.2
        loop.tell(q, [(a, b, "first") for a in q.actions for b in q.buffer if a != b])


def test_all_the_points_of_a_proposal_are_avoided_at_once() -> None:
    """Two points of one proposal that cannot be made: avoiding the first withdraws the proposal
    and frees its rows, so both are named before that and both neighbourhoods stay out."""
    domain = Space([Feature.interval("x", 0.0, 1.0), Feature.interval("y", 0.0, 2.0)])
    loop = LineCoSpar(domain, SquaredExponential(0.3, 1.0, 1e-6), 0.05, n=2, buffer=0, seed=6)
    q = loop.ask()
    assert len(set(q.actions)) == 2 and min(q.actions) >= 0  # two new rows of an empty table
    centres = [loop.space.points[a] / np.array([1.0, 2.0]) for a in q.actions]
    assert loop.avoid_all(q.actions, 0.1)
    assert loop.pending is None and len(loop.space) == 0  # both rows left the table
    for _ in range(6):
        q = loop.ask()
        for p in q.points:
            for centre in centres:
                assert np.linalg.norm(np.array(p) / np.array([1.0, 2.0]) - centre) > 0.1
        loop.tell(q, [(q.actions[0], q.actions[1], "first")] if len(set(q.actions)) == 2 else [])


def test_a_posterior_over_no_point_has_no_argmax() -> None:
    loop = LineCoSpar(Space([Feature.interval("x", 0.0, 1.0)]), KERNEL_1D, 0.05)
    # NumPy's "attempt to get argmax of an empty sequence" before
    with pytest.raises(ValueError, match="no actions yet"):
        _ = loop.posterior.argmax
    with pytest.raises(ValueError, match="no actions yet"):
        loop.posterior.argmax_samples(np.random.default_rng(0), 2)
    assert loop.posterior.argmax_samples(np.random.default_rng(0), 0).size == 0
    assert loop.best_point() is None
