"""The population study (issue 14): warm starts against cold starts on synthetic clinics.

Each clinic has ``S`` subjects on the paper's synthetic 2-D benchmark (``synthetic-2d``: 30 x 30
grid, the config's loop: n = 1, b = 1, self-sparring, no coactive feedback).  For every
``rho``, ``gaitpref bench population`` runs each subject cold and warm-started from the others
(same seeds), and states the confidence after every answer of both runs.  Three parts:

- ``noiseless``: the paper's objectives (``synthetic_population``: subject ``s``'s utility is
  ``sqrt(rho) z_0 + sqrt(1 - rho) z_s`` over the standardised objectives of the authors' set,
  objective 0 the shared part, objectives 1..S the individual ones), subjects answering without
  noise as ``gaitpref simulate`` does: warm against cold, and the calibration;
- ``model_noise``: the same objectives, subjects answering with the config's probit noise on
  the utility's scale (the config's noise over its prior sd, times the objectives' sd of 1);
- ``gp_draws``: the machinery check, subjects drawn from the model's own population prior
  (``gp_population``: the config's kernel, signal variance and jitter) answering with the
  config's noise; the recommendation is judged on the draws' smooth parts, as the confidence
  states it.  If the confidence is calibrated here, the machinery (Laplace posterior, sampling,
  the tolerance) is right, and a gap on the paper's objectives is the model's mismatch.

The calibration's standard error resamples whole subjects (a cluster bootstrap: one subject's
cold and warm answers are one cluster), since answers within a run are correlated.

    python benchmarks/study_population.py [--parts noiseless,model_noise,gp_draws] ...
    python benchmarks/study_population.py --report

writes ``docs/results/population/``: ``results.json`` (the bench's JSON per part and ``rho``;
a run of some parts keeps the others' results) and ``summary.md`` (the tables against the
issue's targets, the calibrations, the runs' commands and machines; the hand-written "What it
shows" section of an existing summary is kept).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import shlex
import sys
import time
from pathlib import Path

import numpy as np

from gaitpref.config import load_config
from gaitpref.data import paper_objectives
from gaitpref.loop.warm import RELEARN_EVERY
from gaitpref.simulate.population import (
    cluster_bootstrap,
    gp_population,
    population_bench,
    synthetic_population,
)

try:
    from _machine import machine_description, machine_markdown
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown

OUT = Path(__file__).resolve().parent.parent / "docs" / "results" / "population"
PARTS = ("noiseless", "model_noise", "gp_draws")
TITLES = {
    "noiseless": "Noiseless subjects on the paper's objectives (the warm-cold runs above)",
    "model_noise": "The paper's objectives, subjects answering with the model's noise",
    "gp_draws": "Machinery check: subjects drawn from the model's own prior, with its noise",
}
LEAST = 30  # bins with fewer answers are not judged
HAND = "## What it shows"


def _per_rho(text: str, rhos: list[float], flag: str) -> list[int]:
    values = [int(v) for v in text.split(",")]
    if len(values) == 1:
        values *= len(rhos)
    if len(values) != len(rhos):
        raise SystemExit(f"{flag}: one value or one per rho ({len(rhos)}), got {text!r}")
    return values


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--parts", default=",".join(PARTS), help="which parts to run")
    parser.add_argument("--subjects", default="24,8,8", help="one value, or one per rho")
    parser.add_argument("--trials", type=int, default=20)
    parser.add_argument("--rho", default="0,0.5,0.8")
    parser.add_argument("--calibration-rho", default="0.5")
    parser.add_argument("--calibration-subjects", default="16")
    parser.add_argument("--calibration-trials", type=int, default=60)
    parser.add_argument("--gp-rho", default="0.5")
    parser.add_argument("--gp-subjects", default="16")
    parser.add_argument("--gp-trials", type=int, default=60)
    parser.add_argument(
        "--gp-noise", type=float, default=1.0,
        help="the GP-draw part's noise, model's and subjects', as a multiple of the config's",
    )  # fmt: skip
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument(
        "--shared-objective", type=int, default=0,
        help="the paper's objective that is the subjects' shared part (noiseless, model_noise)",
    )  # fmt: skip
    parser.add_argument(
        "--first-objective", type=int, default=1,
        help="subject s's own part is the paper's objective first + s (noiseless, model_noise)",
    )  # fmt: skip
    parser.add_argument(
        "--seed", type=int, default=0,
        help="the runs' seed (gaitpref bench population's); the prior draws' clinic too",
    )  # fmt: skip
    parser.add_argument(
        "--relearn-every", type=int, default=RELEARN_EVERY,
        help="re-learn the new subject's share every so many answers (0: rho held)",
    )  # fmt: skip
    parser.add_argument(
        "--share", choices=("average", "map"), default=None,
        help="the warm start's share: a mixture over hypotheses, or one MAP value (default: "
        "the config's, [model] share)",
    )  # fmt: skip
    parser.add_argument("--report", action="store_true", help="summarise results.json only")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    path = args.out / "results.json"
    results: dict[str, dict] = {}
    if path.is_file():
        results = json.loads(path.read_text(encoding="utf-8"))
    if not args.report:
        parts = args.parts.split(",")
        unknown = sorted(set(parts) - set(PARTS))
        if unknown:
            raise SystemExit(f"--parts: unknown {unknown}; choose from {', '.join(PARTS)}")
        for part in parts:
            start = time.perf_counter()
            results[part] = run_part(part, args)
            results.setdefault("runs", {})[part] = {
                "command": "python benchmarks/study_population.py "
                + " ".join(shlex.quote(a) for a in sys.argv[1:]),
                "seconds": round(time.perf_counter() - start, 1),
                "machine": machine_description(),
            }
            args.out.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(results, indent=1) + "\n", encoding="utf-8")
            print(f"{part}: done in {results['runs'][part]['seconds']:.0f} s", flush=True)
    old = args.out / "summary.md"
    hand = _hand_written(old.read_text(encoding="utf-8")) if old.is_file() else ""
    old.write_text(summary(results, hand), encoding="utf-8")


def run_part(part: str, args: argparse.Namespace) -> dict[str, dict]:
    config = load_config("synthetic-2d")
    if args.share is not None:
        learning = dataclasses.replace(config.learning, share=args.share)
        config = dataclasses.replace(config, learning=learning)
    loop = config.make_loop(seed=0)
    noise = float(loop.gp.noise)
    out: dict[str, dict] = {}
    if part == "noiseless":
        rhos = [float(r) for r in args.rho.split(",")]
        for rho, subjects in zip(rhos, _per_rho(args.subjects, rhos, "--subjects"), strict=True):
            clinic = _clinic(args, rho, subjects)
            out[str(rho)] = population_bench(
                config, clinic, args.trials, seed=args.seed, jobs=args.jobs,
                relearn_every=args.relearn_every,
            )  # fmt: skip
    elif part == "model_noise":
        rhos = [float(r) for r in args.calibration_rho.split(",")]
        counts = _per_rho(args.calibration_subjects, rhos, "--calibration-subjects")
        scaled = noise / float(np.sqrt(loop.gp.kernel.variance))  # objectives' sd is 1
        for rho, subjects in zip(rhos, counts, strict=True):
            clinic = _clinic(args, rho, subjects)
            out[str(rho)] = population_bench(
                config, clinic, args.calibration_trials, seed=args.seed, jobs=args.jobs,
                user_noise=scaled,
                relearn_every=args.relearn_every,
            )  # fmt: skip
    else:
        config = dataclasses.replace(config, noise=config.noise * args.gp_noise)
        noise = float(config.noise)
        rhos = [float(r) for r in args.gp_rho.split(",")]
        counts = _per_rho(args.gp_subjects, rhos, "--gp-subjects")
        for i, (rho, subjects) in enumerate(zip(rhos, counts, strict=True)):
            key = [14, i] if args.seed == 0 else [14, i, args.seed]  # 0: the first study's
            draws, smooth = gp_population(config, rho, subjects, np.random.default_rng(key))
            out[str(rho)] = population_bench(
                config, draws, args.gp_trials, seed=args.seed, jobs=args.jobs, user_noise=noise,
                relearn_every=args.relearn_every, truths=smooth,
            )  # fmt: skip
    return out


def _clinic(args: argparse.Namespace, rho: float, subjects: int) -> np.ndarray:
    """The synthetic clinic of the paper's objectives that the flags name."""
    own = range(args.first_objective, args.first_objective + subjects)
    if args.shared_objective in own:
        raise SystemExit(
            f"--shared-objective {args.shared_objective} is one of the subjects' own objectives "
            f"({own.start}-{own.stop - 1})"
        )
    return synthetic_population(
        paper_objectives(), rho, subjects, shared=args.shared_objective, first=args.first_objective
    )


