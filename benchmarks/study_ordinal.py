"""The ordinal study (issue 12): ratings, the region of avoidance and information-gain queries.

Every arm is the default strategy of a config that omits the learning keys (``gated-eubo``,
lengthscales fitted by the evidence every 20 answers; ``n = 1``, ``b = 1``), with no coactive
feedback, for 60 trials.  Two grids:

- ``2d``: the paper's synthetic benchmark (30 x 30 grid on [0, 1]^2, the authors' 100 objectives,
  GP samples of variance 0.1), config lengthscale 0.15 as ``synthetic-2d``;
- ``3d``: a 10 x 10 x 10 grid on [0, 1]^3; objective ``k`` is a sample of a zero-mean GP with a
  squared-exponential kernel, lengthscale 0.25 on every axis and variance 0.1 (the 2-D
  objectives' scale), drawn exactly through the Kronecker factors of the kernel from
  ``numpy.random.default_rng(SeedSequence([STUDY_SEED, 3, k]))``; config lengthscale 0.25.

Two subjects, each of them rating every executed gait at the objective's quartiles
(``gaitpref.simulate.raters.OrdinalRater``; ``[feedback.rating] labels = ["very bad", "bad",
"okay", "good"]``, the worst category the lowest quarter of the grid):

- ``noiseless``: the paper's subject, and exact ratings;
- ``noisy``: the learning study's subject (``IndifferentUser``, probit noise 0.05 and
  indifference band 0.05 on the objectives' scale) with rating noise 0.05 on the normalised
  objective (0 worst gait, 1 best; the quartiles of a 2-D objective lie about 0.15 apart).

Arms: ``prefs`` (preferences alone, no rating scale), ``rated`` (preferences and ratings),
``avoid-0.5``/``avoid-1``/``avoid-2``/``avoid-0`` (ratings and ``[safety] avoid = ["very bad"]``
with that ``lambda``), ``random`` (ratings and preferences on uniformly random gaits: the floor
of the rating-accuracy comparison), ``random+avoid-1`` (random among the region of interest,
``lambda = 1``: the region of avoidance on a strategy that does not avoid bad gaits by itself)
``infogain`` (ratings, strategy ``information-gain``: only when this gaitpref has it) and
``infogain+avoid-1`` (information gain over the region of interest, ``lambda = 1``: ROIAL's
mode); ``avoid-risk``, ``random+risk`` and ``infogain+risk``: the same with the ``risk`` rule
alone (``[safety] avoid = ["very bad"]`` and ``cautious = 0``, the default in defaults version
0.3: avoided when ``P(rated "very bad") > 0.35``, ``loop/safety.py``); ``avoid-cautious``,
``random+cautious`` and ``infogain+cautious``: the same with the cautious level, ``cautious =
0.6`` and ``explore = 1`` (the defaults since defaults version 0.4): while some gait is known-safe
(``P(rated "very bad")`` at most 0.6 times an unrated gait's) only known-safe gaits, and unexplored
ones whose ``mu + sd`` beats every known-safe gait's.
The start arms (``START_ARMS``; ``report-start`` writes them to ``start.md``): ``[safety]
start`` names the simulated operator's start gait, drawn uniformly among the gaits whose true
category is "okay" or better (``start_gait``, seeded per grid and objective), walked on trial 1:
``rated+start`` (no region), ``cautious+start`` (the region with the cautious level, the start
gait declared known-safe), ``reach+start`` (the same with ``reach = 1``: unexplored gaits only
within one lengthscale of a known-safe gait) and ``strict+start`` (cautious 0.4 and ``reach =
0.5``, the setting a screen on the 3-D noiseless cell chose).  Run ``k`` of every arm uses
objective ``k`` and the same seeds (paired comparisons).
Each run records the normalised objective and true category of every executed gait, and the
accuracy of the predicted rating (argmax of ``posterior.rating_probabilities``) after 30 and 60
trials, over the true region of interest (gaits not truly "very bad") and over the whole grid.

    python benchmarks/study_ordinal.py run [--grids 2d,3d] [--objectives 100] [--objectives-3d 30]
                                           [--arms a,b] [--scenarios s] [--jobs 2]
    python benchmarks/study_ordinal.py report
    python benchmarks/study_ordinal.py report-start

``run`` caches each (grid, scenario, arm) under ``out/ordinal-study/``; ``report`` writes
``docs/results/ordinal/``: ``runs.csv`` (one row per run), ``summary.md`` (quoting the hand-written
``notes.md`` beside it, when there is one) and ``ordinal.png``.
"""

from __future__ import annotations

import argparse
import csv
import json
import time
from collections.abc import Collection
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed

from gaitpref.config import ExperimentConfig, parse_config
from gaitpref.data import paper_objectives
from gaitpref.errors import NoSafeGaitError
from gaitpref.loop.cospar import CoSpar
from gaitpref.model.ordinal import Ordinal, rating_probabilities
from gaitpref.simulate.noisy import IndifferentUser
from gaitpref.simulate.raters import OrdinalRater
from gaitpref.simulate.run import run_simulation
from gaitpref.simulate.users import SimulatedUser
from gaitpref.space import Space
from gaitpref.strategies import STRATEGIES, AskContext

try:
    from _machine import machine_description, machine_markdown
except ImportError:  # run as a module
    from benchmarks._machine import machine_description, machine_markdown

