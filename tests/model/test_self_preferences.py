"""A preference of a gait over itself.

``PreferenceGP.posterior([a], [a])`` took it silently: ``f_a - f_a = 0`` whatever the utilities,
so the posterior ignored it (the caller's datum was lost) while the fit still counted it (the
gait became visited, the evidence gained ``log Phi(0)``).  Now it is a ValueError naming the
position and the gait.  The loop keeps its documented behaviour (``docs/model.md``): a
self-comparison is accepted, kept in the answer's records and the session's log, and adds no
term; the answer now lists it in ``ignored`` (before, only clipped suggestions were listed).
``posterior_from``, the generic pair-term entry the loop fits through, takes such a term as
given (a registered feedback kind's self-pairs replay as before).
"""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import Comparison, CoSpar, Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.model import Probit
from tests.loop.test_custom_kind_terms import Nudge, nudges  # noqa: F401 (a fixture)

SPACE = Space([Feature.linspace("x", 0.0, 1.0, 6), Feature.linspace("y", 0.0, 1.0, 4)])
KERNEL = SquaredExponential((0.3, 0.4), 1.0, 1e-6)


def test_posterior_refuses_a_preference_of_a_gait_over_itself() -> None:
    gp = PreferenceGP(SPACE, KERNEL, 0.1)
    with pytest.raises(ValueError, match=r"winners\[1\] and losers\[1\] are both action 4"):
        gp.posterior([0, 4, 2, 7], [3, 4, 2, 1])
    with pytest.raises(ValueError, match=r"winners\[0\] and losers\[0\] are both action 0"):
        gp.posterior([0], [0], ratings=None)
    gp.posterior([0, 2], [3, 1])  # distinct pairs as before


def test_posterior_from_takes_a_self_pair_as_a_constant_term() -> None:
    """The generic entry: the term moves nothing but the evidence, by log Phi(0) = -log 2."""
    gp = PreferenceGP(SPACE, KERNEL, 0.1)
    w, l_ = np.array([0, 5]), np.array([3, 5])
    with_self = gp.posterior_from(w, l_, Probit(np.full(2, 0.1)))
    without = gp.posterior_from(w[:1], l_[:1], Probit(np.full(1, 0.1)))
    assert np.allclose(with_self.mean, without.mean, rtol=1e-9, atol=1e-12)
    assert np.allclose(with_self.variance, without.variance, rtol=1e-9, atol=1e-12)
    assert with_self.log_evidence == pytest.approx(without.log_evidence - np.log(2.0))


def test_the_loop_lists_a_self_comparison_as_ignored() -> None:
    loop = CoSpar(SPACE, KERNEL, 0.1, n=1, buffer=1, seed=3)
    loop.tell(loop.ask())
    query = loop.ask()
    a = query.actions[0]
    answer = loop.tell(query, [(a, a, "first")])
    assert answer.comparisons == (Comparison(a, a, "first"),)  # kept
    assert answer.ignored_comparisons == answer.comparisons  # and said to add no term
    assert answer.preferences == () and loop.preferences == []
    assert loop.posterior.fit is None  # nothing entered the model


@pytest.mark.usefixtures("nudges")
def test_a_kinds_self_preference_is_fitted_as_before() -> None:
    """A registered kind's term of a gait against itself still reaches the model through
    ``posterior_from`` (the paper's path): sessions that recorded one replay unchanged."""
    loop = CoSpar(SPACE, KERNEL, 0.1, n=1, buffer=1, seed=4)
    query = loop.ask()
    a = query.actions[0]
    b = (a + 1) % len(SPACE)
    loop.tell(query, [Nudge(a, a), Nudge(a, b)])
    gp = PreferenceGP(SPACE, KERNEL, 0.1)
    ref = gp.posterior_from(np.array([a, a]), np.array([a, b]), Probit(np.full(2, 0.1)))
    assert np.array_equal(loop.posterior.mean, ref.mean)
    assert loop.posterior.log_evidence == ref.log_evidence