def _hand_written(text: str) -> str:
    """The hand-written section of an existing summary (up to the machine section)."""
    if HAND not in text:
        return ""
    body = text[text.index(HAND) :]
    ends = [i for i in (body.find("\n## Runs"), body.find("\n## Machine")) if i >= 0]
    return body[: min(ends)].rstrip() + "\n" if ends else body.rstrip() + "\n"


def _mean(subjects: list[dict], arm: str, stop: int) -> tuple[float, float]:
    """Mean over subjects of the mean score over trials 1..stop, and its standard error."""
    per = np.array([np.mean(s[arm][:stop]) for s in subjects])
    return float(per.mean()), float(per.std(ddof=1) / np.sqrt(per.size))


def _warm_cold_table(results: dict) -> list[str]:
    trials = min(out["trials"] for out in results.values())
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
        weights = [s["alone"] for s in subjects if s.get("alone") is not None]
        if weights:  # a mixture over share hypotheses: its mean share, and the weight alone
            row.append(f"{np.mean(shares):.2f} (weight alone {np.mean(weights):.2f})")
        else:
            row.append(
                f"{np.mean(shares):.2f} ({alone} of {len(shares)} at 0)" if shares else "rho"
            )
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
            if gain - 2 * se >= -0.01:
                row.append("met (shown: -0.01 below 2 se)")
            elif gain >= -0.01:
                row.append("point estimate met, not shown (2 se reach below -0.01)")
            else:
                row.append("**not met**")
        else:
            row.append("-")
        lines.append("| " + " | ".join(row) + " |")
    return lines