ROOT = Path(__file__).resolve().parent.parent
CACHE = ROOT / "out" / "ordinal-study"
RESULTS = ROOT / "docs" / "results" / "ordinal"
NOTES = RESULTS / "notes.md"  # written by hand after reading the results; summary.md quotes it
TRIALS = 60
SNAPSHOTS = (30, 60)
STUDY_SEED = 20261202
NOISE, BAND, RATING_NOISE = 0.05, 0.05, 0.05
QUARTILES = (0.25, 0.5, 0.75)
LABELS = '["very bad", "bad", "okay", "good"]'
GRIDS = ("2d", "3d")
SCENARIOS = ("noiseless", "noisy")
LENGTHSCALE_3D = 0.25
CAUTIOUS = 0.6  # [safety] cautious of the *+cautious arms (the default since defaults 0.4)

_AXIS = """
[space.{name}]
min = 0.0
max = 1.0
num = {num}
"""
_MODEL = """
[model]
lengthscale = {ls}
signal_variance = 1e-4
jitter = 1e-5
noise = 0.01
"""


@dataclass(frozen=True)
class Arm:
    name: str
    rated: bool = True
    lam: float | None = None  # [safety] lambda (ROIAL's bound); None: see risk
    risk: bool = False  # [safety] avoid = ["very bad"] with the risk rule (risk 0.35)
    cautious: float | None = None  # with risk: [safety] cautious (None: 0, the single level)
    strategy: str = ""  # "" the default; "random": uniform over the allowed gaits
    start: bool = False  # [safety] start: the simulated operator's start gait (start_gait)
    explore: float | None = None  # with cautious: [safety] explore (None: the default, 1)
    reach: float | None = None  # with cautious: [safety] reach (None: anywhere)
    frontier: float | None = None  # with cautious: [safety] frontier (None: off)
    note: str = ""

    def text(self, grid: str, start: int | None = None) -> str:
        axes = ("x", "y") if grid == "2d" else ("x", "y", "z")
        num = 30 if grid == "2d" else 10
        ls = 0.15 if grid == "2d" else LENGTHSCALE_3D
        out = f'name = "ordinal-study-{grid}"\n'
        out += "".join(_AXIS.format(name=a, num=num) for a in axes) + _MODEL.format(ls=ls)
        if self.strategy and self.strategy != "random":
            out += f'\n[cospar]\nstrategy = "{self.strategy}"\n'
        if self.rated:
            out += f"\n[feedback.rating]\nlabels = {LABELS}\n"
        if self.lam is not None:
            out += f'\n[safety]\navoid = ["very bad"]\nlambda = {self.lam}\n'
        elif self.risk:
            out += '\n[safety]\navoid = ["very bad"]\n'
            out += f"cautious = {0 if self.cautious is None else self.cautious}\n"
            if self.explore is not None:
                out += f"explore = {self.explore}\n"
            if self.reach is not None:
                out += f"reach = {self.reach}\n"
            if self.frontier is not None:
                out += f"frontier = {self.frontier}\n"
        if self.start:
            if start is None:
                raise ValueError(f"arm {self.name} needs its start gait")
            out += "" if self.risk or self.lam is not None else "\n[safety]\n"
            out += f"start = [{start}]\n"
        return out

    def config(self, grid: str, start: int | None = None) -> ExperimentConfig:
        return parse_config(self.text(grid, start))


@dataclass(frozen=True)
class UniformRandom:
    """Random selection: each new gait drawn uniformly from the allowed ones."""

    name: str = "random"

    def propose(self, context: AskContext) -> tuple[int, ...]:
        allowed = context.allowed
        pool = np.arange(len(context.posterior.space))
        if allowed is not None:
            pool = pool[allowed]
        return tuple(int(a) for a in context.rng.choice(pool, size=context.n))


ARMS = [
    Arm("prefs", rated=False, note="preferences alone"),
    Arm("rated", note="preferences and ratings"),
    Arm("avoid-0.5", lam=0.5, note='ratings, [safety] avoid = ["very bad"], lambda 0.5'),
    Arm("avoid-1", lam=1.0, note="ratings, ROIAL's bound: [safety] lambda = 1"),
    Arm("avoid-2", lam=2.0, note="as avoid-0.5 with lambda 2"),
    Arm("avoid-0", lam=0.0, note="as avoid-0.5 with lambda 0 (the posterior mean alone)"),
    Arm("avoid-risk", risk=True, note="ratings, risk 0.35 alone (cautious = 0, as to 0.3)"),
    Arm("random", strategy="random", note="ratings, gaits drawn uniformly at random"),
    Arm("random+avoid-1", lam=1.0, strategy="random", note="random among the ROI, lambda 1"),
    Arm("random+risk", risk=True, strategy="random", note="random among the ROI, risk 0.35 alone"),
    Arm("infogain", strategy="information-gain", note="ratings, strategy information-gain"),
    Arm(
        "infogain+avoid-1",
        lam=1.0,
        strategy="information-gain",
        note="information gain over the ROI (ROIAL's mode), lambda 1",
    ),
    Arm(
        "infogain+risk",
        risk=True,
        strategy="information-gain",
        note="information gain over the ROI (ROIAL's mode), risk 0.35 alone",
    ),
    Arm(
        "avoid-cautious",
        risk=True,
        cautious=CAUTIOUS,
        note=f"ratings, risk 0.35, cautious {CAUTIOUS}: the default since defaults version 0.4",
    ),
    Arm(
        "random+cautious",
        risk=True,
        cautious=CAUTIOUS,
        strategy="random",
        note=f"random among the allowed gaits, cautious {CAUTIOUS}",
    ),
    Arm(
        "infogain+cautious",
        risk=True,
        cautious=CAUTIOUS,
        strategy="information-gain",
        note=f"information gain over the allowed gaits, cautious {CAUTIOUS}",
    ),
]


