"""An :class:`AskContext` built by hand (a strategy scripted outside the loop) is checked as the
loop's own: an off-grid buffer failed deep in NumPy (a negative one wrapped to the last gait),
an integer seed was an AttributeError at the first draw, a mask of the wrong shape or dtype a
broadcasting error, and an all-false mask let EUBO propose a gait the mask forbids."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from gaitpref import Feature, PreferenceGP, Space, SquaredExponential, make_strategy
from gaitpref.model.posterior import Posterior
from gaitpref.strategies import STRATEGIES, AskContext


@pytest.fixture(scope="module")
def post() -> Posterior:
    space = Space([Feature.linspace("a", 0, 1, 6), Feature.linspace("b", 0, 1, 4)])
    gp = PreferenceGP(space, SquaredExponential(0.3, 1.0, 1e-6), 0.1)
    return gp.posterior([1, 2], [3, 4])


def context(post: Posterior, **changes: Any) -> AskContext:
    fields: dict[str, Any] = {
        "n": 1,
        "buffer": (1,),
        "trial": 2,
        "rng": np.random.default_rng(0),
        "allowed": None,
    }
    fields.update(changes)
    return AskContext(post, **fields)


@pytest.mark.parametrize(
    ("changes", "error", "message"),
    [
        ({"buffer": (24,)}, ValueError, r"buffer\[0\] = 24 is not an action \(0\.\.23\)"),
        ({"buffer": (1, -1)}, ValueError, r"buffer\[1\] = -1 is not an action"),
        ({"buffer": (1.0,)}, ValueError, r"buffer\[0\] = 1\.0 is not an action"),
        ({"buffer": (True,)}, ValueError, r"buffer\[0\] = True is not an action"),
        ({"buffer": 3}, TypeError, "buffer must be a tuple of action indices, got 3"),
        ({"trial": -1}, ValueError, "trial must be an integer >= 0, got -1"),
        ({"trial": 2.5}, ValueError, "trial must be an integer >= 0, got 2.5"),
        ({"rng": 0}, TypeError, "rng must be a numpy.random.Generator"),
        ({"rng": np.random.RandomState(0)}, TypeError, "rng must be a numpy.random.Generator"),
        ({"allowed": np.ones(3, bool)}, ValueError, r"allowed must be None or a boolean mask"),
        ({"allowed": np.ones(24, int)}, ValueError, "got dtype int64 and shape"),
        ({"allowed": np.zeros(24, bool)}, ValueError, "allowed allows no action"),
        ({"n": 0}, ValueError, r"a query needs 1 to 24 new actions .* got n = 0"),
        ({"n": 25}, ValueError, r"got n = 25"),
    ],
)
def test_bad_context_arguments_are_named(
    post: Posterior, changes: dict[str, Any], error: type, message: str
) -> None:
    with pytest.raises(error, match=message):
        context(post, **changes)


def test_the_posterior_is_a_posterior() -> None:
    with pytest.raises(TypeError, match="posterior must be a gaitpref Posterior"):
        AskContext({"mean": [0.0]}, 1, (), 0, np.random.default_rng(0))  # type: ignore[arg-type]


def test_numpy_integers_are_kept_as_ints(post: Posterior) -> None:
    made = context(post, n=np.int64(2), buffer=[np.int32(1), np.intp(5)], trial=np.uint8(3))
    assert (made.n, made.buffer, made.trial) == (2, (1, 5), 3)
    assert type(made.n) is int and type(made.trial) is int
    assert all(type(a) is int for a in made.buffer)


@pytest.mark.parametrize("name", STRATEGIES)
def test_every_strategy_keeps_to_a_mask_with_one_action(post: Posterior, name: str) -> None:
    allowed = np.zeros(24, bool)
    allowed[17] = True
    picks = make_strategy(name).propose(context(post, n=2, allowed=allowed))
    assert picks == (17, 17)
