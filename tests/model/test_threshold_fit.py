"""Ordinal thresholds learned by the evidence (``model/hyperfit.py``): they stay ordered under
fitting, move toward the thresholds that generated the ratings, are held when the config fixes
them, and appear in the refit record only when fitted."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gaitpref import Feature, Space
from gaitpref.model.evidence import Hyperparameters, PairData
from gaitpref.model.hyperfit import default_prior, fit_hyperparameters
from gaitpref.model.ordinal import Ordinal, rating_likelihood
from gaitpref.model.singles import SingleData

SPACE = Space([Feature.linspace("x", 0.0, 1.0, 9), Feature.linspace("y", 0.0, 1.0, 6)])
VARIANCE, NOISE = 0.005, 0.02
START = Hyperparameters((0.25, 0.25), VARIANCE, 1e-7)
NO_PAIRS = PairData(
    np.zeros(0, np.intp), np.zeros(0, np.intp), np.zeros(0), np.zeros(0, bool), np.zeros(0, bool)
)


def _ratings(actions: np.ndarray, labels: np.ndarray, ordinal: Ordinal) -> SingleData:
    return SingleData(actions.astype(np.intp), rating_likelihood(ordinal, VARIANCE, labels))


@settings(max_examples=25)
@given(
    st.integers(2, 5),
    st.lists(st.tuples(st.integers(0, len(SPACE) - 1), st.integers(1, 5)), min_size=1, max_size=40),
    st.integers(0, 3),
)
def test_fitted_thresholds_stay_increasing(
    categories: int, rated: list[tuple[int, int]], seed: int
) -> None:
    actions = np.array([a for a, _ in rated])
    labels = np.array([min(k, categories) for _, k in rated])
    ordinal = Ordinal(categories, noise=NOISE)
    singles = _ratings(actions, labels, ordinal)
    rng = np.random.default_rng(seed)
    first, second = rng.integers(0, len(SPACE), 8), rng.integers(0, len(SPACE), 8)
    keep = first != second
    n = int(keep.sum())
    pairs = PairData(first[keep], second[keep], np.full(n, NOISE), np.zeros(n, bool),
                     np.zeros(n, bool))  # fmt: skip
    prior = default_prior(SPACE, VARIANCE, NOISE)
    fit = fit_hyperparameters(SPACE, START, pairs, prior, singles=singles)
    assert fit.failed_evaluations == 0, fit.message
    assert fit.before == START and fit.accepted, fit.message
    t = np.array(fit.after.thresholds)
    assert t.shape == (categories - 1,)
    assert np.all(np.diff(t) > 0), t
    record = fit.to_json()["after"]
    assert fit.after.thresholds is not None
    assert isinstance(record, dict) and record["thresholds"] == list(fit.after.thresholds)
    centre = np.array(ordinal.thresholds_for(VARIANCE))
    assert abs(t[0] - centre[0]) <= 3 * np.sqrt(VARIANCE) * (1 + 1e-9)
    # the next refit starts from them, and keeps them increasing
    again = fit_hyperparameters(SPACE, fit.after, pairs, prior, singles=singles)
    assert again.before.thresholds == fit.after.thresholds
    assert np.all(np.diff(np.array(again.after.thresholds)) > 0)


def test_thresholds_move_toward_the_generating_ones() -> None:
    """Ratings of a known utility cut at thresholds narrower than the prior's quantiles and
    shifted up: the fitted lowest threshold and the gaps move toward the generating ones (a
    common shift of all thresholds is weakly identified: the utility's level can absorb it)."""
    rng = np.random.default_rng(5)
    f = 0.07 * np.sin(3 * SPACE.points[:, 0]) * np.cos(2 * SPACE.points[:, 1])
    true = np.array([0.0, 0.03, 0.06])
    actions = rng.integers(0, len(SPACE), 150)
    y = f[actions] + rng.normal(0.0, NOISE, actions.size)
    labels = 1 + np.searchsorted(true, y)
    ordinal = Ordinal(4, noise=NOISE)
    centre = np.array(ordinal.thresholds_for(VARIANCE))
    prior = default_prior(SPACE, VARIANCE, NOISE)
    singles = _ratings(actions, labels, ordinal)
    fit = fit_hyperparameters(SPACE, START, NO_PAIRS, prior, singles=singles)
    assert fit.accepted and fit.failed_evaluations == 0, fit.message
    assert fit.objective_after > fit.objective_before
    t = np.array(fit.after.thresholds)
    assert abs(t[0] - true[0]) < 0.6 * abs(centre[0] - true[0])
    assert np.all(
        np.abs(np.diff(t) - np.diff(true)) < 0.6 * np.abs(np.diff(centre) - np.diff(true))
    )


def test_fixed_thresholds_are_not_fitted_and_the_record_is_as_before() -> None:
    rng = np.random.default_rng(6)
    actions, labels = rng.integers(0, len(SPACE), 30), rng.integers(1, 4, 30)
    fixed = _ratings(actions, labels, Ordinal(3, thresholds=(-0.02, 0.02), noise=NOISE))
    prior = default_prior(SPACE, VARIANCE, NOISE)
    fit = fit_hyperparameters(SPACE, START, NO_PAIRS, prior, singles=fixed)
    assert fit.accepted and fit.after.thresholds is None
    assert fit.observations == 30
    keys = {"lengthscale", "signal_variance", "jitter", "tie_band"}
    after = fit.to_json()["after"]
    assert isinstance(after, dict) and set(after) == keys


def test_thresholds_fitted_before_are_held_without_ratings() -> None:
    rng = np.random.default_rng(8)
    first, second = rng.integers(0, len(SPACE), 30), rng.integers(0, len(SPACE), 30)
    keep = first != second
    n = int(keep.sum())
    pairs = PairData(first[keep], second[keep], np.full(n, NOISE), np.zeros(n, bool),
                     np.zeros(n, bool))  # fmt: skip
    start = Hyperparameters((0.25, 0.25), VARIANCE, 1e-7, 0.0, (-0.03, 0.01, 0.04))
    fit = fit_hyperparameters(SPACE, start, pairs, default_prior(SPACE, VARIANCE, NOISE))
    assert fit.accepted
    assert fit.after.thresholds == pytest.approx(start.thresholds, rel=1e-12)
    assert fit.after.lengthscale != start.lengthscale
