"""``early_scale`` on the line path: EUBO's challenger chosen on the answers refitted at the
scaled lengthscale and read along the query's line (``LineCoSpar`` offers
``AskContext.rescaled`` as the grid loop does)."""

from __future__ import annotations

import numpy as np

from gaitpref import Feature, PreferenceGP, Space, SquaredExponential
from gaitpref.loop.line import LineCoSpar
from gaitpref.loop.lines import LineSettings
from gaitpref.strategies.base import AskContext
from gaitpref.strategies.hybrid import GatedEubo

DOMAIN = Space([Feature.interval(f"x{k}", 0.0, 1.0) for k in range(3)])
KERNEL = SquaredExponential(0.3, 1.0, 1e-6)
PEAK = np.array([0.7, 0.2, 0.5])


class Recording(GatedEubo):
    """gated-eubo that keeps every context it was asked in."""

    def __init__(self, **settings: object) -> None:
        super().__init__(**settings)  # type: ignore[arg-type]
        object.__setattr__(self, "contexts", [])

    def propose(self, context: AskContext) -> tuple[int, ...]:
        self.contexts.append(context)  # type: ignore[attr-defined]
        return super().propose(context)


def _run(strategy: GatedEubo, trials: int = 8, seed: int = 3) -> tuple[LineCoSpar, list[object]]:
    loop = LineCoSpar(
        DOMAIN, KERNEL, 0.05, n=1, buffer=1, seed=seed, strategy=strategy, line=LineSettings(15)
    )
    chosen: list[object] = []
    for _ in range(trials):
        q = loop.ask()
        a = q.actions[0]
        utility = -np.sum((loop.space.points - PEAK) ** 2, axis=1)
        comps = [(a, b, "first" if utility[a] > utility[b] else "second") for b in q.buffer]
        loop.tell(q, [c for c in comps if c[0] != c[1]])
        chosen.append(q.points)
    return loop, chosen


def test_the_line_loops_rescaled_posterior_is_a_fit_at_the_scaled_kernel_on_the_line() -> None:
    strategy = Recording(early_scale=0.5, early_trials=100)
    loop, _ = _run(strategy)
    loop.ask()  # asked with every answer so far in force
    context = strategy.contexts[-1]  # type: ignore[attr-defined]
    assert context.rescaled is not None
    rescaled = context.rescaled(0.5)
    assert rescaled.space is context.posterior.space  # read where the strategy chooses
    # the reference: the same answers on the same points, the kernel's lengthscales halved
    space = context.posterior.space
    prefs = loop.preferences  # indices into the table, the first rows of the line's space
    assert len(prefs) >= 5
    halved = SquaredExponential(0.15, 1.0, 1e-6)
    winners = [p.winner for p in prefs]
    losers = [p.loser for p in prefs]
    reference = PreferenceGP(space, halved, 0.05).posterior(winners, losers)
    np.testing.assert_allclose(rescaled.mean, reference.mean, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(rescaled.variance, reference.variance, rtol=1e-6, atol=1e-9)
    assert not np.allclose(rescaled.mean, context.posterior.mean, rtol=1e-3)


def test_a_local_challenger_changes_the_line_loops_choices_and_is_deterministic() -> None:
    plain = [_run(GatedEubo(), seed=s)[1] for s in range(4)]
    local = [_run(GatedEubo(early_scale=0.5), seed=s)[1] for s in range(4)]
    assert plain != local  # the setting acts on the line path
    assert local == [_run(GatedEubo(early_scale=0.5), seed=s)[1] for s in range(4)]
    after = [_run(GatedEubo(early_scale=0.5, early_trials=0), seed=s)[1] for s in range(4)]
    assert after == plain  # off once early_trials have run
