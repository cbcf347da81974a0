"""A fit is dense in the distinct actions its answers involve (``K_VV``, ``m x m``): past
``MAX_VISITED`` of them a posterior or an evidence is refused, naming the count, before the
matrix is built.  A simulated run of ``MAX_TRIALS`` trials on a large grid or the line path,
visiting a new gait nearly every trial, asked for tens of gigabytes."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.model import laplace
from gaitpref.model.evidence import Hyperparameters, PairData, laplace_evidence

SPACE = Space([Feature.linspace("x", 0.0, 1.0, 40)])
KERNEL = SquaredExponential(0.3, 1.0, 1e-6)


def _chain(m: int) -> tuple[np.ndarray, np.ndarray]:
    """Preferences 0 > 1 > ... > m - 1: exactly ``m`` distinct actions."""
    first = np.arange(m - 1, dtype=np.intp)
    return first, first + 1


def test_a_posterior_past_the_bound_is_refused_before_its_prior_is_built(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(laplace, "MAX_VISITED", 12)
    gp = PreferenceGP(SPACE, KERNEL, 0.1)
    winners, losers = _chain(12)
    assert gp.posterior(winners, losers).mean.shape == (40,)  # at the bound: fitted
    built: list[int] = []
    original = SquaredExponential.cross

    def counting(self: SquaredExponential, *args: object, **kwargs: object) -> object:
        built.append(1)
        return original(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(SquaredExponential, "cross", counting)
    winners, losers = _chain(13)
    with pytest.raises(ValueError, match=r"involve 13 distinct gaits, more than the 12 a post"):
        gp.posterior(winners, losers)
    assert built == []


def test_an_evidence_past_the_bound_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(laplace, "MAX_VISITED", 12)
    hyper = Hyperparameters((0.3,), 1.0, 1e-6)
    first, second = _chain(13)
    n = first.size
    data = PairData(first, second, np.full(n, 0.1), np.zeros(n, bool), np.zeros(n, bool))
    with pytest.raises(ValueError, match=r"involve 13 distinct gaits"):
        laplace_evidence(SPACE, hyper, data)
    first, second = _chain(12)
    n = first.size
    data = PairData(first, second, np.full(n, 0.1), np.zeros(n, bool), np.zeros(n, bool))
    assert np.isfinite(laplace_evidence(SPACE, hyper, data).value)