START_ARMS = [  # [safety] start: the simulated operator's start gait (start_gait)
    Arm("rated+start", start=True, note="ratings, trial 1 the start gait, no region"),
    Arm(
        "cautious+start",
        risk=True,
        cautious=CAUTIOUS,
        start=True,
        note=f"ratings, trial 1 the start gait, declared safe; cautious {CAUTIOUS}",
    ),
    Arm(
        "reach+start",
        risk=True,
        cautious=CAUTIOUS,
        start=True,
        reach=1.0,
        note="as cautious+start, exploring only within one lengthscale of a known-safe gait",
    ),
    Arm(
        "strict+start",
        risk=True,
        cautious=0.4,
        start=True,
        reach=0.5,
        note="cautious 0.4, reach 0.5: chosen by a screen on the 3-D noiseless cell",
    ),
    Arm(
        "frontier+start",
        risk=True,
        cautious=0.5,
        start=True,
        reach=1.0,
        frontier=0.9,
        note="cautious 0.5, reach 1, frontier 0.9: chosen by a screen on the 3-D noisy cell",
    ),
]
START_PAIRS = [  # (arm, base): the target's reading is a region against none, all else equal
    ("cautious+start", "rated+start"),
    ("reach+start", "rated+start"),
    ("strict+start", "rated+start"),
    ("frontier+start", "rated+start"),
    ("reach+start", "cautious+start"),
    ("rated+start", "rated"),
    ("cautious+start", "avoid-cautious"),
]
KNOWN_AT = (1, 2, 5, 10)  # trials after which the start arms count the known-safe gaits

ACCURACY = (  # posterior.rating_probabilities as given, then with the fitted thresholds
    *(f"acc_{where}_{t}" for where in ("roi", "all") for t in SNAPSHOTS),
    *(f"fit_acc_{where}_{t}" for where in ("roi", "all") for t in SNAPSHOTS),
)
AVOIDANCE = [  # (arm with a region of avoidance, the arms without it to compare with)
    ("avoid-0.5", ("rated", "prefs")),
    ("avoid-1", ("rated", "prefs")),
    ("avoid-2", ("rated", "prefs")),
    ("avoid-0", ("rated",)),
    ("avoid-risk", ("rated", "prefs")),
    ("random+avoid-1", ("random",)),
    ("random+risk", ("random",)),
    ("infogain+avoid-1", ("infogain",)),
    ("infogain+risk", ("infogain",)),
    ("avoid-cautious", ("rated", "prefs", "avoid-risk")),
    ("random+cautious", ("random",)),
    ("infogain+cautious", ("infogain",)),
]


def objective_3d(k: int) -> np.ndarray:
    """GP sample ``k`` on the 10 x 10 x 10 grid (see the module docstring), C order."""
    x = np.linspace(0.0, 1.0, 10)
    K = 0.1 ** (1 / 3) * np.exp(-0.5 * (x[:, None] - x[None, :]) ** 2 / LENGTHSCALE_3D**2)
    L = np.linalg.cholesky(K + 1e-8 * np.eye(10))
    rng = np.random.default_rng(np.random.SeedSequence([STUDY_SEED, 3, k]))
    z = rng.standard_normal((10, 10, 10))
    out: np.ndarray = np.einsum("ai,bj,ck,ijk->abc", L, L, L, z).reshape(-1)
    return out


def objective(grid: str, k: int) -> np.ndarray:
    return paper_objectives()[k].reshape(-1) if grid == "2d" else objective_3d(k)


def start_gait(grid: str, category: np.ndarray, k: int) -> int:
    """The simulated operator's start gait on objective ``k``: drawn uniformly among the gaits
    whose true category is "okay" or better (the upper half of the grid), from
    ``default_rng(SeedSequence([STUDY_SEED, 5, 2 or 3, k]))``.  A lab knows its device's nominal
    gait is comfortable enough, not that it is near the best one."""
    rng = np.random.default_rng(np.random.SeedSequence([STUDY_SEED, 5, int(grid[0]), k]))
    return int(rng.choice(np.flatnonzero(category >= 3)))


def _loop(arm: Arm, cfg: ExperimentConfig, rng: np.random.Generator) -> CoSpar:
    if arm.strategy != "random":
        return cfg.make_loop(seed=rng)
    return CoSpar(
        cfg.space,
        cfg.kernel,
        cfg.noise,
        n=cfg.n,
        buffer=cfg.buffer,
        coactive_weight=cfg.coactive_weight,
        seed=rng,
        strategy=UniformRandom(),
        learning=cfg.learning,
        sampler=cfg.sampler,
        ordinal=cfg.ordinal,
        safety=cfg.safety,
    )


