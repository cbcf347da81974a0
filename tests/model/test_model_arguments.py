"""The model's constructors name a bad number: a string, a bool, None (before: NumPy ufunc
errors, or True read as 1)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from gaitpref import Feature, Ordinal, PreferenceGP, Space, SquaredExponential

SPACE = Space([Feature.linspace("a", 0, 1, 5), Feature.linspace("b", 0, 1, 4)])
KERNEL = SquaredExponential(0.3, 1.0, 1e-6)


@pytest.mark.parametrize("noise", ["0.1", True, None, np.nan])
def test_the_preference_noise_is_a_number(noise: object) -> None:
    with pytest.raises(ValueError, match="preference noise must be positive"):
        PreferenceGP(SPACE, KERNEL, noise)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"lengthscale": True, "variance": 1.0}, "lengthscale must be positive and finite"),
        ({"lengthscale": "0.3", "variance": 1.0}, "lengthscale must be positive and finite"),
        ({"lengthscale": (0.3, None), "variance": 1.0}, "lengthscale must be positive"),
        ({"lengthscale": 0.3, "variance": "1"}, "signal variance must be positive"),
        ({"lengthscale": 0.3, "variance": None}, "signal variance must be positive"),
        ({"lengthscale": 0.3, "variance": 1.0, "jitter": True}, "jitter must be >= 0"),
        # each finite, their sum not: the prior's variance was inf at every gait
        (
            {"lengthscale": 0.3, "variance": 1e308, "jitter": 1e308},
            r"signal variance \+ jitter \(each gait's prior variance\) must be finite",
        ),
        # a table of lengthscales was read row after row as one per feature
        ({"lengthscale": [[0.3, 0.4]], "variance": 1.0}, r"one per feature, got shape \(1, 2\)"),
        ({"lengthscale": np.ones((2, 1)), "variance": 1.0}, r"got shape \(2, 1\)"),
    ],
)
def test_kernel_numbers_are_numbers(kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        SquaredExponential(**kwargs)


def test_kernel_lengthscales_from_numpy() -> None:
    # NumPy values, not the floats and tuples the signature names, are taken too
    scalar: Any = np.array(0.3)
    pair: Any = np.array([0.3, 0.2])
    listed: Any = [np.float64(0.3)]
    assert SquaredExponential(scalar, 1.0).lengthscale == 0.3  # a 0-d array failed
    assert SquaredExponential(pair, 1.0).lengthscale == (0.3, 0.2)
    assert SquaredExponential(listed, np.float64(1.0)).lengthscale == (0.3,)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"categories": "abc"}, "categories must be a number of categories or a sequence"),
        ({"categories": True}, "categories must be a number of categories or a sequence"),
        ({"categories": 10**9}, "needs 2 to 100 categories"),
        ({"categories": [1, 2, 3]}, "category names must be non-empty strings"),
        ({"categories": 3, "noise": "x"}, "the rating noise must be positive"),
        ({"categories": 3, "noise": True}, "the rating noise must be positive"),
        ({"categories": 2, "thresholds": 0.5}, "thresholds must be a sequence of numbers"),
        ({"categories": 3, "thresholds": "ab"}, "thresholds must be a sequence of numbers"),
        ({"categories": 3, "thresholds": [0.1, None]}, "thresholds must be numbers"),
    ],
)
def test_rating_scale_arguments(kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Ordinal(**kwargs)


def test_rating_scale_from_numpy() -> None:
    three: Any = np.int64(3)
    thresholds: Any = np.array([0.1])
    assert Ordinal(three).categories == ("1", "2", "3")  # it was "not iterable"
    assert Ordinal(2, thresholds=thresholds).thresholds == (0.1,)


def test_rating_likelihood_labels_are_integers() -> None:
    from gaitpref.model import rating_likelihood

    scale = Ordinal(3)
    # 1.5 was truncated to label 1, True read as 1
    for labels in ([1.5], [True], [[1, 2]]):
        with pytest.raises(ValueError, match=r"rating labels must be a 1-D sequence of integers"):
            rating_likelihood(scale, 1.0, labels)
    assert rating_likelihood(scale, 1.0, np.array([3, 1], dtype=np.int8)).labels.tolist() == [3, 1]
    assert rating_likelihood(scale, 1.0, []).labels.size == 0