def calibration_bins(
    part: dict, arms: tuple[str, ...] = ("cold", "warm"), rng_seed: int = 0
) -> list[dict]:
    """The part's answers (every rho, the ``arms``) binned, with a cluster bootstrap over
    subjects (a subject's cold and warm runs are one cluster)."""
    runs = []
    for out in part.values():
        for s in out["subjects"]:
            stated = [p for arm in arms for p in s["stated"][arm]]
            right = [r for arm in arms for r in s["right"][arm]]
            runs.append((stated, right))
    return cluster_bootstrap(runs, np.random.default_rng(rng_seed))


def _calibration_table(bins: list[dict]) -> list[str]:
    lines = [
        "| stated bin | answers | subjects | mean stated | observed | observed - stated "
        "| se (subjects resampled) | binomial se |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for b in bins:
        binom = np.sqrt(b["observed"] * (1 - b["observed"]) / b["count"])
        cells = [f"{b['lo']:.1f}-{b['hi']:.1f}", str(b["count"]), str(b["clusters"])]
        cells += [f"{b['stated']:.3f}", f"{b['observed']:.3f}"]
        se = f"{b['se']:.3f}" + ("*" if b["observed"] in (0.0, 1.0) else "")
        cells += [f"{b['observed'] - b['stated']:+.3f}", se, f"{binom:.3f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def _verdict(bins: list[dict]) -> str:
    judged = [b for b in bins if b["count"] >= LEAST]
    if not judged:
        return f"No bin holds {LEAST} answers."
    worst = max(judged, key=lambda b: abs(b["observed"] - b["stated"]))
    gap = worst["observed"] - worst["stated"]
    within = sum(1 for b in judged if abs(b["observed"] - b["stated"]) <= 0.05)
    clear = [
        f"{b['lo']:.1f}-{b['hi']:.1f}"
        for b in judged
        if abs(b["observed"] - b["stated"]) > 0.05 + 2 * b["se"]
    ]
    top = max(b["hi"] for b in judged)
    return (
        f"Bins with at least {LEAST} answers: {len(judged)} (up to {top:.1f}); "
        f"{within} within 0.05.  Largest gap {gap:+.3f} (se {worst['se']:.3f}) in "
        f"{worst['lo']:.1f}-{worst['hi']:.1f}.  Bins beyond 0.05 by more than 2 se: "
        + (", ".join(clear) if clear else "none")
        + "."
    )


def summary(results: dict, hand: str) -> str:
    runs = results.get("runs", {})
    lines = ["# Warm starts on synthetic clinics (issue 14)", ""]
    for part in PARTS:
        if part in runs:
            lines.append(f"- {part}: `{runs[part]['command']}` ({runs[part]['seconds']:.0f} s)")
    lines += [
        "",
        "Each part runs every subject cold, then warm-started from the others (same seeds); "
        "the confidence is stated after every answer of both runs.",
    ]
    if "noiseless" in results:
        lines += [
            "",
            "## Warm against cold (noiseless subjects)",
            "",
            "Normalised objective of the executed gaits, mean over subjects (standard error over "
            "subjects); warm - cold paired by subject (same seeds; mean of the per-subject "
            "differences, its standard error).  Targets: at least +0.05 over trials 1-10 where "
            "rho >= 0.5; no loss beyond 0.01 where rho = 0.",
            "",
            *_warm_cold_table(results["noiseless"]),
        ]
    lines += [
        "",
        "## Calibration of the confidence",
        "",
        "After every answer, cold and warm, all rho of the part: the stated probability that "
        "the recommended gait is within 5% of the range of the best, binned, against how often "
        "it was.  Target: within 0.05 of the diagonal.  The standard error of observed - stated "
        "resamples whole subjects (2000 resamples; a subject's cold and warm runs are one "
        "cluster): answers within a run are correlated, and the binomial standard error "
        f"understates it.  Bins with fewer than {LEAST} answers are listed, not judged.  "
        "*: every answer in the bin was wrong (or right); resampling cannot move the observed "
        "frequency, and the se (the stated values' spread only) understates the uncertainty: "
        "with k subjects in the bin, a rate up to about 3/k is not excluded.",
    ]
    for part in PARTS:
        if part not in results:
            continue
        p = results[part]
        rhos = ", ".join(p)
        subjects = sum(len(o["subjects"]) for o in p.values())
        trials = ", ".join(sorted({str(o["trials"]) for o in p.values()}))
        noise = ", ".join(sorted({f"{o['user_noise']:g}" for o in p.values()}))
        share = ", ".join(sorted({str(o.get("share", "map")) for o in p.values()}))
        bins = calibration_bins(p)
        lines += [
            "",
            f"### {TITLES[part]}",
            "",
            f"rho {rhos}; {subjects} subjects, {trials} trials each, cold and warm; the "
            f"subjects' probit noise {noise} (utility units"
            + ("; the model's the same" if part == "gp_draws" else "")
            + f"); the warm start's share: {share} ([model] share).",
            "",
            *_calibration_table(bins),
            "",
            _verdict(bins),
        ]
        for arm in ("cold", "warm"):
            lines += ["", f"{arm.capitalize()} runs only: " + _verdict(calibration_bins(p, (arm,)))]
    lines += ["", hand.rstrip() if hand else f"{HAND}\n\n(to be written by hand)", ""]
    lines += ["## Runs' machines", ""]
    for part in PARTS:
        if part in runs:
            lines += [f"### {part}", "", machine_markdown(runs[part]["machine"]), ""]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
