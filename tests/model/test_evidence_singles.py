"""The Laplace evidence with single-action terms (ordinal ratings) besides pairs: its value
against an independent dense computation over all actions, its gradient against finite
differences in every parameter (lengthscales, signal variance, band, thresholds), the ordinal
likelihood's third and threshold derivatives, and the refusal of a likelihood without ``third``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.stats import norm

from gaitpref import Space
from gaitpref.model.evidence import Hyperparameters, PairData, laplace_evidence
from gaitpref.model.likelihood import StackedActionLikelihood
from gaitpref.model.ordinal import OrdinalLikelihood
from gaitpref.model.singles import SingleData, UnsupportedLikelihoodError
from tests.dense_reference import dense_kernel

THRESHOLDS = (-0.05, -0.01, 0.02)
RATING_NOISE = 0.02


def _pairs(rng: np.random.Generator, A: int, N: int, sigma: float = 0.02) -> PairData:
    first, second = rng.integers(0, A, N), rng.integers(0, A, N)
    keep = first != second
    first, second = first[keep], second[keep]
    n = first.size
    banded = rng.random(n) < 0.7
    tie = banded & (rng.random(n) < 0.4)
    return PairData(first, second, rng.uniform(0.5, 1.5, n) * sigma, banded, tie)


def _ratings(rng: np.random.Generator, A: int, n: int, fixed: bool = False) -> SingleData:
    actions = rng.integers(0, A, n).astype(np.intp)
    labels = rng.integers(1, 5, n).astype(np.intp)
    lik = OrdinalLikelihood(labels, np.array(THRESHOLDS), RATING_NOISE, fixed)
    return SingleData(actions, lik)


# -- an independent dense reference (scipy.stats, all A actions, explicit K^-1) ---------------
Terms = tuple[np.ndarray, np.ndarray, np.ndarray]


def _pair_terms(d: np.ndarray, sigma: np.ndarray, band: np.ndarray, tie: np.ndarray) -> Terms:
    s = np.sqrt(2.0) * sigma
    hi, lo = (d + band) / s, (d - band) / s
    z = np.where(tie, norm.cdf(hi) - norm.cdf(lo), norm.cdf(lo))
    dz = np.where(tie, norm.pdf(hi) - norm.pdf(lo), norm.pdf(lo)) / s
    d2z = np.where(tie, -hi * norm.pdf(hi) + lo * norm.pdf(lo), -lo * norm.pdf(lo)) / s**2
    return np.log(z), dz / z, d2z / z - (dz / z) ** 2


def _rating_terms(f: np.ndarray, labels: np.ndarray, thresholds: np.ndarray, noise: float) -> Terms:
    t = np.concatenate([[-1e3], thresholds, [1e3]])  # +-1e3 utility: as good as infinite here
    hi, lo = (t[labels] - f) / noise, (t[labels - 1] - f) / noise
    z = norm.cdf(hi) - norm.cdf(lo)
    dz = -(norm.pdf(hi) - norm.pdf(lo)) / noise
    d2z = -(hi * norm.pdf(hi) - lo * norm.pdf(lo)) / noise**2
    return np.log(z), dz / z, d2z / z - (dz / z) ** 2


def _dense_evidence(
    K: np.ndarray,
    pairs: PairData,
    band: float,
    singles: np.ndarray,
    labels: np.ndarray,
    thresholds: tuple[float, ...],
) -> float:
    A = K.shape[0]
    K_inv = np.linalg.solve(K, np.eye(A))
    G = np.zeros((pairs.size, A))
    G[np.arange(pairs.size), pairs.first] += 1.0
    G[np.arange(pairs.size), pairs.second] -= 1.0
    E = np.zeros((singles.size, A))
    E[np.arange(singles.size), singles] = 1.0
    bands = np.where(pairs.banded, band, 0.0)

    def terms(f: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        lp, g, h = _pair_terms(G @ f, pairs.sigma, bands, pairs.tie)
        lr, gr, hr = _rating_terms(E @ f, labels, np.asarray(thresholds), RATING_NOISE)
        W = -G.T @ (h[:, None] * G) - E.T @ (hr[:, None] * E)
        return np.sum(lp) + np.sum(lr), G.T @ g + E.T @ gr, W

    f = np.zeros(A)
    for _ in range(200):
        _, grad, W = terms(f)
        step = np.linalg.solve(K_inv + W, K_inv @ f - grad)
        f = f - step
        if np.max(np.abs(step)) < 1e-15 * max(1.0, np.max(np.abs(f))):
            break
    logp, _, W = terms(f)
    _, logdet = np.linalg.slogdet(np.eye(A) + K @ W)
    return float(logp - 0.5 * f @ K_inv @ f - 0.5 * logdet)


@pytest.mark.parametrize("seed", range(3))
def test_evidence_with_ratings_and_preferences_equals_the_dense_reference(
    small_space: Space, seed: int
) -> None:
    rng = np.random.default_rng(300 + seed)
    A = len(small_space)
    pairs = _pairs(rng, A, int(rng.integers(5, 40)))
    singles = _ratings(rng, A, int(rng.integers(5, 30)))
    thresholds = (-0.04, 0.0, 0.03)  # not the likelihood's own: the hyperparameters' are used
    hyper = Hyperparameters((0.03, 0.08), 0.005, 1e-7, 0.015, thresholds)
    ev = laplace_evidence(small_space, hyper, pairs, singles=singles)
    K = dense_kernel(small_space.points, (0.03, 0.08), 0.005, 1e-7)
    assert isinstance(singles.likelihood, OrdinalLikelihood)
    ref = _dense_evidence(K, pairs, 0.015, singles.actions, singles.likelihood.labels, thresholds)
    assert ev.value == pytest.approx(ref, rel=1e-8)
    assert ev.gradient.shape == (2 + 2 + 3,)


def test_ratings_alone_and_the_empty_case(small_space: Space) -> None:
    rng = np.random.default_rng(7)
    singles = _ratings(rng, len(small_space), 12)
    none = PairData(*(np.zeros(0, dtype=np.intp),) * 2, np.zeros(0), *(np.zeros(0, bool),) * 2)
    hyper = Hyperparameters((0.03, 0.08), 0.005, 1e-7, 0.0, THRESHOLDS)
    ev = laplace_evidence(small_space, hyper, none, singles=singles)
    K = dense_kernel(small_space.points, (0.03, 0.08), 0.005, 1e-7)
    assert isinstance(singles.likelihood, OrdinalLikelihood)
    ref = _dense_evidence(K, none, 0.0, singles.actions, singles.likelihood.labels, THRESHOLDS)
    assert ev.value == pytest.approx(ref, rel=1e-8)
    with pytest.raises(ValueError, match="at least one observation"):
        laplace_evidence(small_space, hyper, none, singles=_ratings(rng, len(small_space), 0))


def _finite_difference_check(space: Space, hyper: Hyperparameters, pairs: PairData,
                             singles: SingleData) -> None:  # fmt: skip
    ev = laplace_evidence(space, hyper, pairs, singles=singles)
    theta = hyper.log_vector()
    eps = 1e-5
    checked = 0
    for j in np.flatnonzero(np.isfinite(theta)):
        up, down = theta.copy(), theta.copy()
        up[j] += eps
        down[j] -= eps
        fd = (
            laplace_evidence(space, hyper.with_log_vector(up), pairs, singles=singles).value
            - laplace_evidence(space, hyper.with_log_vector(down), pairs, singles=singles).value
        ) / (2 * eps)
        assert ev.gradient[j] == pytest.approx(fd, rel=1e-5, abs=1e-6), j
        checked += 1
    assert checked == theta.size - (hyper.band == 0)


@pytest.mark.parametrize(("seed", "band"), [(0, 0.01), (1, 0.03), (2, 0.0)])
def test_gradient_matches_finite_differences_in_every_parameter(
    small_space: Space, seed: int, band: float
) -> None:
    rng = np.random.default_rng(400 + seed)
    pairs = _pairs(rng, len(small_space), 40)
    if band == 0.0:  # no band: ties cannot be modelled, all observations plain probit
        keep = ~pairs.tie
        pairs = PairData(pairs.first[keep], pairs.second[keep], pairs.sigma[keep],
                         pairs.banded[keep] & False, pairs.tie[keep])  # fmt: skip
    singles = _ratings(rng, len(small_space), 25)
    hyper = Hyperparameters((0.025, 0.1), 0.004, 4e-7, band, (-0.045, -0.005, 0.03))
    _finite_difference_check(small_space, hyper, pairs, singles)


def test_fixed_thresholds_and_other_likelihoods_take_the_kernel_part(small_space: Space) -> None:
    """Thresholds fixed by the config are not hyperparameters: the gradient has no entries for
    them and its kernel entries still match finite differences; so with a Gaussian score."""
    rng = np.random.default_rng(9)
    pairs = _pairs(rng, len(small_space), 30)
    fixed = _ratings(rng, len(small_space), 20, fixed=True)
    assert fixed.thresholds is None
    hyper = Hyperparameters((0.025, 0.1), 0.004, 4e-7, 0.01)
    ev = laplace_evidence(small_space, hyper, pairs, singles=fixed)
    assert ev.gradient.shape == (4,)
    _finite_difference_check(small_space, hyper, pairs, fixed)
    y = rng.normal(0.0, 0.05, 10)
    score = SingleData(rng.integers(0, len(small_space), 10).astype(np.intp), Gaussian(y, 0.03))
    stacked = SingleData(
        np.concatenate([score.actions, fixed.actions]),
        StackedActionLikelihood(((10, score.likelihood), (20, fixed.likelihood))),
    )
    _finite_difference_check(small_space, hyper, pairs, stacked)


@dataclass(frozen=True)
class Gaussian:
    y: np.ndarray
    s: float

    def terms(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        r = self.y - values
        return -0.5 * (r / self.s) ** 2, r / self.s**2, np.full(values.shape, self.s**-2)

    def third(self, values: np.ndarray) -> np.ndarray:
        return np.zeros(values.shape)


@dataclass(frozen=True)
class NoThird:
    def terms(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return -0.5 * values**2, -values, np.ones(values.shape)


def test_a_likelihood_without_third_is_refused_by_name() -> None:
    with pytest.raises(UnsupportedLikelihoodError, match="NoThird has no third"):
        SingleData(np.array([0, 1], dtype=np.intp), NoThird())
    two = OrdinalLikelihood(np.array([1]), np.array(THRESHOLDS), RATING_NOISE)
    with pytest.raises(UnsupportedLikelihoodError, match="more than one"):
        SingleData(np.array([0, 1], dtype=np.intp), StackedActionLikelihood(((1, two), (1, two))))


@given(
    st.floats(-0.12, 0.12),
    st.integers(1, 4),
    st.floats(0.005, 0.05),
)
def test_third_and_threshold_derivatives_match_finite_differences(
    f: float, label: int, noise: float
) -> None:
    t = np.array(THRESHOLDS)
    lik = OrdinalLikelihood(np.array([label]), t, noise)
    x = np.array([f])
    h = 1e-6 * noise
    c_up, c_down = lik.terms(x + h)[2], lik.terms(x - h)[2]
    scale = noise**-3
    assert lik.third(x)[0] == pytest.approx(
        (c_up - c_down)[0] / (2 * h), rel=1e-4, abs=1e-4 * scale
    )
    dl, dg, dc = lik.threshold_terms(x)
    for j in range(t.size):
        up, down = t.copy(), t.copy()
        up[j] += h
        down[j] -= h
        tu, td = lik.with_thresholds(up).terms(x), lik.with_thresholds(down).terms(x)
        for k, (got, unit) in enumerate(((dl, noise**-1), (dg, noise**-2), (dc, noise**-3))):
            fd = (tu[k][0] - td[k][0]) / (2 * h)
            assert got[0, j] == pytest.approx(fd, rel=1e-4, abs=1e-4 * unit), (j, k)
        if label not in (j + 1, j + 2):  # only the thresholds around the category move it
            assert dl[0, j] == dg[0, j] == dc[0, j] == 0.0


def test_far_tails_stay_finite() -> None:
    f = np.array([-50.0, -1.0, -0.2, 0.2, 1.0, 50.0])
    for label in range(1, 5):
        lik = OrdinalLikelihood(np.full(f.size, label), np.array(THRESHOLDS), RATING_NOISE)
        assert np.all(np.isfinite(lik.third(f)))
        assert all(np.all(np.isfinite(a)) for a in lik.threshold_terms(f))


def test_thresholds_vector_round_trips_and_stays_increasing() -> None:
    hyper = Hyperparameters((0.1,), 0.5, 1e-6, 0.0, (-0.3, 0.1, 0.2))
    theta = hyper.log_vector()
    assert theta.shape == (1 + 2 + 3,)
    back = hyper.with_log_vector(theta)
    assert back.thresholds == pytest.approx(hyper.thresholds)
    theta[3:] = [5.0, -10.0, 3.0]  # any vector gives increasing thresholds (to rounding)
    t = np.array(hyper.with_log_vector(theta).thresholds)
    assert np.all(np.diff(t) > 0)
    assert Hyperparameters((0.1,), 0.5, 1e-6).log_vector().shape == (3,)


@pytest.mark.parametrize(("seed", "band"), [(0, 0.01), (2, 0.0)])
def test_the_sparse_incidence_gives_the_dense_evidence_and_gradient(
    small_space: Space, seed: int, band: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``evidence_from_prior(..., sparse=True)`` (a warm start's rho fit) against the dense
    ``G``: ties, the band, ratings and fitted thresholds, every entry of the gradient."""
    from gaitpref.model import evidence

    rng = np.random.default_rng(500 + seed)
    pairs = _pairs(rng, len(small_space), 40)
    if band == 0.0:
        keep = ~pairs.tie
        pairs = PairData(pairs.first[keep], pairs.second[keep], pairs.sigma[keep],
                         pairs.banded[keep] & False, pairs.tie[keep])  # fmt: skip
    singles = _ratings(rng, len(small_space), 25)
    hyper = Hyperparameters((0.025, 0.1), 0.004, 4e-7, band, (-0.045, -0.005, 0.03))
    dense = laplace_evidence(small_space, hyper, pairs, singles=singles)
    real = evidence.evidence_from_prior

    def sparse(*args: object, **kwargs: object) -> evidence.Evidence:
        return real(*args, **kwargs, sparse=True)  # type: ignore[arg-type]

    monkeypatch.setattr(evidence, "evidence_from_prior", sparse)
    got = laplace_evidence(small_space, hyper, pairs, singles=singles)
    assert got.value == dense.value  # the same fit
    assert np.all(np.isfinite(dense.gradient))
    np.testing.assert_allclose(got.gradient, dense.gradient, rtol=1e-9, atol=1e-12)
