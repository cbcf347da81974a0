"""Issues 12 and 14 together: does a warm start from earlier rated subjects let the region of
avoidance keep a new subject off the worst gaits from the first trials?

The ordinal study (``study_ordinal.py``, ``docs/results/ordinal/``) found that on independent
subjects the default strategy's "very bad" gaits come almost all from trials 1-5, before any
rating of this subject can say where the worst gaits are, and that no region built from this
subject's ratings alone can remove them.  In a clinic the earlier subjects' ratings can.  This
script measures it on a synthetic clinic (``gaitpref.simulate.synthetic_population``: subject
``s``'s utility is ``sqrt(rho) z_shared + sqrt(1 - rho) z_s`` over the paper's standardised
objectives):

- ``E`` earlier subjects (objectives ``first .. first + E - 1``) each walk ``--earlier-trials``
  trials cold, rating every gait, with the region (the rated config's defaults);
- ``N`` new subjects (the next ``N`` objectives) each walk ``--trials`` trials in four arms, same
  seeds: ``rated`` (cold, no region), ``cautious`` (cold, the region: ``[safety] avoid = ["very
  bad"]`` at the defaults, cautious level 0.6), ``warm-rated`` (warm-started from the ``E``
  earlier subjects' preferences and ratings, no region) and ``warm-cautious`` (warm and the
  region).  Warm starts are made as sessions make them (``loop/warm.py``: every term carried,
  ``rho`` learned from the earlier subjects, the new subject's share a mixture re-learned after
  every answer).

An arm ``ARM:map`` is ``ARM`` with ``[model] share = "map"`` (one MAP share, gated, instead of
the mixture), ``ARM::strategy`` with ``warm_first = "strategy"`` and ``ARM:map:strategy`` with
both, for the diagnosis in the summary; ``ARM:::0.5`` gives the share mixture's prior mass on
alone (0.2 in the library; the screen patches ``share_fit.share_prior``, the library has no
such setting).

Subjects: the ordinal study's ``noiseless`` subject (exact preferences, exact ratings at the
quartiles of their own utility).  The config is the ordinal study's 2-D one (the paper's 30 x 30
grid, lengthscale 0.15, the default strategy: gated-eubo, lengthscales fitted every 20 answers).

    python benchmarks/study_clinic_safety.py --rho 0,0.5,0.8 --earlier 8 --new 16 --trials 60 \
        [--arms rated,warm-rated,warm-rated:map] [--jobs 1] [--out FILE.json]
    python benchmarks/study_clinic_safety.py --report FILE.json [--markdown OUT.md]

Results and what they show: ``docs/results/ordinal/clinic/summary.md`` (``results.json`` and
the runs under earlier defaults beside it).
"""

from __future__ import annotations

import argparse
import functools
import json
import time
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed

import gaitpref.model.share_fit as _share_fit
from gaitpref.config import ExperimentConfig, parse_config
from gaitpref.data import paper_objectives
from gaitpref.errors import NoSafeGaitError
from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.warm import Earlier, relearning, warm_start
from gaitpref.simulate.population import synthetic_population
from gaitpref.simulate.raters import OrdinalRater
from gaitpref.simulate.run import run_simulation
from gaitpref.simulate.users import SimulatedUser

try:
    from _machine import machine_description
    from study_ordinal import QUARTILES, Arm, _reduction, _se, true_category
except ImportError:  # run as a module
    from benchmarks._machine import machine_description
    from benchmarks.study_ordinal import QUARTILES, Arm, _reduction, _se, true_category

SEED = 20261203
ARMS = ("rated", "cautious", "warm-rated", "warm-cautious")
RATED = Arm("rated")
CAUTIOUS = Arm("cautious", risk=True, cautious=0.6)


def _config(region: bool, share: str = "", first: str = "") -> ExperimentConfig:
    text = (CAUTIOUS if region else RATED).text("2d")
    given = "".join(
        f'{key} = "{value}"\n' for key, value in (("share", share), ("warm_first", first)) if value
    )  # [model] share / warm_first given (default: the defaults version's)
    return parse_config(text.replace("noise = 0.01\n", "noise = 0.01\n" + given, 1))


