from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.stats import norm

from gaitpref.model.likelihood import Probit, mills_ratio


def _logp(d: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    out: np.ndarray = norm.logcdf(d / (np.sqrt(2.0) * sigma))
    return out


@given(
    st.floats(-0.2, 0.2, allow_nan=False),
    st.floats(0.005, 0.05),
)
def test_probit_derivatives_match_finite_differences(d: float, sigma: float) -> None:
    lik = Probit(np.array([sigma]))
    logp, grad, curv = lik.terms(np.array([d]))
    h = 1e-5 * sigma
    dd = np.array([d - h, d, d + h])
    vals = _logp(dd, np.full(3, sigma))
    assert logp[0] == pytest.approx(vals[1], rel=1e-12, abs=1e-12)
    assert grad[0] == pytest.approx((vals[2] - vals[0]) / (2 * h), rel=1e-6, abs=1e-6)
    g_plus = lik.terms(np.array([d + h]))[1][0]
    g_minus = lik.terms(np.array([d - h]))[1][0]
    assert -curv[0] == pytest.approx((g_plus - g_minus) / (2 * h), rel=1e-6, abs=1e-6)


def test_tails_are_finite_and_have_the_right_limits() -> None:
    z = np.array([-1e6, -1e3, -40.0, -8.0, 0.0, 8.0, 40.0, 1e3])
    lik = Probit(np.full(z.size, 1 / np.sqrt(2.0)))  # scale 1: diff = z
    logp, grad, curv = lik.terms(z)
    assert np.all(np.isfinite(logp)) and np.all(np.isfinite(grad)) and np.all(np.isfinite(curv))
    # phi/Phi -> -z as z -> -inf; log Phi(z) ~ -z^2/2 there
    assert grad[1] == pytest.approx(1e3, rel=1e-5)
    assert logp[1] == pytest.approx(norm.logcdf(-1e3), rel=1e-12)
    assert grad[-1] == 0.0 and logp[-1] == 0.0
    # curvature r (r + z) is in [0, 1] and tends to 1 in the left tail, 0 in the right
    assert np.all((curv >= 0) & (curv <= 1))
    assert curv[2] == pytest.approx(1.0, abs=1e-3)
    assert curv[-2] == pytest.approx(0.0, abs=1e-12)


def test_mills_ratio_matches_direct_formula_in_the_bulk() -> None:
    z = np.linspace(-6, 6, 41)
    assert np.allclose(mills_ratio(z), norm.pdf(z) / norm.cdf(z), rtol=1e-12)
