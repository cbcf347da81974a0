"""The noisy, sometimes indifferent simulated subject answers as the ordered probit says."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from scipy.stats import norm

from gaitpref import Feature, Space
from gaitpref.feedback import Outcome
from gaitpref.simulate.noisy import IndifferentUser
from gaitpref.simulate.users import SimulatedUser

SPACE = Space([Feature.linspace("x", 0.0, 1.0, 5)])
OBJECTIVE = np.array([0.0, 0.02, 0.1, 0.3, 0.31])


def test_without_noise_it_is_indifferent_exactly_within_the_band() -> None:
    user = IndifferentUser(SPACE, OBJECTIVE, np.random.default_rng(0), band=0.05)
    assert user.compare(0, 1) == "none" and user.compare(3, 4) == "none"
    assert user.compare(2, 0) == "first" and user.compare(2, 3) == "second"


def test_with_neither_noise_nor_band_it_answers_like_the_papers_user() -> None:
    a = IndifferentUser(SPACE, OBJECTIVE, np.random.default_rng(0))
    b = SimulatedUser(SPACE, OBJECTIVE, np.random.default_rng(0))
    pairs = [(i, j) for i in range(5) for j in range(5) if i != j]
    assert [a.compare(i, j) for i, j in pairs] == [b.compare(i, j) for i, j in pairs]


def test_answer_frequencies_follow_the_ordered_probit() -> None:
    noise, band = 0.05, 0.05
    user = IndifferentUser(SPACE, OBJECTIVE, np.random.default_rng(1), noise=noise, band=band)
    n = 20_000
    answers = [user.compare(2, 1) for _ in range(n)]
    s, d = np.sqrt(2) * noise, OBJECTIVE[2] - OBJECTIVE[1]
    expected: dict[Outcome, float] = {
        "first": norm.cdf((d - band) / s),
        "none": norm.cdf((d + band) / s) - norm.cdf((d - band) / s),
        "second": norm.cdf((-d - band) / s),
    }
    for outcome, p in expected.items():
        freq = answers.count(outcome) / n
        assert freq == pytest.approx(p, abs=4 * np.sqrt(p * (1 - p) / n))


def test_a_negative_band_is_rejected() -> None:
    with pytest.raises(ValueError, match="band must be >= 0"):
        IndifferentUser(SPACE, OBJECTIVE, np.random.default_rng(0), band=-0.1)


@pytest.mark.parametrize("band", [True, "0.1", None])
def test_the_band_is_a_number(band: Any) -> None:
    # True was a band of 1; a string or None a NumPy ufunc TypeError
    with pytest.raises(ValueError, match="band must be >= 0"):
        IndifferentUser(
            SPACE, np.arange(len(SPACE), dtype=float), np.random.default_rng(0), band=band
        )
