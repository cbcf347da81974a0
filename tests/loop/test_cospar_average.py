"""CoSpar with ``hyper = "average"``: lengthscale hypotheses drawn by weight at each ask."""

from __future__ import annotations

import numpy as np
import pytest

from gaitpref import CoSpar, Space, SquaredExponential
from gaitpref.loop.learning import Learning
from gaitpref.strategies import make_strategy


def _objective(space: Space) -> np.ndarray:
    p = (space.points - space.points.min(axis=0)) / np.ptp(space.points, axis=0)
    out: np.ndarray = np.sin(7 * p[:, 0]) + np.cos(3 * p[:, -1])
    return out


def _loop(space: Space, kernel: SquaredExponential, learning: Learning, seed: int = 3) -> CoSpar:
    return CoSpar(
        space, kernel, 0.02, 1, 1, seed=seed, strategy=make_strategy("gated-eubo"),
        learning=learning,
    )  # fmt: skip


def _play(loop: CoSpar, answers: int) -> list[int]:
    objective = _objective(loop.space)
    proposed: list[int] = []
    for _ in range(answers):
        q = loop.ask()
        proposed += q.actions
        (x,) = q.actions
        comps = [
            (x, b, "first" if objective[x] > objective[b] else "second") for b in q.buffer if b != x
        ]
        loop.tell(q, comps)
    return proposed


def test_one_hypothesis_is_the_fitted_kernels_loop(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    fitted = _loop(small_space, small_kernel, Learning(fit="evidence", refit_every=4))
    one = _loop(
        small_space,
        small_kernel,
        Learning(fit="evidence", refit_every=4, hyper="average", hypotheses=(1.0,)),
    )
    assert _play(fitted, 14) == _play(one, 14)
    np.testing.assert_array_equal(one.posterior.mean, fitted.posterior.mean)
    np.testing.assert_array_equal(one.mixture_mean(), fitted.posterior.mean)
    assert [h.weight for h in one.hypotheses] == [1.0]
    assert [r.after for r in one.refits] == [r.after for r in fitted.refits]


def test_the_mixture_mean_weighs_each_hypothesis_posterior(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    learning = Learning(fit="evidence", refit_every=4, hyper="average")
    loop = _loop(small_space, small_kernel, learning)
    _play(loop, 12)
    hypotheses = loop.hypotheses
    assert len(hypotheses) == 5 and sum(h.weight for h in hypotheses) == pytest.approx(1.0)
    assert [h.factor for h in hypotheses] == list(learning.hypotheses)
    assert hypotheses[2].hyper == loop.hyper  # the centre is the fitted kernel
    means = []
    for h in hypotheses:
        single = _loop(small_space, h.hyper.kernel(), Learning())
        posterior = single._fit(loop.answers)  # the same answers under the fixed kernel
        means.append(h.weight * posterior.mean)
    np.testing.assert_allclose(loop.mixture_mean(), np.sum(means, axis=0), rtol=1e-6, atol=1e-9)
    assert loop.refits[-1].to_json()["hypotheses"] == [h.to_json() for h in hypotheses]


def test_averaging_changes_the_proposals_and_stays_reproducible(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    learning = Learning(fit="evidence", refit_every=4, hyper="average")
    first = _play(_loop(small_space, small_kernel, learning), 20)
    assert first == _play(_loop(small_space, small_kernel, learning), 20)
    fitted = _play(_loop(small_space, small_kernel, Learning(fit="evidence", refit_every=4)), 20)
    assert first != fitted


def test_undo_puts_the_generator_and_hypotheses_back(
    small_space: Space, small_kernel: SquaredExponential
) -> None:
    loop = _loop(
        small_space, small_kernel, Learning(fit="evidence", refit_every=4, hyper="average")
    )
    _play(loop, 8)
    before = loop.hypotheses
    q = loop.ask()
    loop.tell(q, [(q.actions[0], q.buffer[0], "first")] if q.buffer[0] != q.actions[0] else [])
    loop.undo()
    assert loop.hypotheses == before
    assert loop.ask() == q


@pytest.mark.parametrize("seed", range(3))
def test_proposals_stay_inside_the_allowed_actions(
    small_space: Space, small_kernel: SquaredExponential, seed: int
) -> None:
    loop = _loop(
        small_space, small_kernel, Learning(fit="evidence", refit_every=3, hyper="average"), seed
    )
    loop.avoid(int(np.argmax(_objective(small_space))), 0.3)
    allowed = loop.allowed()
    assert allowed is not None and not allowed.all()
    proposed = _play(loop, 15)
    assert len({h.factor for h in loop.hypotheses}) == 5
    assert all(allowed[a] for a in proposed)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"hyper": "average"}, "hyper = 'average' needs fit = 'evidence'"),
        ({"fit": "evidence", "hyper": "mean"}, "hyper must be one of map, average"),
        ({"fit": "evidence", "hyper": "average", "hypotheses": ()}, "hypotheses must be"),
        ({"fit": "evidence", "hypotheses": (1.0, 1.0)}, "hypotheses must differ"),
        ({"fit": "evidence", "hypotheses": (1.0, 0.0)}, "hypotheses must be positive"),
    ],
)
def test_bad_settings_name_the_field(kwargs: dict[str, object], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        Learning(**kwargs)  # type: ignore[arg-type]
