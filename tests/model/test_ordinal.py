"""The ordered probit on single utilities (``model/ordinal.py``): derivatives against finite
differences and an independent log-probability, stability in the tails, the mixed Laplace fit
(preferences and ratings) against a dense Newton, and ``K = 2`` ratings as a threshold model."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.stats import norm

from gaitpref import PreferenceGP, Space, SquaredExponential
from gaitpref.model.likelihood import Probit
from gaitpref.model.ordinal import Ordinal, rating_likelihood, rating_probabilities
from tests.dense_reference import dense_kernel

THRESHOLDS = (-0.05, -0.01, 0.02)


def _lik(labels: list[int], noise: float = 0.02):  # type: ignore[no-untyped-def]
    return rating_likelihood(Ordinal(4, THRESHOLDS, noise), 0.005, labels)


def _reference_logp(f: float, label: int, noise: float) -> float:
    t = (-np.inf, *THRESHOLDS, np.inf)
    lo, hi = (t[label - 1] - f) / noise, (t[label] - f) / noise
    if lo > 0:  # both in the upper tail: the survival functions keep the digits
        return float(np.log(norm.sf(lo) - norm.sf(hi)))
    return float(np.log(norm.cdf(hi) - norm.cdf(lo)))


@given(
    st.floats(-0.08, 0.08),
    st.integers(1, 4),
    st.floats(0.005, 0.05),
)
def test_terms_match_finite_differences_and_a_direct_log_probability(
    f: float, label: int, noise: float
) -> None:
    lik = _lik([label], noise)
    logp, g, c = lik.terms(np.array([f]))
    assert logp[0] == pytest.approx(_reference_logp(f, label, noise), rel=1e-9, abs=1e-9)
    h = 1e-6 * noise
    up, down = lik.terms(np.array([f + h])), lik.terms(np.array([f - h]))
    assert g[0] == pytest.approx((up[0][0] - down[0][0]) / (2 * h), rel=1e-5, abs=1e-4 / noise)
    assert c[0] == pytest.approx(-(up[1][0] - down[1][0]) / (2 * h), rel=1e-4, abs=1e-2 / noise**2)
    assert 0.0 <= c[0] <= 1.0 / noise**2 + 1e-9


def test_far_tails_stay_finite_and_log_concave() -> None:
    f = np.array([-50.0, -1.0, 1.0, 50.0])
    for label in range(1, 5):
        logp, g, c = _lik([label] * 4).terms(f)
        assert np.all(np.isfinite(logp)) and np.all(np.isfinite(g)) and np.all(np.isfinite(c))
        assert np.all(c >= 0.0)
    # the worst category at a huge utility: log p ~ -f^2 / (2 s^2), not -inf
    logp, _, _ = _lik([1]).terms(np.array([5.0]))
    assert -4e4 < logp[0] < -3e4


def test_probabilities_sum_to_one_and_prior_thresholds_split_evenly() -> None:
    ordinal = Ordinal(["very bad", "bad", "okay", "good"], noise=0.02)
    t = ordinal.thresholds_for(0.005)
    assert np.all(np.diff(t) > 0)
    p = rating_probabilities(ordinal, 0.005, np.zeros(1), np.array([0.005]))
    assert np.allclose(p, 0.25)  # the prior predictive: every category equally likely
    p = rating_probabilities(ordinal, 0.005, np.linspace(-0.2, 0.2, 9), np.full(9, 1e-4))
    assert np.allclose(p.sum(axis=1), 1.0)
    assert np.all(np.diff(p[:, -1]) >= 0) and p[-1, -1] > 0.99  # better gaits, more "good"


@np.errstate(invalid="ignore")  # inf * 0 at the open ends, masked below
def _dense(
    K: np.ndarray,
    w: np.ndarray,
    l: np.ndarray,
    sigma: float,
    single: np.ndarray,
    labels: np.ndarray,
    noise: float,
) -> tuple[np.ndarray, np.ndarray]:
    A = K.shape[0]
    K_inv = np.linalg.solve(K, np.eye(A))
    G = np.zeros((w.size, A))
    G[np.arange(w.size), w], G[np.arange(w.size), l] = 1.0, -1.0
    t = np.array([-np.inf, *THRESHOLDS, np.inf])
    scale = np.sqrt(2.0) * sigma

    def derivs(f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        z = (G @ f) / scale
        r = np.exp(norm.logpdf(z) - norm.logcdf(z))
        fs = f[single]
        lo, hi = (t[labels - 1] - fs) / noise, (t[labels] - fs) / noise
        Z = norm.cdf(hi) - norm.cdf(lo)
        plo, phi_ = norm.pdf(lo), norm.pdf(hi)
        dlo = np.where(np.isinf(lo), 0.0, lo * plo)
        dhi = np.where(np.isinf(hi), 0.0, hi * phi_)
        gs = (plo - phi_) / (noise * Z)
        cs = (((plo - phi_) / Z) ** 2 + (dhi - dlo) / Z) / noise**2
        grad = G.T @ (r / scale) + np.bincount(single, gs, A)
        lam = G.T @ (((r**2 + z * r) / scale**2)[:, None] * G) + np.diag(np.bincount(single, cs, A))
        return grad, lam

    f = np.zeros(A)
    for _ in range(200):
        grad, lam = derivs(f)
        step = np.linalg.solve(K_inv + lam, K_inv @ f - grad)
        f = f - step
        if np.max(np.abs(step)) < 1e-15 * max(1.0, np.max(np.abs(f))):
            break
    _, lam = derivs(f)
    return f, np.linalg.solve(K_inv + lam, np.eye(A))


@pytest.mark.parametrize("seed", range(3))
def test_mixed_fit_matches_a_dense_newton(
    small_space: Space, small_kernel: SquaredExponential, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    A = len(small_space)
    w, l = rng.integers(0, A, 15), rng.integers(0, A, 15)
    w, l = w[w != l], l[w != l]
    single = rng.integers(0, A, 20)
    labels = rng.integers(1, 5, 20)
    gp = PreferenceGP(small_space, small_kernel, 0.02)
    post = gp.posterior_from(
        w,
        l,
        Probit(np.full(w.size, 0.02)),
        single=single,
        single_likelihood=_lik(list(labels)),
    )
    f_ref, cov_ref = _dense(
        dense_kernel(small_space.points, (0.03, 0.08), 0.005, 1e-7),
        w,
        l,
        0.02,
        single,
        labels,
        0.02,
    )
    assert np.allclose(post.mean, f_ref, rtol=1e-8, atol=1e-8 * np.max(np.abs(f_ref)))
    assert np.allclose(post.covariance(), cov_ref, rtol=1e-7, atol=1e-8 * np.max(np.abs(cov_ref)))


def test_two_categories_and_no_preferences_recover_a_threshold_model(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    """Gaits whose true utility is above the threshold are rated 2, the others 1: the posterior
    puts the rated gaits on the right side of the threshold."""
    rng = np.random.default_rng(4)
    A = len(small_space)
    truth = 0.1 * np.sin(3 * small_space.points[:, 0] / 0.1) * np.cos(small_space.points[:, 1])
    rated = rng.choice(A, size=min(A, 60), replace=False)
    labels = np.where(truth[rated] > 0.0, 2, 1)
    ordinal = Ordinal(["bad", "good"], thresholds=[0.0], noise=0.01)
    gp = PreferenceGP(small_space, small_kernel, 0.02)
    none = np.zeros(0, dtype=np.intp)
    post = gp.posterior_from(
        none,
        none,
        Probit(np.zeros(0)),
        single=rated,
        single_likelihood=rating_likelihood(ordinal, small_kernel.variance, labels),
    )
    predicted = np.where(np.asarray(post.mean)[rated] > 0.0, 2, 1)
    assert np.mean(predicted == labels) >= 0.95


def test_bad_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="increasing"):
        Ordinal(3, [0.1, -0.1])
    with pytest.raises(ValueError, match="2 thresholds"):
        Ordinal(3, [0.1])
    with pytest.raises(ValueError, match="noise"):
        Ordinal(3, noise=0.0)
    with pytest.raises(ValueError, match="not a category"):
        Ordinal(["bad", "good"]).label_index("okay")
    assert Ordinal(["bad", "good"]).label_index("good") == 2


def test_public_api_ratings_and_predictive_probabilities(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    ordinal = Ordinal(["very bad", "bad", "okay", "good"], noise=0.02)
    gp = PreferenceGP(small_space, small_kernel, 0.02, ordinal=ordinal)
    ratings = [(3, "good"), (30, "very bad"), (31, 1), (7, "okay")]
    post = gp.posterior([3, 7], [30, 31], ratings=ratings)
    same = gp.posterior_from(
        np.array([3, 7]),
        np.array([30, 31]),
        Probit(np.full(2, 0.02)),
        single=np.array([3, 30, 31, 7]),
        single_likelihood=rating_likelihood(ordinal, small_kernel.variance, [4, 1, 1, 3]),
    )
    assert np.array_equal(post.mean, same.mean)
    rng = np.random.default_rng(0)
    draws = post.sample(rng, 20_000)
    # P(a > b): Monte Carlo over the posterior and the probit noise
    a, b = 3, 30
    noisy = draws[:, a] - draws[:, b] + rng.normal(0, np.sqrt(2) * 0.02, draws.shape[0])
    assert post.preference_probability(a, b) == pytest.approx(np.mean(noisy > 0), abs=0.015)
    probs = post.rating_probabilities([3, 30, 20])
    assert probs.shape == (3, 4) and np.allclose(probs.sum(axis=1), 1.0)
    t = np.array([-np.inf, *ordinal.thresholds_for(small_kernel.variance), np.inf])
    latent = draws[:, 3] + rng.normal(0, 0.02, draws.shape[0])
    mc = np.histogram(latent, bins=t)[0] / draws.shape[0]
    assert np.allclose(probs[0], mc, atol=0.015)
    with pytest.raises(ValueError, match="ordinal"):
        PreferenceGP(small_space, small_kernel, 0.02).posterior([1], [2], ratings=[(1, 2)])
