"""The stopping rule's upper half (issue 14): is "90% sure" right nine times in ten?

The population study (``study_population.py``) states the confidence after every answer of 20-
to 60-trial runs, and there it rarely passes 0.5: the half of the calibration curve where
``[stop] confidence = 0.9`` acts stays unmeasured.  This check runs single subjects (cold) long
enough for the confidence to climb: the paper's 100 objectives on the 30 x 30 grid, 150 trials,
the product's confidence (``loop/stopping.py``: 2000 joint samples, the recommended gait within
5% of the range of the best).  Two loops:

- ``default``: what a new config gets (``gated-eubo``, lengthscales fitted every 20 answers;
  the learning study's ``gated+fit`` config);
- ``paper``: the shipped ``synthetic-2d`` config (self-sparring, kernel fixed);
- ``gated``: the default's strategy with the kernel fixed at the config's (``gated``).

and three subjects: ``noiseless`` (answers by the objective), ``model_noise`` (probit noise
equal to the model's: the config's noise over its prior sd, on objectives standardised to sd 1)
and ``low_noise`` (0.3 of the model's: a consistent subject).

The confidence is stated every ``--every`` answers and, once a stated value reaches
``--dense``, after every answer, so the first answer at which the rule would fire
(``--stop``) is found exactly unless the confidence jumps from below ``--dense`` to ``--stop``
within ``--every`` answers (counted and reported).  Two readings:

- the calibration curve: stated against observed in ten bins, standard errors by resampling
  whole subjects (``cluster_bootstrap``);
- the rule itself: for each run, the first answer stated at or above ``--stop``, and whether
  the recommended gait was then within the tolerance.  If the rule is calibrated, it is right
  in at least that share of the runs it stops.

    python benchmarks/check_stop_calibration.py [--arms default,paper] \
        [--subjects noiseless,model_noise] [--objectives 100] [--trials 150] [--jobs 2]
    python benchmarks/check_stop_calibration.py --arms paper,default --subjects noiseless \
        --clinic 0.5,24,20    # warm runs (cells named ARM+warm)
    python benchmarks/check_stop_calibration.py --report

writes ``docs/results/population/stop-calibration/`` (``results.json``: every stated value,
``summary.md``: the tables and the machine; a hand-written section from ``## What it shows`` on is
kept).
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from joblib import Parallel, delayed

from gaitpref.config import ExperimentConfig, load_config, parse_config
from gaitpref.data import paper_objectives
from gaitpref.feedback import Preference
from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.stopping import confidence
from gaitpref.loop.warm import relearning, warm_start
from gaitpref.simulate.population import cluster_bootstrap, synthetic_population
from gaitpref.simulate.users import SimulatedUser

try:
    from _machine import machine_description
    from study_learning import FIT, PAPER, config_text
except ImportError:  # run as a module
    from benchmarks._machine import machine_description
    from benchmarks.study_learning import FIT, PAPER, config_text

RESULTS = Path(__file__).resolve().parent.parent / "docs" / "results"
OUT = RESULTS / "population" / "stop-calibration"
ARMS = ("default", "paper", "gated")
SUBJECTS = ("noiseless", "model_noise", "low_noise")
LEAST = 30  # bins with fewer stated values are listed, not judged
TOLERANCE = 0.05
SAMPLES = 2000  # the product's default ([stop] samples)
HAND = "## What it shows"  # a hand-written section of summary.md, kept by --report


def arm_config(arm: str) -> ExperimentConfig:
    if arm == "default":
        return parse_config(config_text("gated-eubo", FIT))
    if arm == "paper":
        return load_config("synthetic-2d")
    if arm == "gated":  # the default's strategy with the kernel fixed (the config's)
        return parse_config(config_text("gated-eubo", PAPER))
    raise SystemExit(f"--arms: unknown {arm!r}; choose from {', '.join(ARMS)}")


def one_run(
    arm: str,
    subject: str,
    k: int,
    trials: int,
    every: int,
    dense: float,
    clinic: tuple[float, int, int] | None = None,
) -> dict[str, Any]:
    """Objective ``k`` walked ``trials`` times; the stated confidences and whether each was
    right.  ``clinic``: ``(rho, subjects, others' trials)``: subject ``k`` of the synthetic
    clinic of ``rho`` (``synthetic_population``: objective 0 shared, 1.. their own), warm-started
    from the others' cold runs of that many trials, as sessions' warm starts are made."""
    config = arm_config(arm)
    if clinic is None:
        raw = paper_objectives().reshape(100, -1)[k]
        utility = (raw - raw.mean()) / raw.std()
        seeds = [16, k]
    else:
        grids = synthetic_population(paper_objectives(), clinic[0], clinic[1])
        utility, seeds = grids[k], [16, k, 1]
    loop_ss, user_ss, sure_ss = np.random.SeedSequence(seeds).spawn(3)
    loop = config.make_loop(seed=np.random.default_rng(loop_ss))
    noise = _noise(subject, loop)
    if clinic is not None:
        others = [_cold(config, grids[j], clinic[2], j, noise) for j in range(clinic[1]) if j != k]
        loop.warm_start(relearning(warm_start(config.space, loop.hyper, loop.prior, others)))
    user = SimulatedUser(config.space, utility, np.random.default_rng(user_ss), noise=noise)
    rng = np.random.default_rng(sure_ss)
    span = float(utility.max() - utility.min())
    answers: list[int] = []
    stated: list[float] = []
    right: list[bool] = []
    scores: list[float] = []  # the recommended gait's normalised objective
    scales: list[list[float]] = []  # the model's lengthscales then
    close = False
    for t in range(1, trials + 1):
        query = loop.ask()
        loop.tell(query, user.answer(query))
        if not (close or t % every == 0 or t == trials):
            continue
        sure = confidence(
            loop.posterior, rng, tolerance=TOLERANCE, samples=SAMPLES, draws=loop.share_mixture()
        )
        answers.append(t)
        stated.append(sure.probability)
        right.append(bool(utility.max() - utility[sure.recommended] <= TOLERANCE * span))
        scores.append(float((utility[sure.recommended] - utility.min()) / span))
        scales.append([float(v) for v in np.atleast_1d(loop.gp.kernel.lengthscale)])
        close = close or sure.probability >= dense
    return {
        "arm": arm if clinic is None else f"{arm}+warm", "subject": subject, "objective": k,
        "answers": answers,
        "stated": stated, "right": right, "scores": scores, "lengthscales": scales,
    }  # fmt: skip


def _noise(subject: str, loop: CoSpar) -> float:
    """The subject's probit noise on objectives of sd 1."""
    if subject == "noiseless":
        return 0.0
    noise = float(loop.gp.noise) / float(np.sqrt(loop.gp.kernel.variance))
    return noise * (0.3 if subject == "low_noise" else 1.0)


def _cold(
    config: ExperimentConfig, utility: np.ndarray, trials: int, j: int, noise: float
) -> list[Preference]:
    """Subject ``j``'s cold run of ``trials`` trials: the preferences a warm start reads."""
    loop_ss, user_ss = np.random.SeedSequence([16, j, 2]).spawn(2)
    loop = config.make_loop(seed=np.random.default_rng(loop_ss))
    user = SimulatedUser(config.space, utility, np.random.default_rng(user_ss), noise=noise)
    for _ in range(trials):
        query = loop.ask()
        loop.tell(query, user.answer(query))
    return list(loop.preferences)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--arms", default=",".join(ARMS))
    parser.add_argument("--subjects", default=",".join(SUBJECTS))
    parser.add_argument("--objectives", type=int, default=100, help="the first N of the 100")
    parser.add_argument("--trials", type=int, default=150)
    parser.add_argument("--every", type=int, default=5)
    parser.add_argument("--dense", type=float, default=0.75)
    parser.add_argument("--stop", type=float, default=0.9)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument(
        "--clinic", default=None,
        help="RHO,SUBJECTS,TRIALS: warm runs instead, each subject of a synthetic clinic "
        "warm-started from the others' cold runs of TRIALS trials",
    )  # fmt: skip
    parser.add_argument("--report", action="store_true", help="summarise results.json only")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    path = args.out / "results.json"
    results: dict[str, Any] = {"runs": [], "commands": []}
    if path.is_file():
        results = json.loads(path.read_text(encoding="utf-8"))
    if not args.report:
        unknown = sorted(set(args.subjects.split(",")) - set(SUBJECTS))
        if unknown:
            raise SystemExit(f"--subjects: unknown {unknown}; choose from {', '.join(SUBJECTS)}")
        cells = [(a, s) for a in args.arms.split(",") for s in args.subjects.split(",")]
        for arm, subject in cells:
            arm_config(arm)  # a wrong name stops before any work
            start = time.perf_counter()
            clinic = None
            count = args.objectives
            if args.clinic is not None:
                rho, subjects, others = args.clinic.split(",")
                clinic = (float(rho), int(subjects), int(others))
                count = clinic[1]
            runs = Parallel(n_jobs=args.jobs)(
                delayed(one_run)(arm, subject, k, args.trials, args.every, args.dense, clinic)
                for k in range(count)
            )
            name = arm if clinic is None else f"{arm}+warm"
            results["runs"] = [
                r for r in results["runs"] if (r["arm"], r["subject"]) != (name, subject)
            ] + list(runs)
            results["commands"].append(
                {
                    "command": "python benchmarks/check_stop_calibration.py "
                    + " ".join(shlex.quote(a) for a in sys.argv[1:]),
                    "cell": [name, subject],
                    "seconds": round(time.perf_counter() - start, 1),
                    "machine": machine_description(),
                    "trials": args.trials,
                    "every": args.every,
                    "dense": args.dense,
                }
            )
            args.out.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(results) + "\n", encoding="utf-8")
            print(f"{name} / {subject}: {time.perf_counter() - start:.0f} s", flush=True)
    old = args.out / "summary.md"
    text = old.read_text(encoding="utf-8") if old.is_file() else ""
    hand = text[text.index(HAND) :] if HAND in text else ""  # kept as written
    old.write_text(summary(results, args.stop) + ("\n" + hand if hand else ""), encoding="utf-8")