def true_category(space: Space, utility: np.ndarray) -> np.ndarray:
    """Every gait's true category (1 = "very bad"): ``utility`` cut at its quartiles, ties on a
    boundary as the rater places them (``OrdinalRater.true_categories``; the paper's 100 and the
    first 60 3-D objectives put no gait on a quartile, so their categories are as before)."""
    truth = OrdinalRater(space, utility, QUARTILES, np.random.default_rng(0))
    return truth.true_categories()


def run_one(
    arm: Arm, grid: str, scenario: str, k: int, obj: np.ndarray | None = None
) -> dict[str, object]:
    """One 60-trial run of ``arm`` on objective ``k`` of ``grid`` against ``scenario`` (``obj``:
    another objective on the grid instead, with run ``k``'s seeds: a held-out check)."""
    obj = objective(grid, k) if obj is None else obj
    category = true_category(Arm("").config(grid).space, obj)
    cfg = arm.config(grid, start_gait(grid, category, k) if arm.start else None)
    loop_ss, user_ss, rater_ss = np.random.SeedSequence([STUDY_SEED, k]).spawn(3)
    loop = _loop(arm, cfg, np.random.default_rng(loop_ss))
    rng = np.random.default_rng(user_ss)
    user: SimulatedUser
    if scenario == "noisy":
        user = IndifferentUser(cfg.space, obj, rng, noise=NOISE, band=BAND)
    else:
        user = SimulatedUser(cfg.space, obj, rng)
    noise = RATING_NOISE if scenario == "noisy" else 0.0
    rater = None
    if arm.rated:
        rater = OrdinalRater(cfg.space, obj, QUARTILES, np.random.default_rng(rater_ss), noise)
    accuracy: dict[str, float] = {}
    roi = category > 1

    def snapshot(done: int) -> None:
        if done in KNOWN_AT and arm.start and f"known_{done}" not in accuracy:
            known = loop.safety.known_safe(loop.posterior, loop.gp.ordinal)
            if known is not None:
                accuracy[f"known_{done}"] = float(np.sum(known))
                accuracy[f"known_bad_{done}"] = float(np.sum(known & (category == 1)))
        if done in SNAPSHOTS and f"acc_roi_{done}" not in accuracy and arm.rated:
            post = loop.posterior
            probs = post.rating_probabilities(np.arange(len(cfg.space)))
            # the thresholds the Laplace fit used (fitted by the evidence); the posterior's own
            # rating model keeps the prior-quantile ones (see notes.md)
            fitted = loop.hyper.thresholds
            scale = Ordinal(post.ordinal.categories, fitted, post.ordinal.noise) if fitted else None
            for tag, p in (("", probs), ("fit_", None)):
                if p is None:
                    if scale is None:
                        p = probs
                    else:
                        p = rating_probabilities(
                            scale, post.kernel.variance, post.mean, post.variance
                        )
                predicted = 1 + np.argmax(p, axis=1)
                accuracy[f"{tag}acc_roi_{done}"] = float(np.mean(predicted[roi] == category[roi]))
                accuracy[f"{tag}acc_all_{done}"] = float(np.mean(predicted == category))

    start = time.perf_counter()
    stopped = 0
    try:
        result = run_simulation(loop, user, TRIALS, progress=snapshot, rater=rater)
        actions, scores = result.actions, result.normalized_objective
    except NoSafeGaitError:  # the region of interest emptied: the run stops there
        stopped = 1
        actions = np.asarray(loop.executed[:TRIALS], dtype=np.intp)
        scores = user.normalized(actions)
    seconds = time.perf_counter() - start
    allowed = loop.allowed()
    return {
        "scores": np.asarray(scores).tolist(),
        "categories": category[actions].tolist(),
        "seconds": seconds,
        "stopped": stopped,
        "roi_size": int(len(cfg.space) if allowed is None else np.sum(allowed)),
        "refits": len(loop.refits),
        **accuracy,
    }


def _cache(grid: str, scenario: str, arm: str) -> Path:
    return CACHE / grid / scenario / f"{arm}.json"


def _cached(path: Path, arm: Arm, count: int) -> bool:
    """Whether ``path`` holds ``count`` runs with every field this version records."""
    if not path.is_file():
        return False
    runs = json.loads(path.read_text())["runs"]
    return len(runs) >= count and (not arm.rated or all("fit_acc_roi_30" in r for r in runs))


def _runs_machine() -> dict[str, object] | None:
    """The machine the cached runs were made on (``run`` records it beside the cache)."""
    path = CACHE / "machine.json"
    return json.loads(path.read_text()) if path.is_file() else None  # type: ignore[no-any-return]


def _machine_sections(ran: dict[str, object] | None, names: Collection[str] = ()) -> list[str]:
    """The runs' machine (``machine.json``), each of ``names``' arm files that records another
    machine (``run`` writes its own into each arm file), and the report's machine."""
    here = machine_markdown(machine_description())
    if ran is None:
        return ["## Machine", "", here, ""]
    out = ["## Runs' machine", "", machine_markdown(ran), ""]
    elsewhere: dict[str, list[str]] = {}
    for grid in GRIDS:
        for scenario in SCENARIOS:
            for name in names:
                path = _cache(grid, scenario, name)
                own = json.loads(path.read_text()).get("machine") if path.is_file() else None
                if own is not None and own != ran:
                    elsewhere.setdefault(json.dumps(own), []).append(f"{name} ({grid} {scenario})")
    for own, where in elsewhere.items():
        out += [f"### Run elsewhere: {', '.join(where)}", "", machine_markdown(json.loads(own)), ""]
    return [*out, "## Report's machine", "", here, ""]


