"""The hyperparameter fit's own arguments are named where they are given.

Before: a :class:`HyperPrior` with one lengthscale prior fewer than the space's features failed
in NumPy ("boolean index did not match indexed array"), a number in place of a
:class:`LogNormal` was an AttributeError ('median') mid-fit, ``LogNormal("1", ...)`` a NumPy
TypeError and ``LogNormal(True, ...)`` a median of 1; :class:`Hyperparameters` took thresholds
out of order (their log gaps, what a fit starts from, were NaN) and kept a NumPy array of
lengthscales, which made two of them impossible to compare.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from gaitpref import Feature, Space
from gaitpref.model import (
    Hyperparameters,
    HyperPrior,
    LogNormal,
    PairData,
    default_prior,
    fit_hyperparameters,
)
from gaitpref.model.hyperfit import ThresholdPrior

SPACE = Space([Feature.linspace("a", 0.0, 1.0, 5), Feature.linspace("b", 0.0, 1.0, 3)])
HYPER = Hyperparameters((0.3, 0.4), 1.0, 1e-6)
NO = np.zeros(3, dtype=bool)
DATA = PairData(np.array([0, 4, 7]), np.array([3, 9, 14]), np.full(3, 0.1), NO, NO)


def test_a_prior_per_feature() -> None:
    short = HyperPrior((LogNormal(0.25, 0.7),), LogNormal(1.0, 0.0))
    with pytest.raises(ValueError, match="the space has 2 features; the prior has 1 lengthscale"):
        fit_hyperparameters(SPACE, HYPER, DATA, short)
    three = Hyperparameters((0.3, 0.4, 0.5), 1.0, 1e-6)
    with pytest.raises(ValueError, match="and the start 3 lengthscales"):
        fit_hyperparameters(SPACE, three, DATA, default_prior(SPACE, 1.0, 0.1))
    with pytest.raises(TypeError, match="prior must be a HyperPrior"):
        fit_hyperparameters(SPACE, HYPER, DATA, None)  # type: ignore[arg-type]
    fit = fit_hyperparameters(SPACE, HYPER, DATA, default_prior(SPACE, 1.0, 0.1))
    assert len(fit.after.lengthscale) == 2 and all(np.isfinite(fit.after.lengthscale))


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"lengthscale": (0.25, LogNormal(0.25, 0.7))}, TypeError, r"lengthscale\[0\] must be a"),
        ({"lengthscale": LogNormal(0.25, 0.7)}, TypeError, "lengthscale must be a tuple of"),
        ({"variance": 1.0}, TypeError, "variance must be a LogNormal prior, got 1.0"),
        ({"band": 0.1}, TypeError, "band must be a LogNormal prior or None, got 0.1"),
        ({"thresholds": None}, TypeError, "thresholds must be a ThresholdPrior, got None"),
    ],
)
def test_a_hyper_prior_holds_priors(kwargs: dict[str, Any], error: type, message: str) -> None:
    fields: dict[str, Any] = {
        "lengthscale": (LogNormal(0.25, 0.7), LogNormal(0.25, 0.7)),
        "variance": LogNormal(1.0, 0.0),
    }
    with pytest.raises(error, match=message):
        HyperPrior(**{**fields, **kwargs})
    listed = HyperPrior([LogNormal(0.25, 0.7)], LogNormal(1.0, 0.0))  # type: ignore[arg-type]
    assert listed.lengthscale == (LogNormal(0.25, 0.7),)


@pytest.mark.parametrize(
    ("median", "sd", "message"),
    [
        ("1", 0.1, "a prior's median must be positive, got '1'"),
        (True, 0.1, "a prior's median must be positive, got True"),
        (1.0, "0.1", "a prior's sd must be >= 0, got '0.1'"),
        (1.0, np.nan, "a prior's sd must be >= 0, got nan"),
    ],
)
def test_a_log_normal_takes_numbers(median: Any, sd: Any, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        LogNormal(median, sd)
    prior = LogNormal(np.float32(0.5), np.int64(1))  # type: ignore[arg-type]
    assert (prior.median, prior.sd) == (0.5, 1.0) and type(prior.sd) is float


def test_a_threshold_prior_takes_numbers() -> None:
    with pytest.raises(ValueError, match="first_sd must be >= 0, got '1'"):
        ThresholdPrior(first_sd="1")  # type: ignore[arg-type]


def test_hyperparameters_thresholds_in_order_and_plain_values() -> None:
    with pytest.raises(
        ValueError, match=r"thresholds must be in increasing order, got \(1.0, 0.0\)"
    ):
        Hyperparameters((0.3, 0.4), 1.0, 1e-6, thresholds=(1.0, 0.0))
    held = Hyperparameters((0.3, 0.4), 1.0, 1e-6, thresholds=(-1.0, -1.0, 2.0))  # a tie: kept
    assert np.all(np.isfinite(held.log_vector()[:3]))
    made = Hyperparameters(np.array([0.3, 0.4]), np.float64(1.0), 1e-6)  # type: ignore[arg-type]
    assert made == HYPER and made.lengthscale == (0.3, 0.4)
    assert made.with_log_vector(made.log_vector()) == made