def stop_rows(runs: list[dict[str, Any]], stop: float) -> dict[str, Any]:
    """Where the rule at ``stop`` fires in each run, and whether it was right there."""
    fired, hits, at, jumped = 0, 0, [], 0
    for r in runs:
        first = next((i for i, p in enumerate(r["stated"]) if p >= stop), None)
        if first is None:
            continue
        fired += 1
        hits += bool(r["right"][first])
        at.append(r["answers"][first])
        if first > 0 and r["answers"][first] - r["answers"][first - 1] > 1:
            jumped += 1  # fired at a sparse check: the true first crossing may be earlier
    return {"runs": len(runs), "fired": fired, "hits": hits, "at": at, "jumped": jumped}


def _table(runs: list[dict[str, Any]]) -> list[str]:
    rows = cluster_bootstrap(
        [(r["stated"], r["right"]) for r in runs], np.random.default_rng(14), bins=10
    )
    lines = [
        "| stated bin | stated values | subjects | mean stated | observed | observed - stated "
        "| se (subjects resampled) | judged |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for b in rows:
        gap = b["observed"] - b["stated"]
        if b["count"] < LEAST:
            verdict = "too few"
        elif abs(gap) <= TOLERANCE:
            verdict = "within 0.05"
        elif abs(gap) - TOLERANCE > 2 * b["se"]:
            verdict = "**beyond 0.05 by > 2 se**"
        else:
            verdict = "beyond 0.05, within 2 se"
        lines.append(
            f"| {b['lo']:.1f}-{b['hi']:.1f} | {b['count']} | {b['clusters']} | "
            f"{b['stated']:.3f} | {b['observed']:.3f} | {gap:+.3f} | {b['se']:.3f} | {verdict} |"
        )
    return lines


def _machine(info: dict[str, Any]) -> str:
    return (
        f"{info.get('cpu', '?')}, {info.get('cores', '?')} cores, load "
        f"{info.get('load_average_1min', '?')}, {info.get('date', '?')}"
    )


def summary(results: dict[str, Any], stop: float) -> str:
    out = [
        "# The stopping rule's calibration, upper half (issue 14)",
        "",
        "`benchmarks/check_stop_calibration.py` (its docstring says what it runs). Single",
        "subjects on the paper's objectives (standardised; cold, or warm-started where a cell",
        "says `+warm`), 30 x 30 grid, n = 1, b = 1; the",
        f"product's confidence ({SAMPLES} joint samples, recommended gait within "
        f"{TOLERANCE:.0%} of the range of the best).",
        "",
        "Runs:",
        "",
    ]
    for c in results["commands"]:
        out.append(
            f"- `{c['command']}`: {c['cell'][0]} / {c['cell'][1]}, {c['trials']} trials, "
            f"stated every {c['every']} answers and after every answer from "
            f"{c['dense']}: {c['seconds']:.0f} s ({_machine(c['machine'])})"
        )
    cells = sorted({(r["arm"], r["subject"]) for r in results["runs"]})
    for arm, subject in cells:
        runs = [r for r in results["runs"] if (r["arm"], r["subject"]) == (arm, subject)]
        s = stop_rows(runs, stop)
        out += ["", f"## {arm} / {subject} ({len(runs)} subjects)", ""]
        out += _table(runs)
        if s["fired"]:
            rate = s["hits"] / s["fired"]
            se = float(np.sqrt(rate * (1 - rate) / s["fired"]))
            at = np.asarray(s["at"])
            out += [
                "",
                f"The rule `[stop] confidence = {stop}` fires in {s['fired']} of {s['runs']} "
                f"runs (median answer {np.median(at):.0f}, range {at.min()}-{at.max()}); the "
                f"recommended gait was then within the tolerance in {s['hits']} of them "
                f"({rate:.3f}, binomial se {se:.3f}). Fired at a sparse check (the first "
                f"crossing may be up to {max(c['every'] for c in results['commands']) - 1} "
                f"answers earlier): {s['jumped']}.",
            ]
        else:
            out += ["", f"The rule `[stop] confidence = {stop}` never fires in these runs."]
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    main()
