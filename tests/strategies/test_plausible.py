"""EUBO among the plausible maximisers (``strategies/plausible.py``): the gate, the restriction to
the draws' argmaxes against a brute-force EUBO, the region of interest, configs and replay."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from gaitpref import Feature, PreferenceGP, Session, Space, SquaredExponential
from gaitpref.config import parse_config
from gaitpref.model.posterior import Posterior
from gaitpref.sessions.demo import SimulatedSubject, bump_utility
from gaitpref.strategies import STRATEGIES, AskContext, PlausibleEubo, make_strategy
from gaitpref.strategies.eubo import eubo_against
from tests.strategies.contexts import ask_context

SPACE = Space([Feature.linspace("a", 0, 1, 7), Feature.linspace("b", 0, 1, 5)])
KERNEL = SquaredExponential((0.3, 0.4), 0.005, 1e-7)


def _posterior(seed: int, pairs: int = 12) -> Posterior:
    rng = np.random.default_rng(seed)
    w, l = rng.integers(0, len(SPACE), pairs), rng.integers(0, len(SPACE), pairs)
    keep = w != l
    return PreferenceGP(SPACE, KERNEL, 0.02).posterior(w[keep], l[keep])


def _context(
    post: Posterior,
    n: int,
    buffer: tuple[int, ...],
    seed: int,
    allowed: NDArray[np.bool_] | None = None,
) -> AskContext:
    return ask_context(post, n, buffer, seed, allowed, trial=10)


def _draws(post: Posterior, seed: int, samples: int) -> list[int]:
    """The argmaxes the strategy sees: the same generator's first draws."""
    return [int(a) for a in post.argmax_samples(np.random.default_rng(seed), samples)]


def test_the_challenger_is_the_eubo_best_of_the_draws_argmaxes() -> None:
    post = _posterior(1)
    ref = post.argmax
    eubo = eubo_against(post, ref)
    challengers = set()
    for seed in range(30):
        draws = _draws(post, seed, 8)
        (x,) = PlausibleEubo(samples=8, gates=1).propose(_context(post, 1, (ref,), seed))
        if draws[0] == ref:  # the gate: the first draw ranks the buffered gait best
            assert x == ref
            continue
        plausible = sorted(set(draws) - {ref})
        assert x in plausible
        assert eubo[x] == max(eubo[p] for p in plausible)  # brute force over the plausible set
        challengers.add(x)
    # with a grid's worth of draws the choice is not just the draws' first argmax
    assert len(challengers) >= 2


def test_more_gates_repeat_the_buffered_gait_more_often() -> None:
    post = _posterior(2, pairs=30)
    ref = post.argmax
    repeats = {}
    for gates in (1, 4):
        strategy = PlausibleEubo(samples=16, gates=gates)
        got = [strategy.propose(_context(post, 1, (ref,), seed))[0] for seed in range(60)]
        for seed, x in enumerate(got):
            gate = _draws(post, seed, 16)[:gates]
            assert (x == ref) == (ref in gate)
        repeats[gates] = sum(x == ref for x in got)
    assert 0 < repeats[1] < repeats[4]


def test_with_every_action_plausible_it_is_eubo_over_the_grid() -> None:
    post = PreferenceGP(SPACE, KERNEL, 0.02).prior()  # wide: many distinct argmaxes
    ref = 17
    eubo = np.asarray(eubo_against(post, ref))
    seed = next(s for s in range(50) if _draws(post, s, 1)[0] != ref)
    draws = _draws(post, seed, 4096)
    (x,) = PlausibleEubo(samples=4096, gates=1).propose(_context(post, 1, (ref,), seed))
    best = max((a for a in set(draws) if a != ref), key=lambda a: eubo[a])
    assert x == best


def test_no_buffer_starts_at_the_first_draws_argmax() -> None:
    post = _posterior(3)
    for seed in range(5):
        picks = PlausibleEubo().propose(_context(post, 2, (), seed))
        assert picks[0] == _draws(post, seed, 32)[0] and picks[1] != picks[0]


@settings(max_examples=40)
@given(
    n=st.integers(1, 4),
    buffer=st.lists(st.integers(0, 34), max_size=2, unique=True),
    region=st.lists(st.booleans(), min_size=35, max_size=35),
    samples=st.integers(1, 40),
    gates=st.integers(1, 3),
    seed=st.integers(0, 1000),
)
def test_never_outside_the_region_and_n_actions(
    n: int, buffer: list[int], region: list[bool], samples: int, gates: int, seed: int
) -> None:
    allowed = np.array(region)
    if not allowed.any():  # the loop refuses to ask then (NoSafeGaitError)
        return
    strategy = PlausibleEubo(samples=max(samples, gates), gates=gates)
    picks = strategy.propose(_context(_posterior(seed), n, tuple(buffer), seed, allowed))
    assert len(picks) == n and all(allowed[a] for a in picks)
    fresh = [a for a in np.flatnonzero(allowed) if a not in buffer]
    repeat = n == 1 and bool(buffer) and picks[0] in buffer  # the gate fired
    if len(fresh) >= n and not repeat:  # enough new allowed actions: distinct, none buffered
        assert len(set(picks)) == n and not set(picks) & set(buffer)


@pytest.mark.parametrize(
    ("settings_", "message"),
    [
        ({"samples": 0}, "samples must be an integer >= 1"),
        ({"samples": True}, "samples must be an integer >= 1"),
        ({"gates": 0}, "gates must be an integer >= 1"),
        ({"samples": 2, "gates": 3}, r"gates \(3\) must not exceed samples \(2\)"),
    ],
)
def test_bad_settings_are_refused(settings_: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        PlausibleEubo(**settings_)  # type: ignore[arg-type]


CONFIG = """
[space.step_length]
min = 0.08
max = 0.18
num = 15
unit = "m"

[space.step_duration]
min = 0.85
max = 1.15
num = 7
unit = "s"

[model]
lengthscale = { step_length = 0.03, step_duration = 0.08 }
signal_variance = 0.005
jitter = 1e-7
noise = 0.02

[cospar]
n = 1
buffer = 1
strategy = "plausible-eubo"

[cospar.strategy_settings]
samples = 12
gates = 2
"""


def test_a_config_selects_it_with_its_settings() -> None:
    assert "plausible-eubo" in STRATEGIES
    assert parse_config(CONFIG).make_loop().strategy == PlausibleEubo(samples=12, gates=2)
    assert make_strategy("plausible-eubo") == PlausibleEubo()
    with pytest.raises(Exception, match="samples"):
        parse_config(CONFIG.replace("samples = 12", "samples = 0"))
    with pytest.raises(Exception, match="gates"):
        parse_config(CONFIG.replace("gates = 2", "gates = 13"))


def test_a_session_with_it_replays_exactly(tmp_path: Path) -> None:
    config = parse_config(CONFIG)
    url = f"sqlite:///{tmp_path / 'plausible.db'}"
    session = Session.create(url, config, "S01", seed=7)
    subject = SimulatedSubject(config.space, bump_utility(config.space), seed=3)
    for _ in range(12):
        q = session.next_query()
        session.answer(q.id, *subject.respond(q))
    executed = [e.payload["action"] for e in session.events() if e.kind == "trial_executed"]
    mean = np.asarray(session.posterior().mean).copy()
    session.close()
    again = Session.open(url, session.id)  # replay re-derives and checks every proposal
    replayed = [e.payload["action"] for e in again.events() if e.kind == "trial_executed"]
    assert replayed == executed and len(set(executed)) > 1
    np.testing.assert_array_equal(again.posterior().mean, mean)
    assert again.next_query().actions == session.next_query().actions
