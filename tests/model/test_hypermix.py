"""Lengthscale hypotheses weighted by Laplace evidence x prior, against a dense reference."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gaitpref import Space
from gaitpref.model.evidence import Hyperparameters, PairData
from gaitpref.model.hyperfit import HyperPrior, LogNormal
from gaitpref.model.hypermix import weigh_hypotheses
from tests.dense_reference import dense_kernel, dense_laplace_ordered

PRIOR = HyperPrior((LogNormal(0.025, 0.7), LogNormal(0.075, 0.7)), LogNormal(0.005, 0.0))
CENTRE = Hyperparameters((0.03, 0.08), 0.005, 1e-7)


def _data(space: Space, seed: int, n: int) -> PairData:
    rng = np.random.default_rng(seed)
    u = np.sin(9 * space.points[:, 0]) + 3 * space.points[:, 1]
    first, second = rng.integers(0, len(space), n), rng.integers(0, len(space), n)
    keep = first != second
    first, second = first[keep], second[keep]
    win = np.where(u[first] >= u[second], first, second)
    lose = np.where(u[first] >= u[second], second, first)
    m = win.size
    return PairData(win, lose, np.full(m, 0.02), np.zeros(m, bool), np.zeros(m, bool))


def _dense_weights(space: Space, data: PairData, factors: tuple[float, ...]) -> np.ndarray:
    logs = []
    for c in factors:
        scales = tuple(c * v for v in CENTRE.lengthscale)
        K = dense_kernel(space.points, scales, CENTRE.variance, CENTRE.jitter)
        zeros = np.zeros(data.size)
        _, _, ev = dense_laplace_ordered(K, data.first, data.second, data.sigma, zeros, data.tie)
        prior = sum(
            -0.5 * ((math.log(v) - math.log(p.median)) / p.sd) ** 2
            for v, p in zip(scales, PRIOR.lengthscale, strict=True)
        )
        logs.append(ev + prior)
    w = np.exp(np.array(logs) - max(logs))
    out: np.ndarray = w / w.sum()
    return out


@pytest.mark.parametrize(("seed", "n"), [(0, 12), (1, 30), (2, 60)])
def test_weights_equal_the_dense_evidence_times_prior(
    small_space: Space, seed: int, n: int
) -> None:
    data = _data(small_space, seed, n)
    factors = (0.5, 0.71, 1.0, 1.41, 2.0)
    got = weigh_hypotheses(small_space, CENTRE, factors, data, PRIOR)
    weights = np.array([h.weight for h in got])
    np.testing.assert_allclose(weights, _dense_weights(small_space, data, factors), rtol=1e-6)
    assert weights.sum() == pytest.approx(1.0)
    assert [h.hyper.lengthscale for h in got] == [
        tuple(c * v for v in CENTRE.lengthscale) for c in factors
    ]
    assert not np.allclose(weights, weights[0])  # the data tell the hypotheses apart


def test_one_hypothesis_has_all_the_weight(small_space: Space) -> None:
    (only,) = weigh_hypotheses(small_space, CENTRE, (1.0,), _data(small_space, 3, 20), PRIOR)
    assert only.weight == 1.0 and only.hyper == CENTRE


@pytest.mark.parametrize("factors", [(), (1.0, -0.5), (float("nan"),)])
def test_bad_factors_are_refused(small_space: Space, factors: tuple[float, ...]) -> None:
    with pytest.raises(ValueError, match="hypotheses"):
        weigh_hypotheses(small_space, CENTRE, factors, _data(small_space, 0, 10), PRIOR)
