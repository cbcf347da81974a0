"""Ordinal ratings told to the loop as a feedback kind: checked against the query and the scale,
fitted with the preferences in one Laplace fit, excluded and undone like other answers."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import CoSpar, FeedbackError, PreferenceGP, Space, SquaredExponential
from gaitpref.feedback import Comparison, Rating, Suggestion
from gaitpref.model.ordinal import Ordinal

SCALE = Ordinal(["very bad", "bad", "okay", "good"], noise=0.02)


def _loop(space: Space, kernel: SquaredExponential, ordinal: Ordinal | None = SCALE) -> CoSpar:
    return CoSpar(space, kernel, 0.02, n=1, buffer=1, seed=4, ordinal=ordinal)


def test_ratings_and_preferences_fit_together(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    loop = _loop(small_space, small_kernel)
    told: list[tuple[int, str]] = []
    prefs: list[tuple[int, int]] = []
    for k in range(5):
        q = loop.ask()
        a = q.actions[0]
        label = SCALE.categories[k % 4]
        answers: list[object] = [Rating(a, label)]
        if q.buffer and q.buffer[0] != a:
            answers.append(Comparison(a, q.buffer[0], "second"))
            prefs.append((q.buffer[0], a))
        loop.tell(q, answers)
        told.append((a, label))
    gp = PreferenceGP(small_space, small_kernel, 0.02, ordinal=SCALE)
    want = gp.posterior([w for w, _ in prefs], [l for _, l in prefs], ratings=told)
    assert np.allclose(loop.posterior.mean, want.mean, rtol=1e-9, atol=1e-12)
    assert [o.value for a in loop.answers for o in a.singles] == [1, 2, 3, 4, 1]


def test_bad_ratings_are_refused_and_change_nothing(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    loop = _loop(small_space, small_kernel)
    q = loop.ask()
    a = q.actions[0]
    other = (a + 1) % len(small_space)
    for bad, message in [
        ([Rating(a, "great")], "rating 0: rating 'great' is not a category"),
        ([Rating(a, 5)], "not a category"),
        ([Rating(other, 1)], "was not executed"),
        ([Rating(a, 1), Rating(a, 2)], "rated twice"),
    ]:
        with pytest.raises(FeedbackError, match=message):
            loop.tell(q, bad)
    assert loop.pending == q and not loop.answers
    plain = _loop(small_space, small_kernel, ordinal=None)
    q = plain.ask()
    with pytest.raises(FeedbackError, match=r"\[feedback.rating\]"):
        plain.tell(q, [Rating(q.actions[0], 1)])


def test_excluded_ratings_leave_the_model(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    loop = _loop(small_space, small_kernel)
    q = loop.ask()
    feature = small_space.names[0]
    answer = loop.tell(q, [Rating(q.actions[0], "good"), Suggestion(q.actions[0], feature, "+big")])
    assert len(answer.singles) == 1
    assert not np.allclose(loop.posterior.mean, 0.0)
    prior_mean = PreferenceGP(small_space, small_kernel, 0.02).prior().mean
    loop.exclude({q.id: range(len(answer.preferences))}, {q.id: [0]})
    assert np.allclose(loop.posterior.mean, prior_mean)
    loop.undo()
    q2 = loop.ask()
    assert q2 == q
