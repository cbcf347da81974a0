from __future__ import annotations

import numpy as np
import pytest

from gaitpref import Feature, GradientCoactive, Query, SimulatedUser, Space, load_config
from gaitpref.simulate.run import run_simulation


@pytest.fixture
def line() -> Space:
    return Space([Feature.linspace("x", 0.0, 1.0, 6)])


def test_user_prefers_higher_or_lower(line: Space) -> None:
    obj = np.array([0.0, 1.0, 2.0, 3.0, 2.0, 1.0])
    hi = SimulatedUser(line, obj, np.random.default_rng(0))
    lo = SimulatedUser(line, obj, np.random.default_rng(0), minimize=True)
    assert hi.compare(3, 1) == "first" and hi.compare(1, 3) == "second"
    assert lo.compare(3, 1) == "second"
    assert np.allclose(hi.normalized([0, 3, 4]), [0.0, 1.0, 2 / 3])
    assert np.allclose(lo.normalized([0, 3]), [1.0, 0.0])


def test_exact_ties_are_broken_at_random(line: Space) -> None:
    user = SimulatedUser(line, np.array([0, 1, 2, 3, 2, 1.0]), np.random.default_rng(1))
    outcomes = [user.compare(2, 4) for _ in range(2000)]
    assert abs(outcomes.count("first") - 1000) < 5 * np.sqrt(500)


def test_noisy_user_follows_the_probit(line: Space) -> None:
    user = SimulatedUser(
        line, np.array([0, 0.1, 0, 0, 0, 0.0]), np.random.default_rng(2), noise=0.1
    )
    wins = sum(user.compare(1, 0) == "first" for _ in range(4000))
    # Phi(0.1 / (sqrt(2) 0.1)) = Phi(0.7071) = 0.7602
    assert abs(wins / 4000 - 0.7602) < 5 * np.sqrt(0.76 * 0.24 / 4000)


def test_answer_compares_each_pair_once(line: Space) -> None:
    user = SimulatedUser(line, np.arange(6.0), np.random.default_rng(0))
    q = Query(1, (1, 2, 3), (4,))
    pairs = [(c.first, c.second) for c in user.answer(q)]
    assert pairs == [(1, 2), (1, 3), (1, 4), (2, 3), (2, 4), (3, 4)]
    assert user.answer(Query(2, (2,), (2,))) == []


def test_gradient_coactive_hand_computed_cases() -> None:
    space = Space(
        [
            Feature.linspace("x", 0, 1, 5, coactive=(0.25, 0.5)),
            Feature.linspace("y", 0, 1, 4, coactive=(0.3, 0.6)),
        ]
    )
    # f = x-index^2 (grows along x), flat in y
    obj = np.array([[i * i] * 4 for i in range(5)], dtype=float)
    coactive = GradientCoactive(space, obj)
    # np.gradient along x: [1, 2, 4, 6, 7] (edges one-sided); along y: 0
    assert np.allclose(coactive.gradient[:, 0].reshape(5, 4)[:, 0], [1, 2, 4, 6, 7])
    t50, t75 = np.percentile([1, 2, 4, 6, 7] * 4, [50, 75])
    assert (t50, t75) == (4.0, 6.0)
    assert coactive.suggest(space.index([0.0, 0.0])) is None  # 1 <= median: no feedback
    assert coactive.suggest(space.index([0.5, 0.0])) is None  # 4 is not above the median
    s = coactive.suggest(space.index([0.75, 0.0]))  # 6: above median, not above 75th -> small
    assert s is not None and (s.feature, s.move) == ("x", "+small")
    # at the top edge the move clips back to the point: no feedback
    assert coactive.suggest(space.index([1.0, 0.0])) is None
    down = GradientCoactive(space, obj, minimize=True).suggest(space.index([0.75, 0.0]))
    assert down is not None and (down.feature, down.move) == ("x", "-small")


def test_simulation_reports_trials_and_scores() -> None:
    cfg = load_config("compass-gait")
    x = cfg.space.points[:, 0]
    coefficients = [-660.1898, 556.5202, -186.4672, 34.1877, -3.4090, 0.1602]
    cot = np.asarray(np.polyval(coefficients, x), dtype=np.float64)
    loop = cfg.make_loop(seed=0)
    user = SimulatedUser(cfg.space, cot, np.random.default_rng(0), minimize=True)
    result = run_simulation(loop, user, trials=41)
    assert result.actions.shape == (41,)
    assert np.allclose(result.normalized_objective, user.normalized(result.actions))
    assert abs(x[result.posterior_argmax] - 0.132) < 0.015
    assert result.argmax_normalized_objective > 0.95


def test_users_take_grid_indices_and_a_generator(line: Space) -> None:
    user = SimulatedUser(line, np.arange(len(line), dtype=float), np.random.default_rng(0))
    last = len(line) - 1
    # -1 read the last gait (normalized 1.0), 1.7 gait 1
    with pytest.raises(IndexError, match=r"actions\[0\] = -1 is off the grid"):
        user.normalized([-1])
    with pytest.raises(TypeError, match="integer grid indices"):
        user.normalized([1.7])
    with pytest.raises(IndexError, match="action index -1 is off the grid"):
        user.compare(-1, 0)
    assert user.compare(last, 0) == "first"
    with pytest.raises(TypeError, match=r"rng must be a numpy\.random\.Generator"):
        SimulatedUser(line, np.arange(len(line), dtype=float), 0)  # type: ignore[arg-type]
    coactive = GradientCoactive(line, np.arange(len(line), dtype=float) ** 2)
    with pytest.raises(IndexError, match="action index -1 is off the grid"):
        coactive.suggest(-1)


def test_simulation_trials_are_a_count() -> None:
    config = load_config("exo-1d-step-length")
    objective = np.linspace(0.0, 1.0, len(config.space))
    for trials in (2.5, True, 0):
        user = SimulatedUser(config.space, objective, np.random.default_rng(0))
        with pytest.raises(ValueError, match="trials must be an integer >= 1"):
            run_simulation(config.make_loop(seed=0), user, trials)  # type: ignore[arg-type]


def test_an_objective_of_another_shape_is_refused_naming_the_grids() -> None:
    """A 1-D grid's two shapes are one: it said 'the grid needs (15,) or (15,)'."""
    from gaitpref.simulate.users import objective_on_grid

    with pytest.raises(ValueError, match=r"shape \(30, 30\); the grid needs \(15,\)$"):
        objective_on_grid(load_config("exo-1d-step-length").space, np.zeros((30, 30)))
    with pytest.raises(ValueError, match=r"shape \(5,\); the grid needs \(30, 30\) or \(900,\)$"):
        objective_on_grid(load_config("synthetic-2d").space, np.zeros(5))