def run(
    arms: list[Arm],
    grids: list[str],
    scenarios: list[str],
    counts: dict[str, int],
    jobs: int,
    skip_cached: bool = False,
    infogain_2d: int | None = None,
) -> None:
    CACHE.mkdir(parents=True, exist_ok=True)
    machine = {**machine_description(), "jobs": jobs}
    if not (CACHE / "machine.json").is_file():  # the machine of runs that do not name their own
        (CACHE / "machine.json").write_text(json.dumps(machine))
    for grid in grids:
        for scenario in scenarios:
            for arm in arms:
                if arm.strategy not in ("", "random") and arm.strategy not in STRATEGIES:
                    print(f"skipping {arm.name}: this gaitpref has no strategy {arm.strategy!r}")
                    continue
                path = _cache(grid, scenario, arm.name)
                count = counts[grid]
                if arm.strategy == "information-gain" and grid == "2d" and infogain_2d is not None:
                    count = min(count, infogain_2d)
                if skip_cached and _cached(path, arm, count):
                    continue
                start = time.perf_counter()
                rows = Parallel(n_jobs=jobs)(
                    delayed(run_one)(arm, grid, scenario, k) for k in range(count)
                )
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(json.dumps({"arm": arm.name, "machine": machine, "runs": rows}))
                s = np.array([r["scores"] for r in rows])
                c = np.array([r["categories"] for r in rows])
                print(
                    f"{grid} {scenario:9s} {arm.name:10s} {time.perf_counter() - start:6.0f} s  "
                    f"1-20 {s[:, :20].mean():.3f}  1-60 {s.mean():.3f}  "
                    f"worst {np.mean(c == 1):.3f}",
                    flush=True,
                )


Data = dict[tuple[str, str, str], list[dict[str, object]]]


def _load() -> Data:
    out: Data = {}
    for grid in GRIDS:
        for scenario in SCENARIOS:
            for arm in ARMS:
                path = _cache(grid, scenario, arm.name)
                if path.is_file():
                    out[(grid, scenario, arm.name)] = json.loads(path.read_text())["runs"]
    return out


def _metrics(runs: list[dict[str, object]]) -> dict[str, np.ndarray]:
    s = np.array([r["scores"] for r in runs])
    c = np.array([r["categories"] for r in runs])
    out = {
        "early": s[:, :20].mean(axis=1),
        "all": s.mean(axis=1),
        "worst": (c == 1).mean(axis=1),
        "worst_1_5": (c[:, :5] == 1).mean(axis=1),  # before the region can know anything
        "worst_6_60": (c[:, 5:] == 1).mean(axis=1),
        "seconds": np.array([float(r["seconds"]) for r in runs]),  # type: ignore[arg-type]
        "stopped": np.array([int(r["stopped"]) for r in runs]),  # type: ignore[call-overload]
        "roi_size": np.array([int(r["roi_size"]) for r in runs]),  # type: ignore[call-overload]
    }
    for key in ACCURACY:
        out[key] = np.array([float(r.get(key, np.nan)) for r in runs])  # type: ignore[arg-type]
    return out


