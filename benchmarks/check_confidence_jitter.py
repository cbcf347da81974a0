"""Issue 14 diagnosis: is the confidence's under-confidence on the paper's objectives the kernel's
jitter?

The confidence (``loop/stopping.py``) samples the smooth utility, but the Laplace posterior it
samples was fitted with the kernel's jitter (``synthetic-2d``: 10% of the prior variance, an
independent term per gait).  On subjects drawn from the model's own prior it is calibrated
(``check_confidence_prior.py``); on the paper's objectives it states less than it achieves
(``docs/results/population/fresh/``).  This script runs cold sessions of ``synthetic-2d`` (its
loop, self-sparring, n = 1, b = 1) on the fresh clinic's subjects (rho 0.5: objective 99 shared,
25.. individual, standardised), answering with the model's probit noise on their scale
(``--noise``: a multiple of it; 0 for noiseless subjects), and
after every answer states the confidence twice from the same answers:

- ``as_is``: the product's, from the loop's posterior;
- ``no_jitter``: from the posterior refitted with the jitter at ``1e-6`` of the prior variance
  (the kernel otherwise the same);
- with ``--sharpen F``, also ``sharp``: from the posterior refitted with the probit noise times
  ``F`` (a model that credits every answer with more than the config does; the evidence puts
  noiseless subjects' noise at 0.2-0.3 of the config's, ``docs/learning.md``).

Both are judged on the subject's objective (within 5% of its range of the best).  The standard
errors resample whole subjects (``cluster_bootstrap``).

    python benchmarks/check_confidence_jitter.py --subjects 32 --trials 60 [--noise 1] \
        [--sharpen 0.3] [--out rows.json]

Results: ``docs/results/population/fresh/summary.md`` (the calibration section).
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from gaitpref.config import ExperimentConfig, load_config
from gaitpref.data import paper_objectives
from gaitpref.loop import CoSpar
from gaitpref.loop.stopping import confidence
from gaitpref.model.gp import PreferenceGP
from gaitpref.simulate.population import cluster_bootstrap, synthetic_population
from gaitpref.simulate.users import SimulatedUser, objective_on_grid

try:
    from check_confidence_prior import add_rows_arguments, rows_of, within
except ImportError:  # run as a module
    from benchmarks.check_confidence_prior import add_rows_arguments, rows_of, within

TOLERANCE = 0.05


def subject_session(
    config: ExperimentConfig, utility: np.ndarray, s: int, noise: float
) -> tuple[CoSpar, SimulatedUser, np.ndarray]:
    """Subject ``s``'s cold loop, simulated user (``noise`` times the model's probit noise, on
    the standardised objective's scale) and objective on the grid, seeded by ``s``."""
    seeds = np.random.SeedSequence([14, s]).spawn(3)
    loop = config.make_loop(seed=np.random.default_rng(seeds[0]))
    truth = objective_on_grid(config.space, utility)
    scaled = noise * loop.gp.noise / float(np.sqrt(loop.gp.kernel.variance))  # objectives' sd: 1
    user = SimulatedUser(config.space, truth, np.random.default_rng(seeds[1]), noise=scaled)
    return loop, user, truth


def run(
    subjects: int, trials: int, samples: int, noise: float = 1.0, sharpen: float | None = None
) -> list[dict[str, object]]:
    config = load_config("synthetic-2d")
    utilities = synthetic_population(paper_objectives(), 0.5, subjects, shared=99, first=25)
    rows: list[dict[str, object]] = []
    for s in range(subjects):
        loop, user, truth = subject_session(config, utilities[s], s, noise)
        kernel = loop.gp.kernel
        smooth = PreferenceGP(
            config.space,
            dataclasses.replace(kernel, jitter=1e-6 * kernel.variance),
            loop.gp.noise,
        )
        sharp = None
        if sharpen is not None:
            sharp = PreferenceGP(config.space, kernel, sharpen * loop.gp.noise)
        for t in range(trials):
            query = loop.ask()
            loop.tell(query, user.answer(query))
            prefs = loop.preferences
            refit = smooth.posterior(
                [p.winner for p in prefs], [p.loser for p in prefs], [p.noise for p in prefs]
            )
            row: dict[str, object] = {"s": s, "t": t}
            views = [("as_is", loop.posterior), ("no_jitter", refit)]
            if sharp is not None:
                winners, losers = [p.winner for p in prefs], [p.loser for p in prefs]
                views.append(("sharp", sharp.posterior(winners, losers)))
            for name, post in views:
                sure = confidence(
                    post, np.random.default_rng([s, t, 3]), tolerance=TOLERANCE, samples=samples
                )
                row[name] = sure.probability
                row[f"{name}_ok"] = within(truth, sure.recommended, TOLERANCE)
            rows.append(row)
        print(f"subject {s} done", flush=True)
    return rows


def report(
    rows: list[dict[str, object]], names: tuple[str, ...] = ("as_is", "no_jitter", "sharp")
) -> str:
    lines = []
    for name in names:
        if name not in rows[0]:
            continue
        runs = []
        for s in sorted({int(r["s"]) for r in rows}):  # type: ignore[call-overload]
            mine = [r for r in rows if r["s"] == s]
            runs.append(([float(r[name]) for r in mine], [bool(r[f"{name}_ok"]) for r in mine]))  # type: ignore[arg-type]
        lines += [
            f"{name}:",
            "",
            "| stated bin | answers | subjects | mean stated | observed | observed - stated | se |",
            "|---|---|---|---|---|---|---|",
        ]
        for b in cluster_bootstrap(runs, np.random.default_rng(0)):
            lines.append(
                f"| {b['lo']:.1f}-{b['hi']:.1f} | {b['count']} | {b['clusters']} | "
                f"{b['stated']:.3f} | {b['observed']:.3f} | {b['observed'] - b['stated']:+.3f} | "
                f"{b['se']:.3f} |"
            )
        lines.append("")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--subjects", type=int, default=32)
    parser.add_argument("--trials", type=int, default=60)
    parser.add_argument("--samples", type=int, default=300)
    parser.add_argument(
        "--noise", type=float, default=1.0, help="the subjects' noise, times the model's (0: none)"
    )
    parser.add_argument(
        "--sharpen", type=float, default=None, help="also state it with the noise times this"
    )
    add_rows_arguments(parser)
    args = parser.parse_args()
    rows = rows_of(
        args, lambda: run(args.subjects, args.trials, args.samples, args.noise, args.sharpen)
    )
    print(report(rows))


if __name__ == "__main__":
    main()
