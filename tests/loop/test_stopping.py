"""How sure are we: the confidence is calibrated on simulated subjects, and the rule triggers."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from gaitpref import Feature, Space, SquaredExponential, load_config
from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.stopping import Confidence, StopRule, confidence
from gaitpref.model.engines import make_engine
from gaitpref.simulate.users import SimulatedUser

SPACE = Space([Feature.linspace("step_length", 0.0, 1.0, 25)])
KERNEL = SquaredExponential(0.15, 1.0, 1e-6)
NOISE = 0.1


def _subject(seed: int) -> tuple[CoSpar, SimulatedUser]:
    """A subject whose utility is a draw from the model's own prior, and a loop for them."""
    rng = np.random.default_rng([seed, 1])  # not the loop's stream: its first draw would be this
    utility = make_engine(SPACE, KERNEL, "dense").prior_samples(rng, 1)[0]
    user = SimulatedUser(SPACE, utility, rng, noise=NOISE)
    return CoSpar(SPACE, KERNEL, NOISE, n=2, seed=seed), user


def _truly_within(user: SimulatedUser, action: int, tolerance: float) -> bool:
    u = user.utility
    return bool(u.max() - u[action] <= tolerance * (u.max() - u.min()))


def _stated_and_observed(seeds: range, queries: int | None) -> tuple[np.ndarray, np.ndarray]:
    stated, observed = [], []
    for seed in seeds:
        loop, user = _subject(seed)
        for _ in range(1 + seed % 6 if queries is None else queries):
            q = loop.ask()
            loop.tell(q, user.answer(q))
        sure = confidence(loop.posterior, np.random.default_rng([seed, 2]), samples=300)
        stated.append(sure.probability)
        observed.append(_truly_within(user, sure.recommended, 0.05))
    return np.array(stated), np.array(observed, dtype=float)


def test_the_stated_probability_matches_the_observed_frequency_under_the_prior() -> None:
    """Subjects drawn from the prior, no data: the stated probability (a Gaussian, sampled
    exactly) is the observed frequency of gait 0 being within 5% of the best (within 0.06, 2.4
    binomial standard errors over 200 subjects)."""
    p, hit = _stated_and_observed(range(200), 0)
    assert abs(p.mean() - hit.mean()) < 0.06, (p.mean(), hit.mean())


def test_with_data_the_stated_probability_is_conservative_and_ranks_the_sessions() -> None:
    """After 1-6 answers the Laplace posterior is wider than the exact one (its mean is shrunk,
    Kuss & Rasmussen 2005), so the stated probability is below the observed frequency, never
    above it (measured: 0.16 stated, 0.40 observed); and the subjects it is surer of are
    right more often."""
    p, hit = _stated_and_observed(range(120), None)
    assert p.mean() <= hit.mean() + 0.02, (p.mean(), hit.mean())
    high = p >= np.median(p)
    assert hit[high].mean() > hit[~high].mean()


def test_confidence_grows_with_data_and_regret_shrinks() -> None:
    loop, user = _subject(3)
    before = confidence(loop.posterior, np.random.default_rng(0), samples=500)
    for _ in range(15):
        q = loop.ask()
        loop.tell(q, user.answer(q))
    after = confidence(loop.posterior, np.random.default_rng(0), samples=500)
    assert after.probability > before.probability
    assert after.regret < before.regret
    assert 0.0 <= after.relative_regret < before.relative_regret <= 1.0
    assert after.recommended == int(np.argmax(loop.posterior.mean))


def test_allowed_restricts_the_recommendation_and_the_best() -> None:
    loop, user = _subject(4)
    for _ in range(10):
        q = loop.ask()
        loop.tell(q, user.answer(q))
    allowed = np.ones(len(SPACE), dtype=bool)
    allowed[int(np.argmax(loop.posterior.mean))] = False
    sure = confidence(loop.posterior, np.random.default_rng(0), samples=200, allowed=allowed)
    assert allowed[sure.recommended]
    with pytest.raises(ValueError, match="no gait is allowed"):
        confidence(loop.posterior, np.random.default_rng(0), allowed=np.zeros(25, dtype=bool))


@pytest.mark.parametrize(
    ("allowed", "message"),
    [
        # integers were read bitwise (~1 is -2, an index) and as column indices: the
        # recommendation and "the best" came from the wrong gaits, silently
        (np.ones(25, dtype=int), "got dtype int64 and shape"),
        (
            np.ones(24, dtype=bool),
            r"boolean mask over the 25 gaits, got dtype bool and shape \(24,\)",
        ),
        ([True] * 25, None),  # a list of bools is a mask
    ],
)
def test_allowed_is_a_boolean_mask_over_every_gait(allowed: Any, message: str | None) -> None:
    post = CoSpar(SPACE, KERNEL, NOISE, seed=0).posterior
    if message is None:
        same = confidence(post, np.random.default_rng(0), samples=50, allowed=allowed)
        assert same == confidence(post, np.random.default_rng(0), samples=50)
        return
    with pytest.raises(ValueError, match=message):
        confidence(post, np.random.default_rng(0), samples=50, allowed=allowed)


