"""Re-learning the new subject's share as they answer (``loop/warm.py``): a subject unlike the
others stays alone (the cold loop, exactly), one like them comes to share, and undo restores it;
the same with the share averaged over hypotheses (``share = "average"``)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.learning import Learning
from gaitpref.loop.stopping import confidence
from gaitpref.loop.warm import WarmStart, warm_data
from gaitpref.model.share_mix import ALONE_PRIOR, SHARE_FACTORS
from gaitpref.simulate.users import SimulatedUser
from tests.loop.test_warm import KERNEL, SPACE, UTILITY, _drive, _earlier


def _warm(rho: float = 0.8) -> WarmStart:
    return WarmStart(warm_data(SPACE, _earlier()), rho, 2, share=0.0, relearn_every=1, gate=0.0)


def test_a_subject_unlike_the_others_stays_alone_and_runs_as_the_cold_loop() -> None:
    cold = CoSpar(SPACE, KERNEL, 0.1, n=2, seed=4)
    unlike = CoSpar(SPACE, KERNEL, 0.1, n=2, seed=4)
    unlike.warm_start(_warm())
    assert np.array_equal(unlike.posterior.mean, cold.posterior.mean)
    for loop in (cold, unlike):  # the others prefer 0.7; this subject prefers the far end
        for _ in range(6):
            q = loop.ask()
            a, b = q.actions[0], (q.buffer[0] if q.buffer else q.actions[1])
            loop.tell(q, [(a, b, "first" if a < b else "second")])
    shares = [a.share_refit for a in unlike.answers]
    assert all(s is not None and s.after == 0.0 for s in shares)
    assert unlike.warm is not None and unlike.warm.share == 0.0
    assert unlike.executed == cold.executed
    assert np.allclose(unlike.posterior.mean, cold.posterior.mean, rtol=0, atol=1e-8)


def test_a_subject_like_the_others_comes_to_share_and_undo_restores_the_share() -> None:
    loop = CoSpar(SPACE, KERNEL, 0.1, n=2, seed=4)
    loop.warm_start(_warm())
    user = SimulatedUser(SPACE, 10 * UTILITY, np.random.default_rng(1), noise=0.0)
    for _ in range(6):  # answers as the others do (the same utility's order)
        q = loop.ask()
        loop.tell(q, user.answer(q))
    assert loop.warm is not None and loop.warm.share is not None and loop.warm.share > 0.5
    assert abs(loop.posterior.argmax - int(np.argmax(UTILITY))) <= 2
    fits = [a.share_refit for a in loop.answers]
    assert all(f is not None for f in fits)
    last = fits[-1]
    assert last is not None and last.after == loop.warm.share
    loop.undo()
    assert loop.warm.share == last.before
    # held (recorded before share refits): no refit, the share stays rho
    held = CoSpar(SPACE, KERNEL, 0.1, n=2, seed=4)
    held.warm_start(dataclasses.replace(_warm(), share=None, relearn_every=0))
    _drive(held, 3)
    assert all(a.share_refit is None for a in held.answers)
    assert held.warm is not None and held.warm.share is None


def _averaging(seed: int = 4) -> CoSpar:
    loop = CoSpar(SPACE, KERNEL, 0.1, n=2, seed=seed, learning=Learning(share="average"))
    loop.warm_start(_warm())
    return loop


def test_averaged_shares_move_off_alone_for_a_like_subject_and_undo_restores_them() -> None:
    loop = _averaging()
    user = SimulatedUser(SPACE, 10 * UTILITY, np.random.default_rng(1), noise=0.0)
    for _ in range(6):
        q = loop.ask()
        loop.tell(q, user.answer(q))
    hypotheses = loop.share_hypotheses
    assert [h.share for h in hypotheses] == pytest.approx([c * 0.8 for c in SHARE_FACTORS])
    assert sum(h.weight for h in hypotheses) == pytest.approx(1.0)
    assert hypotheses[0].weight < ALONE_PRIOR  # the answers agree with the others
    assert hypotheses[-1].weight > hypotheses[-1].prior
    mean_share = sum(h.weight * h.share for h in hypotheses)
    assert loop.warm is not None and loop.warm.share == pytest.approx(mean_share)
    last = loop.answers[-1].share_refit
    assert last is not None and last.after == loop.warm.share and last.hypotheses == hypotheses
    mixture = loop.share_mixture()
    assert mixture is not None and len(mixture.components) == len(hypotheses)
    assert np.allclose(mixture.mean, loop.mixture_mean())
    alone = mixture.components[0][1]  # the subject alone: the others' data cannot reach it
    assert not np.allclose(alone.mean, loop.posterior.mean)
    before = last.before
    loop.undo()
    assert loop.warm.share == before
    assert loop.share_hypotheses == loop.answers[-1].share_refit.hypotheses  # type: ignore[union-attr]


def test_one_share_hypothesis_runs_as_the_share_held_there(monkeypatch: pytest.MonkeyPatch) -> None:
    import gaitpref.model.share_fit as share_fit

    monkeypatch.setattr(share_fit, "share_prior", lambda rho: ((rho, 1.0),))
    one = _averaging()
    held = CoSpar(SPACE, KERNEL, 0.1, n=2, seed=4)  # today's posterior with the share at rho
    held.warm_start(dataclasses.replace(_warm(), share=0.8, relearn_every=0))
    one.warm_start(dataclasses.replace(_warm(), share=0.8))  # from the same start
    _drive(one, 4)
    _drive(held, 4)
    assert one.executed == held.executed
    assert np.array_equal(one.posterior.mean, held.posterior.mean)
    assert [h.weight for h in one.share_hypotheses] == [1.0]
    mixture = one.share_mixture()
    assert mixture is not None
    a = confidence(held.posterior, np.random.default_rng(2), samples=300)
    b = confidence(one.posterior, np.random.default_rng(2), samples=300, draws=mixture)
    assert a == b


def _like_the_others(
    loop: CoSpar, answers: int, user: SimulatedUser | None = None
) -> SimulatedUser:
    """``answers`` answers of a subject who orders the gaits as the others do (``user``, else a
    new one); returns the subject."""
    user = user or SimulatedUser(SPACE, 10 * UTILITY, np.random.default_rng(1), noise=0.0)
    for _ in range(answers):
        q = loop.ask()
        loop.tell(q, user.answer(q))
    return user


def test_posteriors_under_the_weighed_shares_are_the_weighing_fits_to_the_bit() -> None:
    """An answer's weighing fits every share hypothesis; the posteriors the ask and the
    confidence read under them are built on those fits, equal to fitting each again."""
    loop = _averaging()
    _like_the_others(loop, 4)
    refit = loop.answers[-1].share_refit
    assert refit is not None and loop.warm is not None
    assert all(not a.share_refit.fits for a in loop.answers if a.share_refit)  # no m x m kept
    key, reused = loop._shared
    assert key is loop.posterior
    others = {h.share for h in refit.hypotheses} - {loop.warm.share}
    assert set(reused) == others and others  # built when the answer was told, none fitted since
    for share, posterior in reused.items():
        fresh = loop._fit(loop.answers, warm=dataclasses.replace(loop.warm, share=share))
        assert posterior.fit is not None and fresh.fit is not None
        for name in ("visited", "chol_prior", "chol_hessian", "whitened_mode"):
            assert np.array_equal(getattr(posterior.fit, name), getattr(fresh.fit, name)), name
        assert np.array_equal(posterior.mean, fresh.mean)
    mixture = loop.share_mixture()
    assert mixture is not None
    stated = confidence(loop.posterior, np.random.default_rng(3), samples=200, draws=mixture)
    loop._shared = (None, {})  # every hypothesis fitted again, as before the reuse
    again = loop.share_mixture()
    assert again is not None
    assert confidence(loop.posterior, np.random.default_rng(3), samples=200, draws=again) == stated


def test_a_fit_of_other_data_is_refused() -> None:
    loop = _averaging()
    user = _like_the_others(loop, 3)
    earlier = [p.fit for p in loop._shared[1].values()]  # fits of the first three answers
    assert earlier and earlier[0] is not None
    _like_the_others(loop, 1, user)
    assert loop.warm is not None
    with pytest.raises(ValueError, match="visited nodes differ"):
        loop._fit(loop.answers, warm=loop.warm, fit=earlier[0])