def _walk(
    cfg: ExperimentConfig,
    utility: np.ndarray,
    trials: int,
    seeds: list[int],
    earlier: list[Earlier] | None,
) -> tuple[CoSpar, dict[str, object]]:
    loop_ss, user_ss, rater_ss = np.random.SeedSequence(seeds).spawn(3)
    loop = cfg.make_loop(seed=np.random.default_rng(loop_ss))
    rho = None
    if earlier is not None:
        warm = warm_start(
            cfg.space, loop.hyper, loop.prior, earlier,
            context=loop.context(), model_ties=loop.learning.ties == "model",
        )  # fmt: skip
        loop.warm_start(relearning(warm))
        rho = warm.rho
    user = SimulatedUser(cfg.space, utility, np.random.default_rng(user_ss))
    rater = OrdinalRater(cfg.space, utility, QUARTILES, np.random.default_rng(rater_ss))
    category = true_category(cfg.space, utility)
    start = time.perf_counter()
    stopped = 0
    try:
        result = run_simulation(loop, user, trials, rater=rater)
        actions = np.asarray(result.actions, dtype=np.intp)
    except NoSafeGaitError:
        stopped = 1
        actions = np.asarray(loop.executed[:trials], dtype=np.intp)
    scores = user.normalized(actions)
    return loop, {
        "scores": np.round(np.asarray(scores), 4).tolist(),
        "categories": category[actions].tolist(),
        "seconds": time.perf_counter() - start,
        "stopped": stopped,
        "rho": rho,
        "share": None if loop.warm is None else loop.warm.share,
    }


def _earlier_run(utility: np.ndarray, trials: int, seeds: list[int]) -> Earlier:
    loop, _ = _walk(_config(True), utility, trials, seeds, None)
    return Earlier(loop.preferences, loop.ties, loop.singles)


def _new_run(
    arm: str, utility: np.ndarray, trials: int, seeds: list[int], earlier: list[Earlier]
) -> dict[str, object]:
    prior = earlier if arm.startswith("warm") else None
    # "warm-rated:map": that arm with [model] share = "map"; "warm-rated:map:strategy" also
    # with warm_first = "strategy"; "warm-rated::strategy" the latter alone; a fourth field,
    # "warm-rated:::0.5", the share mixture's prior mass on alone (screen only: patched)
    base, *given = arm.split(":")
    share, first, alone = [*given, "", "", ""][:3]
    cfg = _config(base.endswith("cautious"), share, first)
    if not alone:
        return _walk(cfg, utility, trials, seeds, prior)[1]
    original = _share_fit.share_prior
    _share_fit.share_prior = functools.partial(original, alone=float(alone))
    try:
        return _walk(cfg, utility, trials, seeds, prior)[1]
    finally:
        _share_fit.share_prior = original


def run(
    rhos: list[float],
    n_earlier: int,
    n_new: int,
    trials: int,
    earlier_trials: int,
    jobs: int,
    arms: tuple[str, ...] = ARMS,
) -> dict[str, object]:
    objectives = paper_objectives()
    out: dict[str, object] = {
        "earlier": n_earlier,
        "new": n_new,
        "trials": trials,
        "earlier_trials": earlier_trials,
        "machine": machine_description(),
        "parts": [],
    }
    parallel = Parallel(n_jobs=jobs, backend="loky", inner_max_num_threads=1)
    start = time.perf_counter()
    for rho in rhos:
        clinic = synthetic_population(objectives, rho, n_earlier + n_new, shared=0, first=1)
        earlier = list(
            parallel(
                delayed(_earlier_run)(clinic[e], earlier_trials, [SEED, 1, e])
                for e in range(n_earlier)
            )
        )
        calls = [(arm, k) for k in range(n_new) for arm in arms]
        rows = parallel(
            delayed(_new_run)(arm, clinic[n_earlier + k], trials, [SEED, 2, k], earlier)
            for arm, k in calls
        )
        runs: dict[str, list[dict[str, object]]] = {arm: [] for arm in arms}
        for (arm, _), row in zip(calls, rows, strict=True):
            runs[arm].append(row)
        out["parts"].append({"rho": rho, "runs": runs})  # type: ignore[attr-defined]
        print(f"rho {rho}: {time.perf_counter() - start:.0f} s", flush=True)
    out["seconds"] = time.perf_counter() - start
    return out


