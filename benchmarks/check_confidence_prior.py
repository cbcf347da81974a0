"""Machinery check of the confidence (issue 14): cold runs on subjects drawn from the model's prior.

Each subject's utility is one draw ``f = g + e`` from the config's own prior (``g`` the smooth
part, ``e`` the kernel's jitter, an independent term per gait), and the subject answers with the
config's probit noise: exactly what the model assumes.  After every answer of a cold run
(``synthetic-2d``'s loop) two probabilities are stated and checked:

- ``p_smooth``: the product's confidence (``loop/stopping.py``: samples without the jitter),
  judged on the smooth part ``g``;
- ``p_full``: the same with the jitter in the samples, judged on ``f``.

Under the model both are exact posterior probabilities, so binned against how often they were
right they lie on the diagonal up to the Laplace approximation and sampling error.  The
standard error resamples whole subjects (``cluster_bootstrap``).

    python benchmarks/check_confidence_prior.py --subjects 24 --trials 60 [--config FILE] \
        [--out rows.json]

Single process; ~1 minute per subject at 60 trials on the 2-core machine (load ~7).
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np

from gaitpref.config import load_config
from gaitpref.loop.stopping import confidence
from gaitpref.simulate.population import cluster_bootstrap
from gaitpref.simulate.users import SimulatedUser


def within(utility: np.ndarray, gait: int, tolerance: float = 0.05) -> bool:
    return bool(utility.max() - utility[gait] <= tolerance * (utility.max() - utility.min()))


def run(config_name: str, subjects: int, trials: int, samples: int = 1000) -> list[dict]:
    config = load_config(config_name)
    rows = []
    for s in range(subjects):
        seeds = np.random.SeedSequence([7, s]).spawn(4)
        loop = config.make_loop(seed=np.random.default_rng(seeds[0]))
        f, e = loop.posterior.engine.prior_parts(np.random.default_rng(seeds[1]), 1)
        full = f[0].copy()
        smooth = full - e[0] if e is not None else full.copy()
        user = SimulatedUser(
            config.space, full, np.random.default_rng(seeds[2]), noise=loop.gp.noise
        )
        for t in range(trials):
            query = loop.ask()
            loop.tell(query, user.answer(query))
            post = loop.posterior
            sure = confidence(post, np.random.default_rng([s, t, 0]), samples=samples)
            draws = post.sample(np.random.default_rng([s, t, 9]), samples, nugget=True)
            best, worst = draws.max(axis=1), draws.min(axis=1)
            rec = sure.recommended
            p_full = float(np.mean(best - draws[:, rec] <= 0.05 * (best - worst)))
            rows.append(
                {
                    "s": s,
                    "t": t,
                    "p_smooth": sure.probability,
                    "ok_smooth": within(smooth, rec),
                    "p_full": p_full,
                    "ok_full": within(full, rec),
                }
            )
        print(f"subject {s} done", flush=True)
    return rows


def report(rows: list[dict]) -> None:
    for p, ok in (("p_smooth", "ok_smooth"), ("p_full", "ok_full")):
        runs = []
        for s in sorted({r["s"] for r in rows}):
            mine = [r for r in rows if r["s"] == s]
            runs.append(([r[p] for r in mine], [r[ok] for r in mine]))
        print(p)
        for b in cluster_bootstrap(runs, np.random.default_rng(0)):
            print(
                f"  {b['lo']:.1f}-{b['hi']:.1f}: {b['count']:4d} answers, {b['clusters']:2d} "
                f"subjects, stated {b['stated']:.3f}, observed {b['observed']:.3f}, "
                f"gap {b['observed'] - b['stated']:+.3f} (se {b['se']:.3f})"
            )


def add_rows_arguments(parser: argparse.ArgumentParser) -> None:
    """``--out`` (write the rows as JSON) and ``--rows`` (report rows written before)."""
    parser.add_argument("--out", type=Path, default=None, help="write the rows as JSON")
    parser.add_argument("--rows", type=Path, default=None, help="report rows written before")


def rows_of(args: argparse.Namespace, make: Callable[[], list[dict]]) -> list[dict]:
    """The rows of ``--rows``, else ``make()``'s, written to ``--out`` when given."""
    if args.rows is not None:
        rows: list[dict] = json.loads(args.rows.read_text(encoding="utf-8"))
        return rows
    rows = make()
    if args.out is not None:
        args.out.write_text(json.dumps(rows), encoding="utf-8")
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--config", default="synthetic-2d")
    parser.add_argument("--subjects", type=int, default=24)
    parser.add_argument("--trials", type=int, default=60)
    add_rows_arguments(parser)
    args = parser.parse_args()
    report(rows_of(args, lambda: run(args.config, args.subjects, args.trials)))


if __name__ == "__main__":
    main()
