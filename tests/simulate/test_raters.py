"""Simulated ordinal raters: categories at the objective's quantiles, noise near the boundaries,
and simulations that rate every executed gait."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import CoSpar, SimulatedUser, load_config, run_simulation
from gaitpref.model.ordinal import Ordinal
from gaitpref.simulate.raters import OrdinalRater
from gaitpref.simulate.run import SimulationResult


def test_noiseless_ratings_split_the_grid_at_the_quantiles() -> None:
    space = load_config("synthetic-2d").space
    objective = np.random.default_rng(0).normal(size=len(space))
    rater = OrdinalRater(space, objective, (0.25, 0.5, 0.75), np.random.default_rng(1))
    ratings = np.array([rater.rate(a) for a in range(len(space))])
    shares = np.bincount(ratings, minlength=5)[1:] / len(space)
    assert np.allclose(shares, 0.25, atol=1.5 / len(space))
    best, worst = int(np.argmax(objective)), int(np.argmin(objective))
    assert rater.rate(best) == 4 and rater.rate(worst) == 1


def test_noise_blurs_only_near_the_boundaries() -> None:
    space = load_config("synthetic-2d").space
    objective = np.linspace(0.0, 1.0, len(space))
    rater = OrdinalRater(space, objective, (0.5,), np.random.default_rng(2), noise=0.05)
    near = int(np.argmin(np.abs(rater.utility - rater.boundaries[0])))
    assert {rater.rate(near) for _ in range(200)} == {1, 2}
    assert {rater.rate(len(space) - 1) for _ in range(200)} == {2}


def test_bad_quantiles_are_refused() -> None:
    space = load_config("synthetic-2d").space
    for q in [(), (0.5, 0.5), (0.0, 0.5), (0.7, 0.3), (1.0,)]:
        with pytest.raises(ValueError, match="quantiles"):
            OrdinalRater(space, np.zeros(len(space)), q, np.random.default_rng(0))


def test_a_simulation_rates_every_trial_and_the_ratings_enter_the_model() -> None:
    cfg = load_config("exo-1d-step-length")
    objective = -((cfg.space.points[:, 0] - 0.12) ** 2)
    ordinal = Ordinal(["very bad", "bad", "okay", "good"], noise=0.02)

    def run(rated: bool) -> SimulationResult:
        loop = CoSpar(cfg.space, cfg.kernel, cfg.noise, n=1, buffer=1, seed=3, ordinal=ordinal)
        user = SimulatedUser(cfg.space, objective, np.random.default_rng(4))
        rater = (
            OrdinalRater(cfg.space, objective, (0.25, 0.5, 0.75), np.random.default_rng(5))
            if rated
            else None
        )
        return run_simulation(loop, user, 12, rater=rater)

    with_ratings, without = run(True), run(False)
    assert with_ratings.ratings is not None
    assert len(with_ratings.ratings) == 12 and set(with_ratings.ratings) <= {1, 2, 3, 4}
    assert with_ratings.to_json()["ratings"] == with_ratings.ratings.tolist()
    assert without.ratings is None and "ratings" not in without.to_json()
    assert not np.allclose(with_ratings.posterior.mean, without.posterior.mean)


@pytest.mark.parametrize(
    ("labels", "quantiles", "message"),
    [
        (None, (0.5,), "the loop has no rating scale"),
        # 2 categories on a scale of 4: every gait the rater found worse than the median was
        # told "very bad" and the region of avoidance closed over the grid (NoSafeGaitError)
        (["very bad", "bad", "okay", "good"], (0.5,), "gives 2 categories (1 quantiles)"),
        (["bad", "good"], (0.25, 0.5, 0.75), "but the loop has 2 categories"),
    ],
)
def test_a_rater_and_a_loop_of_different_scales_are_refused_before_any_trial(
    labels: list[str] | None, quantiles: tuple[float, ...], message: str
) -> None:
    cfg = load_config("exo-1d-step-length")
    objective = -((cfg.space.points[:, 0] - 0.12) ** 2)
    ordinal = None if labels is None else Ordinal(labels, noise=0.02)
    loop = CoSpar(cfg.space, cfg.kernel, cfg.noise, n=1, buffer=1, seed=3, ordinal=ordinal)
    user = SimulatedUser(cfg.space, objective, np.random.default_rng(4))
    rater = OrdinalRater(cfg.space, objective, quantiles, np.random.default_rng(5))
    with pytest.raises(ValueError, match="the rater gives") as info:
        run_simulation(loop, user, 12, rater=rater)
    assert message in str(info.value)
    assert len(loop.executed) == 0


def _shares(rater: OrdinalRater) -> list[int]:
    counts = np.bincount(rater.true_categories(), minlength=rater.categories + 1)[1:]
    return [int(c) for c in counts]


def test_a_flat_objective_is_rated_in_one_middle_category() -> None:
    """Every gait ties: they were all rated the best ('good'); now all in the category where
    the middle of the grid lies (the position 0.5: at or above the median, below the top
    quartile)."""
    space = load_config("synthetic-2d").space
    flat = np.full(len(space), 2.5)
    quartiles = OrdinalRater(space, flat, (0.25, 0.5, 0.75), np.random.default_rng(0))
    assert {quartiles.rate(a) for a in range(len(space))} == {3}
    tertiles = OrdinalRater(space, flat, (1 / 3, 2 / 3), np.random.default_rng(0))
    assert _shares(tertiles) == [0, len(space), 0]


def test_a_flat_objective_with_noise_is_refused_naming_it() -> None:
    space = load_config("synthetic-2d").space
    with pytest.raises(ValueError, match=r"objective: the same at every gait \(2\.5\)"):
        OrdinalRater(space, np.full(len(space), 2.5), (0.5,), np.random.default_rng(0), 0.05)


def test_a_plateau_on_a_boundary_goes_where_its_middle_lies() -> None:
    """A bottom plateau of 30% of the grid spans the lower quartile: it is rated worst (it went
    up to 'bad' and no gait was rated worst); a top plateau of 30% is rated best."""
    space = load_config("synthetic-2d").space
    objective = np.random.default_rng(0).normal(size=len(space))
    bottom = np.maximum(objective, np.quantile(objective, 0.3))
    top = np.minimum(objective, np.quantile(objective, 0.7))
    q = (0.25, 0.5, 0.75)
    low = OrdinalRater(space, bottom, q, np.random.default_rng(0))
    assert _shares(low) == [270, 180, 225, 225]
    assert low.rate(int(np.argmin(bottom))) == 1
    high = OrdinalRater(space, top, q, np.random.default_rng(0))
    assert _shares(high) == [225, 225, 180, 270]
    # minimised, the same plateau is at the bottom of the utility: rated worst
    assert _shares(OrdinalRater(space, top, q, np.random.default_rng(0), minimize=True))[0] == 270


def test_a_gait_alone_on_a_boundary_goes_up_as_before() -> None:
    """Five distinct values with the median a gait's own: it is in the upper category."""
    space = load_config("exo-1d-step-length").space
    objective = np.arange(len(space), dtype=float)
    assert len(space) % 2 == 1  # an odd count: the median is a gait's value
    rater = OrdinalRater(space, objective, (0.5,), np.random.default_rng(0))
    middle = len(space) // 2
    assert rater.boundaries[0] == rater.utility[middle]
    assert rater.rate(middle) == 2 and rater.rate(middle - 1) == 1


def test_noiseless_rate_is_the_true_category() -> None:
    space = load_config("synthetic-2d").space
    objective = np.round(np.random.default_rng(3).normal(size=len(space)), 1)  # many ties
    rater = OrdinalRater(space, objective, (0.25, 0.5, 0.75), np.random.default_rng(0))
    rated = [rater.rate(a) for a in range(len(space))]
    assert rated == rater.true_categories().tolist()
