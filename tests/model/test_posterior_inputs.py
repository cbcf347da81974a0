"""The posterior's readers check what a caller gives them: indices, sizes, generators, masks."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from gaitpref import Feature, Ordinal, Posterior, PreferenceGP, Space, SquaredExponential
from gaitpref.model import Probit

SPACE = Space([Feature.linspace("a", 0, 1, 5), Feature.linspace("b", 0, 1, 4)])


@pytest.fixture(scope="module")
def post() -> Posterior:
    gp = PreferenceGP(SPACE, SquaredExponential(0.3, 1.0, 1e-6), 0.1, ordinal=Ordinal(3))
    return gp.posterior([0, 1], [2, 3], ratings=[(5, 3)])


READERS: dict[str, Callable[[Posterior, Any], object]] = {
    "mean_at": lambda p, a: p.mean_at(a),
    "variance_at": lambda p, a: p.variance_at(a),
    "variance_many": lambda p, a: p.variance_many(a),
    "covariance_at": lambda p, a: p.covariance_at(a),
    "rating_probabilities": lambda p, a: p.rating_probabilities(a),
}


@pytest.mark.parametrize("reader", READERS)
def test_off_grid_indices_are_refused_not_wrapped(post: Posterior, reader: str) -> None:
    read = READERS[reader]
    for bad in ([-1], [20], [3, -20]):
        with pytest.raises(IndexError, match=r"actions\[\d\] = -?\d+ is off the grid \(0\.\.19\)"):
            read(post, bad)
    with pytest.raises(TypeError, match="integer grid indices, got dtype float64"):
        read(post, [1.7])
    with pytest.raises(ValueError, match="1-D"):
        read(post, [[1, 2]])
    # valid indices of any integer type read as before
    assert np.array_equal(
        np.asarray(read(post, np.array([19, 0], dtype=np.int32))), np.asarray(read(post, [19, 0]))
    )


def test_rating_probabilities_of_one_action(post: Posterior) -> None:
    assert np.array_equal(post.rating_probabilities(4), post.rating_probabilities([4]))
    with pytest.raises(IndexError, match="off the grid"):
        post.rating_probabilities(-1)


def test_preference_probability_checks_both_actions(post: Posterior) -> None:
    with pytest.raises(IndexError, match="action index -1 is off the grid"):
        post.preference_probability(-1, 0)
    with pytest.raises(IndexError, match="action index 20 is off the grid"):
        post.preference_probability(0, 20)
    with pytest.raises(TypeError, match=r"action index must be an integer, got 1\.5"):
        post.preference_probability(1.5, 0)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="must be an integer, got True"):
        post.preference_probability(True, 0)
    numpy_19: Any = np.int64(19)  # a NumPy integer is an index too
    assert post.preference_probability(numpy_19, 0) == post.preference_probability(19, 0)


@pytest.mark.parametrize("size", [-1, 2.5, True, "3"])
def test_sample_size_must_be_a_count(post: Posterior, size: object) -> None:
    with pytest.raises(ValueError, match=r"size \(the number of samples\) must be an integer >= 0"):
        post.sample(np.random.default_rng(0), size)  # type: ignore[arg-type]


def test_sample_takes_numpy_counts_and_needs_a_generator(post: Posterior) -> None:
    numpy_3: Any = np.int64(3)
    assert post.sample(np.random.default_rng(0), numpy_3).shape == (3, 20)
    for rng in (0, None, np.random.RandomState(0)):
        with pytest.raises(TypeError, match=r"rng must be a numpy\.random\.Generator"):
            post.sample(rng, 2)  # type: ignore[arg-type]


def test_nugget_is_a_bool_and_mixtures_need_a_generator(post: Posterior) -> None:
    from gaitpref.model.share_mix import PosteriorMixture

    flag: Any = "False"  # truthy: the jitter's part was kept, silently
    with pytest.raises(TypeError, match="nugget must be True or False, got 'False'"):
        post.sample(np.random.default_rng(0), 2, nugget=flag)
    smooth = post.sample(np.random.default_rng(0), 2, nugget=np.False_)  # type: ignore[arg-type]
    assert np.array_equal(smooth, post.sample(np.random.default_rng(0), 2, nugget=False))
    mixture = PosteriorMixture(((0.5, post), (0.5, post)))
    seed: Any = 0  # an AttributeError in rng.choice before
    with pytest.raises(TypeError, match=r"rng must be a numpy\.random\.Generator"):
        mixture.sample(seed, 2)
    with pytest.raises(TypeError, match="nugget must be True or False"):
        mixture.sample(np.random.default_rng(0), 2, nugget=flag)


def test_argmax_samples_checks_the_mask(post: Posterior) -> None:
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="boolean mask over the 20 actions"):
        post.argmax_samples(rng, 2, np.ones(3, dtype=bool))
    with pytest.raises(ValueError, match="boolean mask over the 20 actions"):
        post.argmax_samples(rng, 2, np.ones(20))  # type: ignore[arg-type]
    # all false: before, every action tied at -inf and disallowed ones were returned
    with pytest.raises(ValueError, match="allows no action"):
        post.argmax_samples(rng, 2, np.zeros(20, dtype=bool))
    only = np.zeros(20, dtype=bool)
    only[7] = True
    assert post.argmax_samples(rng, 3, only).tolist() == [7, 7, 7]


def test_posterior_names_a_bad_noise_or_rating() -> None:
    gp = PreferenceGP(SPACE, SquaredExponential(0.3, 1.0), 0.1, ordinal=Ordinal(3))
    with pytest.raises(ValueError, match=r"noise must be one number or one per comparison \(2\)"):
        gp.posterior([0, 1], [2, 3], noise=[0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match=r"ratings\[1\] must be an \(action, label\) pair"):
        gp.posterior([0], [1], ratings=[(2, 1), (3,)])  # type: ignore[list-item]
    with pytest.raises(ValueError, match=r"ratings\[0\]: rating 4 is not a category"):
        gp.posterior([0], [1], ratings=[(2, 4)])
    assert gp.posterior([0], [1], ratings=[(2, 3)]).visited.tolist() == [0, 1, 2]


def test_covariance_at_has_the_covariance_limit() -> None:
    from gaitpref.model.posterior import COVARIANCE_LIMIT_ACTIONS

    big = Space([Feature.linspace("a", 0, 1, 200), Feature.linspace("b", 0, 1, 100)])
    post = PreferenceGP(big, SquaredExponential(0.3, 1.0, 1e-6), 0.1).posterior([0], [1])
    # 20,000 actions asked for a 3 GiB matrix (covariance() refuses the same)
    with pytest.raises(ValueError, match=r"covariance_at would build a 20000 x 20000 matrix"):
        post.covariance_at(np.arange(len(big)))
    with pytest.raises(ValueError, match=f"at most {COVARIANCE_LIMIT_ACTIONS} actions"):
        post.covariance_at(np.zeros(COVARIANCE_LIMIT_ACTIONS + 1, dtype=np.intp))
    assert post.covariance_at([0, 5, 7]).shape == (3, 3)


@pytest.mark.parametrize(
    ("noise", "message"),
    [
        # read by NumPy as noises before: True as 1.0, "0.1" as 0.1
        (True, r"noise must be numbers \(one, or one per comparison\), got True"),
        ("0.1", "noise must be numbers"),
        ([np.True_, 0.1], "noise must be numbers"),
        ([0.1, True], "noise must be numbers"),
        # its square overflowed in the likelihood (the model's own noise is held to the same)
        (
            1e200,
            r"positive with a finite square \(at most 1.34e\+154\), got 1e\+200 for comparison 0",
        ),
        ([0.1, -1.0], r"got -1.0 for comparison 1"),
        ([0.1, np.nan], r"got nan for comparison 1"),
    ],
)
def test_per_comparison_noise_is_numbers_with_finite_squares(noise: object, message: str) -> None:
    gp = PreferenceGP(SPACE, SquaredExponential(0.3, 1.0), 0.1)
    with pytest.raises(ValueError, match=message):
        gp.posterior([0, 1], [2, 3], noise=noise)  # type: ignore[arg-type]


def test_per_comparison_noise_of_any_number_kind() -> None:
    gp = PreferenceGP(SPACE, SquaredExponential(0.3, 1.0), 0.1)
    mixed: Any = [np.float32(0.25), 0.1]
    given = gp.posterior([0, 1], [2, 3], noise=mixed)
    same = gp.posterior([0, 1], [2, 3], noise=np.array([float(np.float32(0.25)), 0.1]))
    assert np.array_equal(given.mean, same.mean)
    assert np.array_equal(
        gp.posterior([0], [2], noise=1).mean, gp.posterior([0], [2], noise=1.0).mean
    )


def test_the_ordinal_model_is_an_ordinal() -> None:
    with pytest.raises(TypeError, match=r"ordinal must be a gaitpref\.Ordinal or None, got 5"):
        PreferenceGP(SPACE, SquaredExponential(0.3, 1.0), 0.1, ordinal=5)  # type: ignore[arg-type]


def test_posterior_from_checks_its_indices_and_likelihood() -> None:
    gp = PreferenceGP(SPACE, SquaredExponential(0.3, 1.0), 0.1)
    lik = Probit(np.full(2, 0.1))
    # floats were truncated to gaits, silently; off-grid and negative indices NumPy's error
    with pytest.raises(TypeError, match="first must hold integer grid indices, got dtype float64"):
        gp.posterior_from(np.array([0.0, 5.0]), np.array([1, 2]), lik)
    with pytest.raises(IndexError, match=r"second\[1\] = -1 is off the grid"):
        gp.posterior_from(np.array([0, 5]), np.array([1, -1]), lik)
    with pytest.raises(ValueError, match="2 first but 1 second actions"):
        gp.posterior_from(np.array([0, 5]), np.array([1]), lik)
    with pytest.raises(TypeError, match="likelihood must be a likelihood"):  # AttributeError
        gp.posterior_from(np.array([0, 5]), np.array([1, 2]), 0.1)  # type: ignore[arg-type]
    listed: Any = [0, 5]  # a list was "'list' object has no attribute 'size'"
    given = gp.posterior_from(listed, [1, 2], lik)  # type: ignore[arg-type]
    same = gp.posterior([0, 5], [1, 2], noise=0.1)
    assert np.array_equal(given.mean, same.mean)
