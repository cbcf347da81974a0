"""The population study (issue 14): warm starts against cold starts on synthetic clinics.

Each clinic has ``S`` subjects on the paper's synthetic 2-D benchmark (``synthetic-2d``: 30 x 30
grid, the config's loop: n = 1, b = 1, self-sparring, no coactive feedback).  Subject ``s``'s
utility is ``sqrt(rho) z_0 + sqrt(1 - rho) z_s`` over the standardised objectives of the
authors' set (``gaitpref.simulate.population.synthetic_population``: objective 0 is the shared
part, objectives 1..S the individual ones, the same at every ``rho``).  For every ``rho``,
``gaitpref bench population`` runs each subject cold and warm-started from the others (same
seeds), and the confidence's calibration over all answers of both runs.

Two kinds of simulated subject:

- noiseless (the paper's, ``gaitpref simulate``): warm against cold, and the calibration;
- "as the model assumes": probit noise equal to the config's, on the utility's scale (the
  config's noise over its prior sd, times the objectives' sd of 1): the calibration when the
  model's likelihood is the subjects' (``--calibration-rho``, ``--calibration-trials``).

    python benchmarks/study_population.py [--subjects 24,12,12] [--trials 20] [--rho 0,0.5,0.8]

writes ``docs/results/population/``: ``results.json`` (the bench's JSON per ``rho``, and per
``rho`` for the model's own noise) and ``summary.md`` (the tables against the issue's targets,
the calibrations, the machine).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from gaitpref.config import load_config
from gaitpref.data import paper_objectives
from gaitpref.loop.warm import RELEARN_EVERY
from gaitpref.simulate.population import population_bench, synthetic_population

try:
    from _machine import machine_description, machine_markdown
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown

OUT = Path(__file__).resolve().parent.parent / "docs" / "results" / "population"


def _per_rho(text: str, rhos: list[float]) -> list[int]:
    values = [int(v) for v in text.split(",")]
    if len(values) == 1:
        values *= len(rhos)
    if len(values) != len(rhos):
        raise SystemExit(f"--subjects: one value or one per rho ({len(rhos)}), got {text!r}")
    return values


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--subjects", default="24,12,12", help="one value, or one per rho")
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--rho", default="0,0.5,0.8")
    parser.add_argument("--calibration-rho", default="0.5")
    parser.add_argument("--calibration-subjects", type=int, default=12)
    parser.add_argument("--calibration-trials", type=int, default=30)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument(
        "--relearn-every", type=int, default=RELEARN_EVERY,
        help="re-learn the new subject's share every so many answers (0: rho held)",
    )  # fmt: skip
    args = parser.parse_args()
    config = load_config("synthetic-2d")
    objectives = paper_objectives()
    rhos = [float(r) for r in args.rho.split(",")]
    results: dict[str, dict] = {"noiseless": {}, "model_noise": {}}
    start = time.perf_counter()
    for rho, subjects in zip(rhos, _per_rho(args.subjects, rhos), strict=True):
        clinic = synthetic_population(objectives, rho, subjects)
        results["noiseless"][str(rho)] = population_bench(
            config, clinic, args.trials, jobs=args.jobs, relearn_every=args.relearn_every
        )
        print(f"noiseless, rho = {rho}: done at {time.perf_counter() - start:.0f} s", flush=True)
    loop = config.make_loop(seed=0)
    noise = float(loop.gp.noise) / float(np.sqrt(loop.gp.kernel.variance))
    if args.calibration_rho:
        for rho in [float(r) for r in args.calibration_rho.split(",")]:
            clinic = synthetic_population(objectives, rho, args.calibration_subjects)
            results["model_noise"][str(rho)] = population_bench(
                config, clinic, args.calibration_trials, jobs=args.jobs, user_noise=noise,
                relearn_every=args.relearn_every,
            )  # fmt: skip
            print(f"model noise, rho = {rho}: done at {time.perf_counter() - start:.0f} s")
    seconds = time.perf_counter() - start
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "results.json").write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
    (OUT / "summary.md").write_text(summary(results, args, noise, seconds), encoding="utf-8")


def _mean(subjects: list[dict], arm: str, stop: int) -> tuple[float, float]:
    """Mean over subjects of the mean score over trials 1..stop, and its standard error."""
    per = np.array([np.mean(s[arm][:stop]) for s in subjects])
    return float(per.mean()), float(per.std(ddof=1) / np.sqrt(per.size))


def _warm_cold_table(results: dict, trials: int) -> list[str]:
    lines = [
        "| rho | subjects | learnt rho (mean) | share at the end (mean; alone) | "
        "cold 1-10 | warm 1-10 | warm - cold 1-10 | "
        f"cold 1-{trials} | warm 1-{trials} | warm - cold 1-{trials} | target |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for rho, out in results.items():
        subjects = out["subjects"]
        row = [rho, str(len(subjects)), f"{np.mean([s['rho'] for s in subjects]):.2f}"]
        shares = [s["share"] for s in subjects if s.get("share") is not None]
        alone = sum(1 for x in shares if x == 0.0)
        row.append(f"{np.mean(shares):.2f} ({alone} of {len(shares)} at 0)" if shares else "rho")
        gains = []
        for stop in (10, trials):
            cold, cold_se = _mean(subjects, "cold", stop)
            warm, warm_se = _mean(subjects, "warm", stop)
            diff = np.array(
                [np.mean(s["warm"][:stop]) - np.mean(s["cold"][:stop]) for s in subjects]
            )
            se = float(diff.std(ddof=1) / np.sqrt(diff.size))
            gains.append((float(diff.mean()), se))
            row += [
                f"{cold:.3f} ({cold_se:.3f})",
                f"{warm:.3f} ({warm_se:.3f})",
                f"{diff.mean():+.3f} ({se:.3f})",
            ]
        r, (gain, se) = float(rho), gains[0]
        if r >= 0.5:
            row.append("met" if gain >= 0.05 else "**not met**")
        elif r == 0.0:
            if gain >= -0.01:
                row.append("met")
            elif gain + 2 * se >= -0.01:
                row.append("not shown: -0.01 is within 2 se")
            else:
                row.append("**not met**")
        else:
            row.append("-")
        lines.append("| " + " | ".join(row) + " |")
    return lines


def _calibration_table(results: dict) -> list[str]:
    bins = _pooled(results)
    lines = [
        "| stated bin | answers | mean stated | observed | observed - stated | binomial se |",
        "|---|---|---|---|---|---|",
    ]
    for b in bins:
        se = np.sqrt(b["observed"] * (1 - b["observed"]) / b["count"])
        cells = [f"{b['lo']:.1f}-{b['hi']:.1f}", str(b["count"])]
        cells += [f"{b['stated']:.3f}", f"{b['observed']:.3f}"]
        cells += [f"{b['observed'] - b['stated']:+.3f}", f"{se:.3f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def _worst(results: dict, least: int = 30) -> float:
    """The largest |observed - stated| over bins with at least ``least`` answers."""
    gaps = [abs(b["observed"] - b["stated"]) for b in _pooled(results) if b["count"] >= least]
    return max(gaps) if gaps else float("nan")


def summary(results: dict, args: argparse.Namespace, noise: float, seconds: float) -> str:
    main, matched = results["noiseless"], results["model_noise"]
    lines = [
        "# Warm starts on synthetic clinics (issue 14)",
        "",
        f"`python benchmarks/study_population.py --subjects {args.subjects} --trials "
        f"{args.trials} --rho {args.rho} --calibration-rho {args.calibration_rho} "
        f"--calibration-subjects {args.calibration_subjects} --calibration-trials "
        f"{args.calibration_trials} --relearn-every {args.relearn_every} --jobs {args.jobs}` "
        f"({seconds:.0f} s).",
        "",
        "## Warm against cold (noiseless subjects)",
        "",
        "Normalised objective of the executed gaits, mean over subjects (standard error over "
        "subjects); warm - cold paired by subject (same seeds; mean of the per-subject "
        "differences, its standard error).  Targets: at least +0.05 over trials 1-10 where "
        "rho >= 0.5; no loss beyond 0.01 where rho = 0.",
        "",
        *_warm_cold_table(main, args.trials),
        "",
        "## Calibration of the confidence",
        "",
        "After every answer, cold and warm, all rho: the stated probability that the "
        "recommended gait is within 5% of the range of the best, binned, against how often it "
        "was.  Target: within 0.05 of the diagonal.  Answers of one subject's run are "
        "correlated, so the binomial standard error is a lower bound.",
        "",
        f"### Subjects as the model assumes them (probit noise {noise:g} on the objectives' "
        "scale: the config's noise over its prior sd)",
        "",
        *_calibration_table(matched),
        "",
        f"Largest gap in a bin with at least 30 answers: {_worst(matched):.3f}.",
        "",
        "### Noiseless subjects (the runs above)",
        "",
        *_calibration_table(main),
        "",
        f"Largest gap in a bin with at least 30 answers: {_worst(main):.3f}.",
        "",
        "## Machine",
        "",
        machine_markdown(machine_description()),
        "",
    ]
    return "\n".join(lines)


def _pooled(results: dict) -> list[dict]:
    """The bins of every rho merged (count-weighted)."""
    merged: dict[float, dict] = {}
    for out in results.values():
        for b in out["calibration"]:
            m = merged.setdefault(
                b["lo"], {"lo": b["lo"], "hi": b["hi"], "count": 0, "s": 0.0, "o": 0.0}
            )
            m["count"] += b["count"]
            m["s"] += b["stated"] * b["count"]
            m["o"] += b["observed"] * b["count"]
    return [
        {
            "lo": m["lo"],
            "hi": m["hi"],
            "count": m["count"],
            "stated": m["s"] / m["count"],
            "observed": m["o"] / m["count"],
        }
        for _, m in sorted(merged.items())
    ]


if __name__ == "__main__":
    main()
