"""The ordered-probit (tie) likelihood against direct formulas and finite differences."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import norm

from gaitpref.model.likelihood import OrderedProbit, Probit


def _direct_logp(d: float, sigma: float, band: float, tie: bool) -> float:
    s = np.sqrt(2.0) * sigma
    if tie:
        return float(np.log(norm.cdf((d + band) / s) - norm.cdf((d - band) / s)))
    return float(norm.logcdf((d - band) / s))


def _one(sigma: float, band: float, tie: bool) -> OrderedProbit:
    return OrderedProbit(np.array([sigma]), np.array([band]), np.array([tie]))


@settings(max_examples=60, deadline=None)
@given(
    z=st.floats(-6.0, 6.0),
    sigma=st.floats(0.005, 0.05),
    band_ratio=st.floats(0.05, 3.0),
    tie=st.booleans(),
)
def test_derivatives_match_finite_differences(
    z: float, sigma: float, band_ratio: float, tie: bool
) -> None:
    d, band = z * sigma, band_ratio * sigma
    lik = _one(sigma, band, tie)
    x = np.array([d])
    logp, g, c = lik.terms(x)
    assert logp[0] == pytest.approx(_direct_logp(d, sigma, band, tie), rel=1e-10, abs=1e-12)
    h = 1e-4 * sigma

    def at(k: int, dd: float) -> float:
        return float(lik.terms(np.array([dd]))[k][0])

    scale = 1.0 / sigma  # g ~ 1/sigma, c ~ 1/sigma^2, c' ~ 1/sigma^3
    assert g[0] == pytest.approx((at(0, d + h) - at(0, d - h)) / (2 * h), abs=1e-6 * scale)
    assert -c[0] == pytest.approx((at(1, d + h) - at(1, d - h)) / (2 * h), abs=1e-6 * scale**2)
    third = lik.third(x)[0]
    assert third == pytest.approx((at(2, d + h) - at(2, d - h)) / (2 * h), abs=1e-5 * scale**3)
    # derivatives in log band
    e = 1e-6
    up, down = _one(sigma, band * np.exp(e), tie), _one(sigma, band * np.exp(-e), tie)
    for k, value in enumerate(lik.band_terms(x)):
        fd = (up.terms(x)[k][0] - down.terms(x)[k][0]) / (2 * e)
        assert value[0] == pytest.approx(fd, rel=1e-5, abs=1e-6 * scale**k)


def test_zero_band_is_the_papers_probit_bit_for_bit() -> None:
    rng = np.random.default_rng(0)
    sigma, d = rng.uniform(0.005, 0.05, 50), rng.normal(0, 0.05, 50)
    ours = OrderedProbit(sigma, np.zeros(50), np.zeros(50, dtype=bool)).terms(d)
    for a, b in zip(ours, Probit(sigma).terms(d), strict=True):
        assert np.array_equal(a, b)
    assert np.array_equal(
        OrderedProbit(sigma, np.zeros(50), np.zeros(50, dtype=bool)).third(d),
        Probit(sigma).third(d),
    )


def test_tie_is_symmetric_and_log_concave_with_bounded_curvature() -> None:
    d = np.linspace(-5, 5, 201)
    n = d.size
    lik = OrderedProbit(np.full(n, 1 / np.sqrt(2)), np.full(n, 0.7), np.ones(n, dtype=bool))
    logp, g, c = lik.terms(d)
    assert np.allclose(logp, logp[::-1], rtol=1e-13) and np.allclose(g, -g[::-1], atol=1e-13)
    assert np.all((c > 0) & (c <= 1)) and g[n // 2] == 0.0
    assert logp[n // 2] == pytest.approx(np.log(norm.cdf(0.7) - norm.cdf(-0.7)), rel=1e-13)


def test_far_tails_stay_finite_and_match_the_probit_limit() -> None:
    """Far from the band a tie's log-likelihood is the shifted probit's, with curvature -> 1."""
    d = np.array([-1e4, -200.0, -40.0, 40.0, 200.0, 1e4])
    n = d.size
    tie = OrderedProbit(np.full(n, 1 / np.sqrt(2)), np.full(n, 0.5), np.ones(n, dtype=bool))
    out = (*tie.terms(d), tie.third(d), *tie.band_terms(d))
    assert all(np.all(np.isfinite(a)) for a in out)
    logp, g, c = out[:3]
    assert logp[0] == pytest.approx(norm.logcdf(d[0] + 0.5), rel=1e-9)
    assert g[1] == pytest.approx(-(d[1] + 0.5), rel=1e-3) and g[-2] == pytest.approx(-g[1])
    assert np.allclose(c, 1.0, atol=1e-3)


def test_invalid_bands_are_rejected() -> None:
    with pytest.raises(ValueError, match="> 0 for 'no preference'"):
        OrderedProbit(np.ones(1), np.zeros(1), np.ones(1, dtype=bool))
    with pytest.raises(ValueError, match="one entry per observation"):
        OrderedProbit(np.ones(2), np.zeros(1), np.zeros(1, dtype=bool))
