"""The evidence, population and optimiser entry points name a bad index, code, start or count.

Before: ``PairData`` took float indices (0.5 was truncated to gait 0 by the kernel) and negative
ones (``laplace_evidence`` failed in NumPy, "index -1 is out of bounds"; a population's code -1
was read as the last gait of subject -1); an off-grid index was NumPy's error; a Laplace start
of the wrong length was SciPy's "shapes ... are incompatible"; ``PopulationModel.posterior``
took a target of -1 or 0.5 (truncated to subject 0); ``PreferenceGP.posterior(init=array)`` was
an AttributeError; ``max_evaluations`` of 0, -1, 2.5 or True ran one evaluation and reported
the limit reached.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from gaitpref import Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.model import (
    Hyperparameters,
    LogitNormal,
    PairData,
    PopulationModel,
    Probit,
    default_prior,
    fit_hyperparameters,
    fit_population,
    laplace_evidence,
)
from gaitpref.model.laplace import fit_laplace
from gaitpref.model.share_fit import fit_share

SPACE = Space([Feature.linspace("a", 0.0, 1.0, 5), Feature.linspace("b", 0.0, 1.0, 3)])
KERNEL = SquaredExponential((0.3, 0.4), 1.0, 1e-6)
HYPER = Hyperparameters((0.3, 0.4), 1.0, 1e-6)
NO = np.zeros(2, dtype=bool)


def _data(first: object, second: object) -> PairData:
    return PairData(np.asarray(first), np.asarray(second), np.full(2, 0.1), NO, NO)


@pytest.mark.parametrize(
    ("first", "message"),
    [
        ([0.5, 1.0], r"first must be a 1-D array of integer indices, got dtype float64"),
        ([True, False], r"first must be a 1-D array of integer indices, got dtype bool"),
        ([-1, 2], r"first must hold indices >= 0, got -1"),
    ],
)
def test_pair_data_indices_are_integers_from_zero(first: list[object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        _data(first, [3, 4])


def test_the_evidence_names_an_index_off_the_grid() -> None:
    with pytest.raises(IndexError, match=r"data.second\[1\] = 15 is off the grid \(0..14\)"):
        laplace_evidence(SPACE, HYPER, _data([0, 1], [3, 15]))
    assert np.isfinite(laplace_evidence(SPACE, HYPER, _data([0, 1], [3, 14])).value)


def test_a_laplace_start_of_the_wrong_length_is_named() -> None:
    with pytest.raises(ValueError, match=r"init must hold one value per visited action \(4\)"):
        laplace_evidence(SPACE, HYPER, _data([0, 1], [3, 4]), init=np.zeros(7))
    k_vv = KERNEL.cross(SPACE, np.arange(3), rows=np.arange(3))
    first, second = np.array([0]), np.array([1])
    with pytest.raises(ValueError, match=r"init must hold one value per visited action \(3\)"):
        fit_laplace(k_vv, np.arange(3), first, second, Probit(np.full(1, 0.1)), np.zeros((3, 1)))


def test_population_posteriors_name_a_bad_code_or_target() -> None:
    model = PopulationModel(SPACE, KERNEL, 0.5, 0.1)
    lik = Probit(np.full(1, 0.1))
    with pytest.raises(ValueError, match="first must hold indices >= 0, got -1"):
        model.posterior(np.array([-1]), np.array([3]), lik, 0)
    with pytest.raises(ValueError, match="single must be a 1-D array of integer indices"):
        model.posterior(np.array([0]), np.array([3]), lik, 0, single=np.array([0.5]))
    with pytest.raises(ValueError, match="2 first but 1 second codes"):
        model.posterior(np.array([0, 1]), np.array([3]), lik, 0)
    for target in (-1, 0.5, True, None):
        with pytest.raises(ValueError, match="target must be a subject, an integer >= 0"):
            model.posterior(np.array([0]), np.array([3]), lik, target)  # type: ignore[arg-type]
    ok = model.posterior(np.array([0, 15 + 2]), np.array([3, 15 + 4]), Probit(np.full(2, 0.1)), 1)
    assert np.all(np.isfinite(ok.mean))


def test_init_must_be_a_posterior() -> None:
    gp = PreferenceGP(SPACE, KERNEL, 0.1)
    with pytest.raises(TypeError, match="init must be a Posterior"):
        gp.posterior([0], [1], init=np.zeros(15))  # type: ignore[arg-type]
    assert gp.posterior([0], [1], init=gp.prior()).fit is not None


FITS: dict[str, Callable[[object], object]] = {
    "fit_hyperparameters": lambda n: fit_hyperparameters(
        SPACE, HYPER, _data([0, 1], [3, 4]), default_prior(SPACE, 1.0, 0.1),
        max_evaluations=n,  # type: ignore[arg-type]
    ),
    "fit_population": lambda n: fit_population(
        SPACE, HYPER, 0.5, _data([0, 16], [3, 19]), default_prior(SPACE, 1.0, 0.1),
        max_evaluations=n,  # type: ignore[arg-type]
    ),
    "fit_share": lambda n: fit_share(
        SPACE, HYPER, 0.5, 0.5, _data([0, 16], [3, 19]), LogitNormal(),
        max_evaluations=n,  # type: ignore[arg-type]
    ),
}  # fmt: skip


@pytest.mark.parametrize("count", [0, -1, 2.5, True, None])
@pytest.mark.parametrize("name", sorted(FITS))
def test_evaluation_budgets_are_counts(name: str, count: object) -> None:
    with pytest.raises(ValueError, match="max_evaluations must be an integer >= 1"):
        FITS[name](count)


@pytest.mark.parametrize("name", sorted(FITS))
def test_a_one_evaluation_budget_runs(name: str) -> None:
    FITS[name](np.int64(1))


def _problem() -> tuple[Any, ...]:
    visited = np.array([1, 3, 5], dtype=np.intp)
    k_vv = KERNEL.cross(SPACE, visited, rows=visited)
    return k_vv, visited, np.array([0, 1]), np.array([1, 2]), Probit(np.full(2, 0.1))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        # a tolerance of inf accepted the start (the prior) as the mode, silently
        ({"tol": np.inf}, r"tol must be a number in \(0, 1\), got inf"),
        ({"tol": 1.0}, r"tol must be a number in \(0, 1\), got 1.0"),
        ({"tol": np.nan}, "tol must be a number"),
        ({"tol": 0.0}, "tol must be a number"),
        ({"tol": "1e-9"}, "tol must be a number"),
        # 0 or less failed with "did not converge in 0 Newton iterations"; 10**12 had no bound
        ({"max_iter": 0}, r"max_iter must be an integer in 1\.\.10,000, got 0"),
        ({"max_iter": 10**12}, "max_iter must be an integer"),
        ({"max_iter": 2.5}, "max_iter must be an integer"),
        ({"max_iter": True}, "max_iter must be an integer"),
    ],
)
def test_a_laplace_fit_names_a_bad_tolerance_or_budget(
    kwargs: dict[str, Any], message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        fit_laplace(*_problem(), **kwargs)


def test_a_laplace_fit_names_a_bad_problem() -> None:
    k_vv, visited, first, second, lik = _problem()
    with pytest.raises(ValueError, match=r"first holds 5, not an index into the 3 visited"):
        fit_laplace(k_vv, visited, np.array([0, 5]), second, lik)  # NumPy's IndexError before
    with pytest.raises(ValueError, match=r"second holds -1"):
        fit_laplace(k_vv, visited, first, np.array([1, -1]), lik)
    with pytest.raises(ValueError, match="first and second differ in shape"):
        fit_laplace(k_vv, visited, first, np.array([1]), lik)
    with pytest.raises(ValueError, match=r"k_vv must be the \(2,\) visited actions' square"):
        fit_laplace(k_vv, visited[:2], first, second, lik)
    with pytest.raises(ValueError, match="must be finite"):  # blamed on the likelihood before
        fit_laplace(np.full((3, 3), np.nan), visited, first, second, lik)
    budget: Any = np.int64(50)
    fit = fit_laplace(k_vv, visited, first, second, lik, tol=1e-9, max_iter=budget)
    exact = fit_laplace(k_vv, visited, first, second, lik)
    assert np.allclose(fit.mode, exact.mode, atol=1e-8) and fit.mode[0] > 0 > fit.mode[2]