def _paired(
    a: list[dict[str, object]], b: list[dict[str, object]]
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Metrics of two arms over the objectives both ran (run ``k`` is objective ``k``)."""
    n = min(len(a), len(b))
    return _metrics(a[:n]), _metrics(b[:n])


def _target(
    data: Data, grid: str, scenario: str, arm: str, base: str
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], bool] | None:
    """The paired metrics of ``arm`` and ``base`` in one cell (None: one is not cached) and
    whether the target holds: at least 70% fewer worst gaits at no more than 0.01 loss."""
    if (grid, scenario, arm) not in data or (grid, scenario, base) not in data:
        return None
    a, b = _paired(data[(grid, scenario, arm)], data[(grid, scenario, base)])
    fewer = b["worst"].mean() > 0 and a["worst"].mean() <= 0.3 * b["worst"].mean()
    return a, b, bool(fewer and (a["all"] - b["all"]).mean() >= -0.01)


def _se(x: np.ndarray) -> float:
    return float(np.std(x, ddof=1) / np.sqrt(x.size)) if x.size > 1 else float("nan")


def _pm(x: np.ndarray, signed: bool = False) -> str:
    if np.all(np.isnan(x)):
        return ""
    return f"{x.mean():+.3f} ± {_se(x):.3f}" if signed else f"{x.mean():.3f} ± {_se(x):.3f}"


def _reduction(a: np.ndarray, b: np.ndarray) -> str:
    """``1 - mean(a) / mean(b)`` with a paired bootstrap standard error (2000 draws, seeded)."""
    if b.mean() == 0:
        return "n/a"
    rng = np.random.default_rng(STUDY_SEED)
    idx = rng.integers(0, a.size, size=(2000, a.size))
    mb = b[idx].mean(axis=1)
    boot = 1 - a[idx].mean(axis=1) / np.where(mb > 0, mb, np.nan)
    return f"{1 - a.mean() / b.mean():.0%} ± {np.nanstd(boot, ddof=1):.0%}"


def report() -> None:
    data = _load()
    if not data:
        raise SystemExit(f"no cached runs under {CACHE}: run the study first")
    RESULTS.mkdir(parents=True, exist_ok=True)
    keys = ["grid", "scenario", "arm", "objective", "mean_1_20", "mean_1_60", "worst_share_1_60"]
    extra = [*ACCURACY, "seconds", "stopped"]
    extra += ["roi_size", "refits"]
    with (RESULTS / "runs.csv").open("w", newline="") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(keys + extra)
        for (grid, scenario, arm), runs in data.items():
            for k, r in enumerate(runs):
                s, c = np.asarray(r["scores"]), np.asarray(r["categories"])
                cells = [grid, scenario, arm, k, f"{s[:20].mean():.5f}", f"{s.mean():.5f}"]
                cells.append(f"{np.mean(c == 1):.5f}")
                for e in extra:
                    v = r.get(e, "")
                    cells.append(f"{v:.5g}" if isinstance(v, float) else v)
                w.writerow(cells)
    _summary(data)
    _figure(data)


def _summary(data: Data) -> None:
    lines = [
        "# Ordinal study: results",
        "",
        "Generated by `python benchmarks/study_ordinal.py report` from the cached runs (the",
        "module docstring of `benchmarks/study_ordinal.py` says what every arm, grid and subject",
        "is).  Every arm: the default strategy (gated-eubo, lengthscales fitted every 20",
        "answers), n = 1, b = 1, no coactive feedback, 60 trials; ratings at the objective's",
        "quartiles.  Cells are means over runs (one per objective) ± standard error; differences",
        "are paired (same objective, same seeds).  `worst` is the share of executed gaits whose",
        'true category is the worst ("very bad", the objective\'s lowest quarter) over trials',
        "1-60; accuracy is the share of gaits whose predicted rating (argmax of",
        "`posterior.rating_probabilities`) is the true category, over the true region of",
        'interest (ROI: the gaits not truly "very bad") or over the whole grid.',
        "",
    ]
    for grid in GRIDS:
        for scenario in SCENARIOS:
            rows = [
                (a, data[(grid, scenario, a.name)])
                for a in ARMS
                if (grid, scenario, a.name) in data
            ]
            if not rows:
                continue
            lines += [f"## {grid} grid, {scenario} subject ({len(rows[0][1])} objectives)", ""]
            lines += [
                "| arm | trials 1-20 | trials 1-60 | worst, 1-60 | accuracy ROI @30 | @60 "
                "| accuracy all @30 | @60 | fitted t: ROI @30 | @60 | all @30 | @60 "
                "| s/run | stopped | ROI at 60 | what |",
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
            ]
            for arm, runs in rows:
                m = _metrics(runs)
                cells = [arm.name] + [_pm(m[k]) for k in ("early", "all", "worst")]
                cells += [_pm(m[k]) for k in ACCURACY]
                cells += [
                    f"{m['seconds'].mean():.1f}",
                    str(int(m["stopped"].sum())),
                    f"{m['roi_size'].mean():.0f}",
                    arm.note,
                ]
                lines.append("| " + " | ".join(cells) + " |")
            lines.append("")
    lines += _comparisons(data)
    runs = sum(len(r) for r in data.values())
    seconds = sum(float(x["seconds"]) for r in data.values() for x in r)  # type: ignore[arg-type]
    ran = _runs_machine()
    jobs = ran.get("jobs", 1) if ran else 1
    lines += [
        "## What ran",
        "",
        f"{runs} runs of 60 trials ({len(data)} grid x subject x arm cells), "
        f"{seconds / 60:.0f} minutes of run time in all (the sum of each run's wall time, "
        f"`--jobs {jobs}` processes, one BLAS thread each).  `s/run` is wall time on a machine",
        "shared with other work (see the load below): read it as a rough cost, not a speed result.",
        "",
    ]
    if NOTES.is_file():
        lines += ["## Reading the results", "", NOTES.read_text().strip(), ""]
    lines += _machine_sections(ran)
    (RESULTS / "summary.md").write_text("\n".join(lines))


def _comparisons(data: Data) -> list[str]:
    lines = [
        "## Region of avoidance against no region of avoidance",
        "",
        "Target (issue 12): at least 70% fewer executed gaits in the worst category over trials",
        "1-60, at no more than 0.01 loss of mean normalised objective over trials 1-60.",
        "`reduction` is `1 - worst(arm) / worst(base)` with a paired bootstrap standard error.",
        "",
        "`1-5` and `6-60`: the worst share over trials 1-5 (before the region knows anything: the",
        "first gaits are all but random) and over trials 6-60, arm / base.",
        "",
        "| grid | subject | arm - base | worst share: arm | base | reduction | paired diff "
        "| 1-5 | 6-60 | objective 1-60: paired diff | met |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for grid in GRIDS:
        for scenario in SCENARIOS:
            for arm, bases in AVOIDANCE:
                for base in bases:
                    pair = _target(data, grid, scenario, arm, base)
                    if pair is None:
                        continue
                    a, b, met = pair
                    lines.append(
                        f"| {grid} | {scenario} | {arm} - {base} | {a['worst'].mean():.3f} "
                        f"| {b['worst'].mean():.3f} | {_reduction(a['worst'], b['worst'])} "
                        f"| {_pm(a['worst'] - b['worst'], True)} "
                        f"| {a['worst_1_5'].mean():.3f} / {b['worst_1_5'].mean():.3f} "
                        f"| {a['worst_6_60'].mean():.3f} / {b['worst_6_60'].mean():.3f} "
                        f"| {_pm(a['all'] - b['all'], True)} "
                        f"| {'yes' if met else 'no'} |"
                    )
    lines += [
        "",
        "## Ratings and preferences against preferences alone",
        "",
        "Target (issue 12): +0.03 or better mean normalised objective over trials 1-20.",
        "",
        "| grid | subject | trials 1-20: rated - prefs | trials 1-60: rated - prefs | met |",
        "|---|---|---|---|---|",
    ]
    for grid in GRIDS:
        for scenario in SCENARIOS:
            if (grid, scenario, "rated") not in data or (grid, scenario, "prefs") not in data:
                continue
            a, b = _paired(data[(grid, scenario, "rated")], data[(grid, scenario, "prefs")])
            d = a["early"] - b["early"]
            lines.append(
                f"| {grid} | {scenario} | {_pm(d, True)} | {_pm(a['all'] - b['all'], True)} "
                f"| {'yes' if d.mean() >= 0.03 else 'no'} |"
            )
    lines += [
        "",
        "## Accuracy of the predicted rating: information gain against random selection and "
        "the default strategy",
        "",
    ]
    if not any(key[2] == "infogain" for key in data):
        lines += [
            "Not run: this gaitpref has no `information-gain` strategy yet (it arrives from",
            "another branch); the `random` and `rated` (default strategy) arms' accuracies are in",
            "the tables above, ready for the comparison.",
            "",
        ]
        return lines
    lines += [
        "| grid | subject | arm - base | ROI @30 | ROI @60 | all @30 | all @60 "
        "| fitted t: ROI @30 | @60 | all @30 | @60 |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for grid in GRIDS:
        for scenario in SCENARIOS:
            for arm, base in [
                ("infogain", "random"),
                ("infogain", "rated"),
                ("infogain+avoid-1", "random+avoid-1"),
                ("infogain+avoid-1", "rated"),
                ("infogain+risk", "random+risk"),
                ("infogain+risk", "infogain"),
                ("infogain+risk", "rated"),
                ("infogain+cautious", "random+cautious"),
                ("infogain+cautious", "infogain"),
            ]:
                if (grid, scenario, arm) not in data or (grid, scenario, base) not in data:
                    continue
                a, b = _paired(data[(grid, scenario, arm)], data[(grid, scenario, base)])
                cells = [grid, scenario, f"{arm} - {base} ({a['all'].size} objectives)"]
                cells += [_pm(a[k] - b[k], True) for k in ACCURACY]
                lines.append("| " + " | ".join(cells) + " |")
    lines.append("")
    return lines


def report_start() -> None:
    """``docs/results/ordinal/start.md``: the start-gait arms (``START_ARMS``) and their paired
    comparisons, from the cached runs of those arms (and of ``rated`` and ``avoid-cautious``
    where cached); written apart from ``summary.md``, whose arms need not all be cached."""
    data: Data = {}
    for grid in GRIDS:
        for scenario in SCENARIOS:
            for arm in [*START_ARMS, *ARMS]:
                path = _cache(grid, scenario, arm.name)
                if path.is_file() and (arm in START_ARMS or arm.name in _START_CONTEXT):
                    data[(grid, scenario, arm.name)] = json.loads(path.read_text())["runs"]
    if not data:
        raise SystemExit(f"no cached runs of the start arms under {CACHE}: run them first")
    RESULTS.mkdir(parents=True, exist_ok=True)
    lines = [
        "# Ordinal study: a declared-safe start gait",
        "",
        "Generated by `python benchmarks/study_ordinal.py report-start` from the cached runs of",
        "the start arms.  As the rest of the study (`summary.md`): the default strategy",
        "(gated-eubo), n = 1, b = 1, 60 trials, ratings at the quartiles, run `k` on objective `k`",
        "with the same seeds in every arm.  The start arms give `[safety] start` the simulated",
        "operator's start gait: drawn uniformly (seeded per objective) among the gaits whose true",
        'category is "okay" or better (`start_gait`), so trial 1 walks a gait known to be',
        "comfortable, not one known to be near the best.  `worst/run` is the number of executed",
        'gaits truly "very bad" over trials 1-60 (split 1 / 2-5 / 6-60); `known@t` the',
        "known-safe gaits after trial `t` (of them truly very bad).",
        "",
    ]
    for grid in GRIDS:
        for scenario in SCENARIOS:
            rows = [
                (n, data[(grid, scenario, n)]) for n in _START_ORDER if (grid, scenario, n) in data
            ]
            if not rows:
                continue
            lines += [f"## {grid} grid, {scenario} subject ({len(rows[0][1])} objectives)", ""]
            lines += [
                "| arm | trials 1-20 | trials 1-60 | worst/run | 1 / 2-5 / 6-60 "
                + "".join(f"| known@{t} " for t in KNOWN_AT)
                + "| s/run |",
                "|---|---|---|---|---" + "|---" * len(KNOWN_AT) + "|---|",
            ]
            for name, runs in rows:
                m = _metrics(runs)
                c = np.array([r["categories"] for r in runs]) == 1
                per = [c[:, :1].sum(1).mean(), c[:, 1:5].sum(1).mean(), c[:, 5:].sum(1).mean()]
                cells = [name, _pm(m["early"]), _pm(m["all"]), _pm(c.sum(1).astype(float))]
                cells.append(" / ".join(f"{x:.2f}" for x in per))
                for t in KNOWN_AT:
                    known = [float(r[f"known_{t}"]) for r in runs if f"known_{t}" in r]  # type: ignore[arg-type]
                    bad = [float(r[f"known_bad_{t}"]) for r in runs if f"known_{t}" in r]  # type: ignore[arg-type]
                    cells.append(f"{np.mean(known):.0f} ({np.mean(bad):.1f})" if known else "")
                cells.append(f"{m['seconds'].mean():.1f}")
                lines.append("| " + " | ".join(cells) + " |")
            lines.append("")
    lines += [
        "## Paired comparisons",
        "",
        "Target (issue 12): at least 70% fewer executed gaits in the worst category over trials",
        "1-60 with the region of avoidance than without it, at no more than 0.01 loss of mean",
        "normalised objective over trials 1-60; the target's reading is `cautious+start -",
        "rated+start` (and `reach+start - rated+start`): the same start gait, region or none.",
        "`reduction` is `1 - worst(arm) / worst(base)` with a paired bootstrap standard error.",
        "",
        "| grid | subject | arm - base | worst/run: arm | base | reduction | paired diff "
        "| objective 1-20: diff | objective 1-60: diff | met |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for grid in GRIDS:
        for scenario in SCENARIOS:
            for arm, base in START_PAIRS:
                pair = _target(data, grid, scenario, arm, base)
                if pair is None:
                    continue
                a, b, met = pair
                lines.append(
                    f"| {grid} | {scenario} | {arm} - {base} ({a['all'].size}) "
                    f"| {a['worst'].mean() * TRIALS:.2f} | {b['worst'].mean() * TRIALS:.2f} "
                    f"| {_reduction(a['worst'], b['worst'])} "
                    f"| {_pm((a['worst'] - b['worst']) * TRIALS, True)} "
                    f"| {_pm(a['early'] - b['early'], True)} | {_pm(a['all'] - b['all'], True)} "
                    f"| {'yes' if met else 'no'} |"
                )
    lines += ["", *_machine_sections(_runs_machine(), _START_ORDER)]
    (RESULTS / "start.md").write_text("\n".join(lines))


_START_CONTEXT = ("rated", "avoid-cautious")  # arms without a start gait, for context
_START_ORDER = [*_START_CONTEXT, *(a.name for a in START_ARMS)]


def _figure(data: Data) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    shown = ["prefs", "rated", "avoid-cautious", "random", "random+cautious"]
    shown += ["infogain", "infogain+cautious"]
    panels = [(g, s) for g in GRIDS for s in SCENARIOS]
    fig, axes = plt.subplots(2, len(panels), figsize=(4 * len(panels), 7), sharex=True)
    for col, (grid, scenario) in enumerate(panels):
        for name in shown:
            if (grid, scenario, name) not in data:
                continue
            runs = data[(grid, scenario, name)]
            s = np.array([r["scores"] for r in runs])
            worst = np.cumsum(np.array([r["categories"] for r in runs]) == 1, axis=1)
            t = np.arange(1, s.shape[1] + 1)
            for row, values in ((0, s), (1, worst / t)):
                mean = values.mean(axis=0)
                se = values.std(axis=0, ddof=1) / np.sqrt(values.shape[0])
                axes[row, col].plot(t, mean, label=name)
                axes[row, col].fill_between(t, mean - se, mean + se, alpha=0.2)
        axes[0, col].set_title(f"{grid} grid, {scenario} subject")
        axes[1, col].set_xlabel("trial")
        for row in (0, 1):
            axes[row, col].grid(alpha=0.3)
    axes[0, 0].set_ylabel("mean normalised objective")
    axes[1, 0].set_ylabel('share of gaits so far truly "very bad"')
    axes[0, 0].legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(RESULTS / "ordinal.png", dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run")
    r.add_argument("--grids", default=",".join(GRIDS))
    r.add_argument("--objectives", type=int, default=100, help="2-D objectives")
    r.add_argument("--objectives-3d", type=int, default=30)
    r.add_argument("--arms", default="all", help="comma-separated arm names, or 'all'")
    r.add_argument("--scenarios", default=",".join(SCENARIOS))
    r.add_argument("--jobs", type=int, default=2)
    r.add_argument("--skip-cached", action="store_true", help="keep complete cached cells")
    r.add_argument("--infogain-2d", type=int, default=None, help="2-D objectives for infogain")
    sub.add_parser("report")
    sub.add_parser("report-start", help="docs/results/ordinal/start.md: the start-gait arms")
    args = parser.parse_args()
    if args.command == "report":
        report()
        return
    if args.command == "report-start":
        report_start()
        return
    names = {a.name: a for a in [*ARMS, *START_ARMS]}
    arms = ARMS if args.arms == "all" else [names[n] for n in args.arms.split(",")]
    counts = {"2d": args.objectives, "3d": args.objectives_3d}
    grids, scenarios = args.grids.split(","), args.scenarios.split(",")
    run(arms, grids, scenarios, counts, args.jobs, args.skip_cached, args.infogain_2d)


if __name__ == "__main__":
    main()
