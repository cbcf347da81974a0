"""Re-learning the new subject's share as they answer (``loop/warm.py``): a subject unlike the
others stays alone (the cold loop, exactly), one like them comes to share, and undo restores it."""

from __future__ import annotations

import dataclasses

import numpy as np

from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.warm import WarmStart, warm_data
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
