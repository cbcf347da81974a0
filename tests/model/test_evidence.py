"""The Laplace evidence and its gradient; the tie likelihood's Newton mode against a dense one."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import PreferenceGP, Space, SquaredExponential
from gaitpref.model.evidence import Hyperparameters, PairData, laplace_evidence
from tests.dense_reference import dense_kernel, dense_laplace_ordered


def _data(rng: np.random.Generator, A: int, N: int, sigma: float = 0.02) -> PairData:
    first, second = rng.integers(0, A, N), rng.integers(0, A, N)
    keep = first != second
    first, second = first[keep], second[keep]
    n = first.size
    banded = rng.random(n) < 0.7  # the rest are coactive-like plain probit preferences
    tie = banded & (rng.random(n) < 0.4)
    return PairData(first, second, rng.uniform(0.5, 1.5, n) * sigma, banded, tie)


@pytest.mark.parametrize("seed", range(3))
def test_mode_with_ties_equals_the_dense_reference(
    small_space: Space, small_kernel: SquaredExponential, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    data = _data(rng, len(small_space), int(rng.integers(10, 60)))
    band = 0.015
    post = PreferenceGP(small_space, small_kernel, 0.02).posterior_from(
        data.first, data.second, data.likelihood(band)
    )
    K = dense_kernel(small_space.points, (0.03, 0.08), 0.005, 1e-7)
    bands = np.where(data.banded, band, 0.0)
    f_ref, cov_ref, ev_ref = dense_laplace_ordered(
        K, data.first, data.second, data.sigma, bands, data.tie
    )
    assert np.allclose(post.mean, f_ref, rtol=1e-8, atol=1e-8 * np.max(np.abs(f_ref)))
    assert np.allclose(post.covariance(), cov_ref, rtol=1e-7, atol=1e-8 * np.max(cov_ref))
    hyper = Hyperparameters((0.03, 0.08), 0.005, 1e-7, band)
    assert laplace_evidence(small_space, hyper, data).value == pytest.approx(ev_ref, rel=1e-8)
    assert post.log_evidence == pytest.approx(ev_ref, rel=1e-8)


@pytest.mark.parametrize(("seed", "band"), [(0, 0.01), (1, 0.03), (2, 0.0)])
def test_gradient_matches_finite_differences(small_space: Space, seed: int, band: float) -> None:
    rng = np.random.default_rng(seed)
    data = _data(rng, len(small_space), 50)
    if band == 0.0:  # no band: ties cannot be modelled, all observations plain probit
        keep = ~data.tie
        data = PairData(
            data.first[keep], data.second[keep], data.sigma[keep], data.banded[keep] & False,
            data.tie[keep],
        )  # fmt: skip
    hyper = Hyperparameters((0.025, 0.1), 0.004, 4e-7, band)
    ev = laplace_evidence(small_space, hyper, data)
    theta = hyper.log_vector()
    free = np.isfinite(theta)
    eps = 1e-5
    for j in np.flatnonzero(free):
        up, down = theta.copy(), theta.copy()
        up[j] += eps
        down[j] -= eps
        fd = (
            laplace_evidence(small_space, hyper.with_log_vector(up), data).value
            - laplace_evidence(small_space, hyper.with_log_vector(down), data).value
        ) / (2 * eps)
        assert ev.gradient[j] == pytest.approx(fd, rel=1e-5, abs=1e-6), j
    if band == 0.0:
        assert ev.gradient[-1] == 0.0


def test_jitter_keeps_its_ratio_and_the_scale_redundancy_holds(small_space: Space) -> None:
    """Scaling s, sigma and the band together leaves the likelihood's probabilities unchanged:
    the evidence moves only by the Jacobian of f's scale, so sigma is held fixed in the fit."""
    rng = np.random.default_rng(4)
    data = _data(rng, len(small_space), 40)
    hyper = Hyperparameters((0.03, 0.08), 0.005, 5e-7, 0.01)
    moved = hyper.with_log_vector(hyper.log_vector() + np.array([0, 0, np.log(4.0), 0]))
    assert moved.jitter / moved.variance == pytest.approx(hyper.jitter / hyper.variance)
    c = 3.0
    scaled_data = PairData(data.first, data.second, c * data.sigma, data.banded, data.tie)
    scaled = Hyperparameters(
        hyper.lengthscale, c**2 * hyper.variance, c**2 * hyper.jitter, c * 0.01
    )
    a = laplace_evidence(small_space, hyper, data)
    b = laplace_evidence(small_space, scaled, scaled_data)
    assert a.value == pytest.approx(b.value, rel=1e-9)
    assert np.allclose(a.gradient, b.gradient, rtol=1e-6, atol=1e-9)
