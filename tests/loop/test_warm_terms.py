"""Warm starts carry every kind's terms: preferences, ties (when modelled) and ratings, made with
the new loop's likelihood; at rho = 1 they pool with the new subject's as one subject's data, at
rho = 0 they leave the new subject's posterior alone."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.feedback import ActionObservation, ModelContext, Preference, Tie, kinds
from gaitpref.loop.learning import pair_data
from gaitpref.loop.warm import Earlier, WarmStart, warm_posterior, warm_start, warm_terms
from gaitpref.model.evidence import Hyperparameters
from gaitpref.model.hyperfit import default_prior
from gaitpref.model.likelihood import OrderedProbit, StackedActionLikelihood
from gaitpref.model.ordinal import Ordinal
from gaitpref.model.singles import SingleData

SPACE = Space([Feature.linspace("x", 0.0, 1.0, 12)])
KERNEL = SquaredExponential(0.2, 1.0, 1e-6)
NOISE, BAND = 0.3, 0.2
SCALE = Ordinal(("bad", "okay", "good"), (-0.5, 0.5), 0.3)
CONTEXT = ModelContext(SPACE, NOISE, 1.0, SCALE, KERNEL.variance)


def _subject(shift: int) -> Earlier:
    prefs = [Preference((3 + shift) % 12, (8 + k) % 12, NOISE, "comparison", k) for k in range(3)]
    ties = [Tie((1 + shift) % 12, (2 + shift) % 12, 9)]
    singles = [
        ActionObservation((4 + shift) % 12, "rating", 3, 10),
        ActionObservation((10 + shift) % 12, "rating", 1, 11),
    ]
    return Earlier(prefs, ties, singles)


def _rating_likelihood(observations: list[ActionObservation]) -> object:
    (rating,) = [k for k in kinds() if k.name == "rating"]
    return rating.action_likelihood(observations, CONTEXT)


def test_the_terms_are_node_codes_with_the_new_loops_likelihood() -> None:
    earlier = [_subject(0), _subject(5)]
    data, singles = warm_terms(CONTEXT, True, earlier)
    A = len(SPACE)
    own = [pair_data(e.preferences, e.ties, NOISE, True) for e in earlier]
    assert np.array_equal(data.first, np.concatenate([own[0].first + A, own[1].first + 2 * A]))
    assert np.array_equal(data.tie, np.concatenate([d.tie for d in own])) and data.tie.sum() == 2
    assert data.banded.all()  # ties modelled: comparisons are banded, as the new subject's are
    assert singles is not None and singles.size == 4
    assert sorted(singles.actions // A) == [1, 1, 2, 2]
    dropped, _ = warm_terms(CONTEXT, False, earlier)  # ties not modelled: left out
    assert not dropped.tie.any() and not dropped.banded.any() and dropped.size == 6


@pytest.mark.parametrize("rho", [0.0, 1.0])
def test_rho_zero_ignores_and_rho_one_pools_every_term(rho: float) -> None:
    earlier = [_subject(0), _subject(5)]
    data, singles = warm_terms(CONTEXT, True, earlier)
    warm = WarmStart(data, rho, 2, singles)
    gp = PreferenceGP(SPACE, KERNEL, NOISE, ordinal=SCALE)
    mine = _subject(2)
    own = pair_data(mine.preferences, mine.ties, NOISE, True)
    own_single = np.array([o.action for o in mine.singles], dtype=np.intp)
    own_lik = _rating_likelihood(list(mine.singles))
    post = warm_posterior(warm, gp, own, BAND, own_single, own_lik)  # type: ignore[arg-type]
    if rho == 0.0:
        ref = gp.posterior_from(
            own.first, own.second, own.likelihood(BAND),
            single=own_single, single_likelihood=own_lik,  # type: ignore[arg-type]
        )  # fmt: skip
    else:
        A = len(SPACE)
        theirs = [o for e in earlier for o in e.singles]
        stacked = StackedActionLikelihood(
            ((2, own_lik), (4, _rating_likelihood(theirs)))  # type: ignore[arg-type]
        )
        single = np.concatenate([own_single, [o.action for o in theirs]]).astype(np.intp)
        assert singles is not None and np.array_equal(singles.actions % A, single[2:])
        # one subject's data: the gaits of every pair term, the new subject's first
        ref = gp.posterior_from(
            np.concatenate([own.first, data.first % A]),
            np.concatenate([own.second, data.second % A]),
            OrderedProbit(
                np.concatenate([own.sigma, data.sigma]),
                np.where(np.concatenate([own.banded, data.banded]), BAND, 0.0),
                np.concatenate([own.tie, data.tie]),
            ),
            single=single, single_likelihood=stacked,
        )  # fmt: skip
    scale = np.max(np.abs(ref.mean))
    assert np.allclose(post.mean, ref.mean, rtol=0, atol=1e-8 * scale)
    assert np.allclose(post.variance, ref.variance, rtol=1e-7, atol=1e-12)


def test_warm_start_learns_rho_from_every_term() -> None:
    hyper = Hyperparameters((0.2,), 1.0, 1e-6, BAND)
    prior = default_prior(SPACE, 1.0, NOISE)
    earlier = [_subject(0), _subject(0), _subject(6)]
    warm = warm_start(SPACE, hyper, prior, earlier, context=CONTEXT, model_ties=True)
    assert warm.singles is not None and warm.singles.size == 6 and warm.data.tie.sum() == 3
    assert 0.0 < warm.rho < 1.0
    prefs_only = warm_start(SPACE, hyper, prior, [e.preferences for e in earlier])
    assert prefs_only.singles is None and prefs_only.rho != warm.rho
    assert isinstance(warm.singles, SingleData)
    with pytest.raises(ValueError, match="context"):
        warm_start(SPACE, hyper, prior, earlier)