def test_the_rule_triggers_on_confidence_or_trials() -> None:
    sure = Confidence(94, 0.91, 0.01, 0.02, 0.05, 2000)
    assert sure.sentence("G95") == "91% that G95 is within 5% of the best"
    assert StopRule().reason(100, sure) is None  # no rule
    rule = StopRule(confidence=0.9)
    assert rule.active
    assert "91% that gait 94 is within 5%" in str(rule.reason(3, sure))
    named = rule.reason(3, sure, "G94")  # a session names it as its confidence sentence does
    assert named == f"{sure.sentence('G94')} (confidence = 90%)"
    assert rule.reason(3, Confidence(94, 0.89, 0.01, 0.02, 0.05, 2000)) is None
    by_trials = StopRule(max_trials=20)
    assert by_trials.reason(19, None) is None
    assert by_trials.reason(20, None) == "20 trials reached max_trials = 20"
    with pytest.raises(ValueError, match="confidence must lie"):
        StopRule(confidence=1.5)
    with pytest.raises(ValueError, match="tolerance"):
        StopRule(tolerance=1.0)
    # samples=10**9 ran a million blocks; True was a rule of one trial or of certainty
    with pytest.raises(ValueError, match=r"samples must be an integer in 1\.\.100000"):
        StopRule(samples=10**9)
    with pytest.raises(ValueError, match="max_trials must be an integer >= 1, got True"):
        StopRule(max_trials=True)
    with pytest.raises(ValueError, match="confidence must lie"):
        StopRule(confidence=True)
    with pytest.raises(ValueError, match="tolerance must be a fraction"):
        StopRule(tolerance="0.1")  # type: ignore[arg-type]


def test_confidence_takes_a_bounded_count_of_samples() -> None:
    loop = load_config("exo-1d-step-length").make_loop(seed=0)
    for samples in (2.5, 10**12, 0, True):
        with pytest.raises(ValueError, match=r"samples must be an integer in 1\.\.100000"):
            confidence(loop.posterior, np.random.default_rng(0), samples=samples)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="block must be an integer >= 1"):
        confidence(loop.posterior, np.random.default_rng(0), samples=10, block=1.5)  # type: ignore[arg-type]
    ten: Any = np.int64(10)  # a NumPy integer is an integer too
    assert confidence(loop.posterior, np.random.default_rng(0), samples=ten).samples == 10


def test_the_confidence_is_about_the_smooth_utility_not_the_jitter() -> None:
    """With a large jitter (an independent term per gait), subjects whose utility is the smooth
    part of a prior draw: without data the stated probability is the observed frequency (as
    above); samples with the jitter would state far less (their "best" is the largest of many
    independent draws)."""
    kernel = SquaredExponential(0.15, 1.0, 1.0)  # jitter as large as the signal
    engine = make_engine(SPACE, kernel, "dense")
    prior = CoSpar(SPACE, kernel, NOISE, n=2, seed=0).posterior
    stated, observed, with_jitter = [], [], []
    for seed in range(200):
        f, e = engine.prior_parts(np.random.default_rng([seed, 1]), 1)
        assert e is not None
        user = SimulatedUser(SPACE, (f - e)[0], np.random.default_rng(seed))
        sure = confidence(prior, np.random.default_rng([seed, 2]), samples=300)
        stated.append(sure.probability)
        observed.append(_truly_within(user, sure.recommended, 0.05))
        g = prior.sample(np.random.default_rng([seed, 2]), 300)
        best = g.max(axis=1)
        with_jitter.append(np.mean(best - g[:, 0] <= 0.05 * (best - g.min(axis=1))))
    p, hit, low = np.mean(stated), np.mean(observed), np.mean(with_jitter)
    assert abs(p - hit) < 0.03, (p, hit)  # measured: 0.156 stated, 0.135 observed
    assert hit - low > 0.05, (low, hit)  # measured: 0.070 with the jitter


def test_the_confidence_draws_its_samples_on_one_blas_thread(monkeypatch: Any) -> None:
    """As ask and tell do (``model/threads.py``): with BLAS's default threads a session's
    confidence took 0.4-0.8 s on two loaded cores against 9 ms on one, after every answer and
    for every row of an export (``benchmarks/results/long.md``)."""
    from threadpoolctl import threadpool_info, threadpool_limits

    from gaitpref.model.posterior import Posterior

    loop, user = _subject(4)
    for _ in range(6):
        q = loop.ask()
        loop.tell(q, user.answer(q))
    seen: list[int] = []
    sample = Posterior.sample

    def spy(self: Posterior, *args: Any, **kwargs: Any) -> np.ndarray:
        seen.append(max(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"))
        return sample(self, *args, **kwargs)

    monkeypatch.setattr(Posterior, "sample", spy)
    with threadpool_limits(limits=2, user_api="blas"):
        confidence(loop.posterior, np.random.default_rng(5), samples=300, block=100)
        seen.append(max(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"))
    assert seen == [1, 1, 1, 2]  # restored afterwards