def _worst(rows: list[dict[str, object]], lo: int, hi: int) -> np.ndarray:
    return np.array([np.sum(np.asarray(r["categories"][lo:hi]) == 1) for r in rows], float)


def _score(rows: list[dict[str, object]], lo: int, hi: int) -> np.ndarray:
    return np.array([np.mean(r["scores"][lo:hi]) for r in rows])


def report(results: dict[str, object]) -> str:
    trials = int(results["trials"])  # type: ignore[arg-type]
    lines = [
        f"{results['earlier']} earlier subjects x {results['earlier_trials']} trials (cold, rated, "
        f"region); {results['new']} new subjects x {trials} trials per arm, noiseless; "
        f"{results['seconds']:.0f} s in all.",
        "",
        f"| rho | arm | learnt rho | worst/run 1-5 | 6-{trials} | 1-{trials} | objective 1-20 "
        f"| 1-{trials} |",
        "|---|---|---|---|---|---|---|---|",
    ]
    pairs = [
        ("warm-cautious", "warm-rated", "the region, given the warm start"),
        ("warm-cautious", "rated", "warm start and region against neither"),
        ("cautious", "rated", "the region, cold (the ordinal study's comparison)"),
        ("warm-rated", "rated", "the warm start alone"),
    ]
    diff = [
        "",
        f"| rho | comparison | worst gaits 1-{trials}: fewer | objective 1-{trials}: paired "
        "| 1-20 |",
        "|---|---|---|---|---|",
    ]
    for part in results["parts"]:  # type: ignore[attr-defined]
        rho, runs = part["rho"], part["runs"]
        for arm, rows in runs.items():
            learnt = [r["rho"] for r in rows if r["rho"] is not None]
            lines.append(
                f"| {rho} | {arm} | {f'{np.mean(learnt):.2f}' if learnt else '-'} | "
                f"{_worst(rows, 0, 5).mean():.2f} | {_worst(rows, 5, trials).mean():.2f} | "
                f"{_worst(rows, 0, trials).mean():.2f} ± {_se(_worst(rows, 0, trials)):.2f} | "
                f"{_score(rows, 0, 20).mean():.3f} | {_score(rows, 0, trials).mean():.3f} |"
            )
        extra = [(a, a.partition(":")[0], "[model] keys given") for a in runs if ":" in a]
        for a, b, what in pairs + extra:
            if a not in runs or b not in runs:
                continue
            d60 = _score(runs[a], 0, trials) - _score(runs[b], 0, trials)
            d20 = _score(runs[a], 0, 20) - _score(runs[b], 0, 20)
            red = _reduction(_worst(runs[a], 0, trials), _worst(runs[b], 0, trials))
            diff.append(
                f"| {rho} | {a} - {b} ({what}) | {red} | {d60.mean():+.3f} ± {_se(d60):.3f} | "
                f"{d20.mean():+.3f} ± {_se(d20):.3f} |"
            )
    return "\n".join(lines + diff) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rho", default="0,0.5,0.8")
    parser.add_argument("--earlier", type=int, default=8)
    parser.add_argument("--new", type=int, default=16)
    parser.add_argument("--trials", type=int, default=60)
    parser.add_argument("--earlier-trials", type=int, default=30)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument(
        "--arms",
        default=",".join(ARMS),
        help='arms to run; "ARM:SHARE:FIRST" gives [model] share and warm_first',
    )
    parser.add_argument("--out", type=Path, default=Path("out/clinic-safety.json"))
    parser.add_argument("--report", type=Path, default=None, help="a results file to summarise")
    parser.add_argument("--markdown", type=Path, default=None)
    args = parser.parse_args()
    if args.report is not None:
        text = report(json.loads(args.report.read_text()))
    else:
        rhos = [float(r) for r in args.rho.split(",")]
        arms = tuple(a for a in args.arms.split(",") if a)
        results = run(
            rhos, args.earlier, args.new, args.trials, args.earlier_trials, args.jobs, arms
        )
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(results))
        text = report(results)
    if args.markdown is not None:
        args.markdown.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
