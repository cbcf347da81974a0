"""Warm against cold on a simulated clinic: ``gaitpref bench population``.

The objectives hold one utility grid per subject (``S x A``).  Every subject first walks ``T``
trials alone (the cold run, simulated as ``gaitpref simulate`` does: the config's loop, a
simulated user, noiseless unless ``user_noise`` is given, comparisons only); then, for each
held-out subject, the same run again (same seeds) warm-started from the other subjects' cold
runs (``loop/warm.py``: their preferences through the population kernel, ``rho`` learned from
them).  A trial's score is the normalised objective of its executed gait (1 at the subject's
best, 0 at the worst).

After every answer, in both runs, the loop states its confidence (``loop/stopping.py``): the
probability that its recommended gait is within ``tolerance`` of the best, and the truth is
checked against the subject's objective.  :func:`calibration` bins those pairs: when it said
``p``, how often it was right.

:func:`synthetic_population` builds the populations of the study in
``docs/results/population``: each subject's utility is ``sqrt(rho) z_0 + sqrt(1 - rho) z_s``
over standardised objectives ``z`` (the paper's, ``gaitpref.data``).

A bench that stopped resumes from its partial file (:func:`population_bench`, ``resume``): the
file's first line names the bench (:func:`population_sweep`), each cold run's line holds the
preferences it left (:func:`walked_record`), from which the warm runs start, so the runs kept
are rebuilt from the file and only the others run (:mod:`gaitpref.simulate.resume_lines`).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from gaitpref.config import ExperimentConfig
from gaitpref.feedback import Preference
from gaitpref.limits import MAX_POPULATION_NODES, MAX_SEED, MAX_TRIALS
from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.stopping import check_tolerance, confidence
from gaitpref.loop.warm import RELEARN_EVERY, relearning, warm_start
from gaitpref.simulate.partial import JsonLines, partial_file, run_error
from gaitpref.simulate.resume import ResumeError
from gaitpref.simulate.resume_lines import first_line, read_lines, write_lines
from gaitpref.simulate.sweep import run_tasks
from gaitpref.simulate.users import SimulatedUser, check_user_noise, objective_on_grid
from gaitpref.space import FloatArray

#: A subject's two runs, in the order they run: alone, then warm-started from the others.
ARMS = ("cold", "warm")
#: The other subjects' preferences a warm run starts from.
Others = Sequence[Sequence[Preference]]


@dataclass(frozen=True)
class Walked:
    """One subject's run: per-trial scores, the preferences it left, and the confidence pairs
    ``(stated probability, recommendation truly within tolerance)`` after each answer."""

    scores: list[float]
    preferences: list[Preference]
    stated: list[float]
    right: list[bool]
    rho: float | None = None
    share: float | None = None  # the new subject's share at the end (warm, re-learned)
    alone: float | None = None  # the weight on share 0 at the end (warm, share = "average")


def _walk_args(args: tuple[Any, ...]) -> Walked:
    """:func:`_walk` of one task's arguments (the function the sweep runs)."""
    return _walk(*args)


def walked_record(subject: int, arm: str, seed: int, walked: Walked) -> dict[str, object]:
    """One finished run as a bench keeps it when another fails (a line of the partial file); a
    cold run's holds the preferences it left (``"preferences"``: ``winner``, ``loser``,
    ``noise``, ``source`` and ``query_id``, a list each), from which the warm runs start."""
    record: dict[str, object] = {
        "subject": subject,
        "run": arm,
        "seed": seed,
        "scores": walked.scores,
        "stated": walked.stated,
        "right": walked.right,
        "rho": walked.rho,
        "share": walked.share,
        "alone": walked.alone,
    }
    if arm == "cold":
        prefs = walked.preferences
        record["preferences"] = {
            "winner": [int(p.winner) for p in prefs],
            "loser": [int(p.loser) for p in prefs],
            "noise": [float(p.noise) for p in prefs],
            "source": [p.source for p in prefs],
            "query_id": [int(p.query_id) for p in prefs],
        }
    return record


def _walked_of(record: Mapping[str, Any]) -> Walked:
    """The run a :func:`walked_record` holds (KeyError, TypeError or ValueError when it is not
    one; the caller checks that it gives the record back)."""
    prefs: list[Preference] = []
    if record["run"] == "cold":
        cols = record["preferences"]
        fields = ("winner", "loser", "noise", "source", "query_id")
        if not isinstance(cols, dict) or sorted(cols) != sorted(fields):
            raise ValueError("not the preferences of a run")
        rows = zip(*(cols[f] for f in fields), strict=True)
        for winner, loser, noise, source, query_id in rows:
            if source not in ("comparison", "coactive"):
                raise ValueError(f"not a source of a preference: {source!r}")
            prefs.append(Preference(winner, loser, noise, source, query_id))
    return Walked(
        list(record["scores"]), prefs, list(record["stated"]), list(record["right"]),
        record["rho"], record["share"], record["alone"],
    )  # fmt: skip


def _array_digest(values: ArrayLike) -> str:
    arr = np.ascontiguousarray(values, dtype="<f8")
    return hashlib.sha256(str(arr.shape).encode("ascii") + arr.tobytes()).hexdigest()


def population_sweep(
    config: ExperimentConfig,
    objectives: ArrayLike,
    trials: int,
    *,
    seed: int,
    tolerance: float,
    samples: int,
    user_noise: float,
    relearn_every: int,
    truths: ArrayLike | None,
) -> dict[str, object]:
    """What ``bench population``'s runs depend on (its partial file's first line names it): the
    release, the config's name and text (a digest), the objectives (and truths: a digest of
    their values), the trials, seed, tolerance, confidence samples, the subjects' noise and how
    often the warm runs re-learn the share.  Not ``jobs``: the runs are the same on any."""
    from gaitpref import __version__

    return {
        "bench": "population",
        "gaitpref": __version__,
        "config": config.name,
        "config_sha256": config.sha256,
        "objectives_sha256": _array_digest(objectives),
        "truths_sha256": None if truths is None else _array_digest(truths),
        "trials": trials,
        "seed": seed,
        "tolerance": tolerance,
        "samples": samples,
        "user_noise": user_noise,
        "relearn_every": relearn_every,
    }


def _kept_runs(
    partial: Path, sweep: Mapping[str, object], subjects: int, trials: int, seed: int
) -> dict[tuple[str, int], Walked]:
    """The finished runs in ``partial`` by (arm, subject) (the file written again without a
    line cut short); a line that is not a run of this bench is refused naming it."""
    if not partial.is_file():
        raise FileNotFoundError(
            f"{partial}: no such file, no finished runs to resume from; run the bench without "
            "resuming"
        )
    lines, rewrite = read_lines(partial, sweep)
    kept: dict[tuple[str, int], Walked] = {}
    for line, record in lines:
        where = f"{partial}:{line}"
        k, arm = record.get("subject"), record.get("run")
        scores = record.get("scores")
        if (
            not isinstance(k, int)
            or not 0 <= k < subjects
            or arm not in ARMS
            or record.get("seed") != seed
            or not isinstance(scores, list)
            or len(scores) != trials
        ):
            raise ResumeError(
                f"{where}: not a run of this bench (subjects 0..{subjects - 1}, cold or warm, "
                f"seed {seed}, {trials} trials)"
            )
        assert isinstance(arm, str)
        if (arm, k) in kept:
            raise ResumeError(f"{where}: the {arm} run of subject {k} is in the file twice")
        try:
            walked = _walked_of(record)
            same = json.dumps(walked_record(k, arm, seed, walked)) == json.dumps(record)
        except (KeyError, TypeError, ValueError):
            same = False
        if not same:
            raise ResumeError(f"{where}: not a run record of bench population (subject {k}, {arm})")
        kept[arm, k] = walked
    if rewrite:
        records = [walked_record(k, arm, seed, w) for (arm, k), w in kept.items()]
        write_lines(partial, sweep, records)
    return kept


def _walk(
    config: ExperimentConfig,
    objective: FloatArray,
    truth: FloatArray,
    trials: int,
    seeds: Sequence[int],
    others: Sequence[Sequence[Preference]] | None,
    tolerance: float,
    samples: int,
    user_noise: float = 0.0,
    relearn_every: int = RELEARN_EVERY,
) -> Walked:
    loop_ss, user_ss, sure_ss = np.random.SeedSequence(list(seeds)).spawn(3)
    loop: CoSpar = config.make_loop(seed=np.random.default_rng(loop_ss))
    rho = None
    if others is not None:
        warm = warm_start(config.space, loop.hyper, loop.prior, others)
        if relearn_every:  # start alone, share as the evidence says (as sessions made now)
            warm = relearning(warm, relearn_every)
        loop.warm_start(warm)
        rho = warm.rho
    user = SimulatedUser(config.space, objective, np.random.default_rng(user_ss), noise=user_noise)
    sure_rng = np.random.default_rng(sure_ss)
    span = float(truth.max() - truth.min())
    executed: list[int] = []
    stated: list[float] = []
    right: list[bool] = []
    while len(executed) < trials:
        query = loop.ask()
        loop.tell(query, user.answer(query))
        executed.extend(query.actions)
        sure = confidence(
            loop.posterior, sure_rng, tolerance=tolerance, samples=samples,
            draws=loop.share_mixture(),
        )  # fmt: skip
        stated.append(sure.probability)
        right.append(bool(truth.max() - truth[sure.recommended] <= tolerance * span))
    scores = user.normalized(np.asarray(executed[:trials], dtype=np.intp)).tolist()
    share = None if loop.warm is None else loop.warm.share
    alone = next((h.weight for h in loop.share_hypotheses if h.share == 0.0), None)
    return Walked(scores, list(loop.preferences), stated, right, rho, share, alone)


def _bin_of(p: FloatArray, bins: int) -> NDArray[np.intp]:
    """The bin of each probability among ``bins`` equal bins of ``[0, 1]`` (1 in the last)."""
    out: NDArray[np.intp] = np.minimum((p * bins).astype(np.intp), bins - 1)
    return out


def calibration(stated: ArrayLike, right: ArrayLike, bins: int = 10) -> list[dict[str, float]]:
    """Stated probability against observed frequency, in ``bins`` equal bins of ``[0, 1]``."""
    p = np.asarray(stated, dtype=np.float64)
    hit = np.asarray(right, dtype=np.float64)
    which = _bin_of(p, bins)
    out = []
    for b in range(bins):
        mine = which == b
        if mine.any():
            out.append(
                {
                    "lo": b / bins,
                    "hi": (b + 1) / bins,
                    "count": int(mine.sum()),
                    "stated": float(p[mine].mean()),
                    "observed": float(hit[mine].mean()),
                }
            )
    return out


def cluster_bootstrap(
    runs: Sequence[tuple[Sequence[float], Sequence[bool]]],
    rng: np.random.Generator,
    bins: int = 10,
    resamples: int = 2000,
) -> list[dict[str, float]]:
    """:func:`calibration` of all ``runs`` (``(stated, right)`` per cluster: one subject's
    answers), with each bin's number of clusters and the standard error of its ``observed -
    stated`` from ``resamples`` resamples of whole clusters (answers within a subject's run are
    correlated: the binomial standard error understates it).  A resample that leaves a bin
    empty does not count towards that bin's standard error."""
    if not runs:
        raise ValueError("cluster_bootstrap needs at least one run")
    stated = [np.asarray(p, dtype=np.float64) for p, _ in runs]
    right = [np.asarray(r, dtype=np.float64) for _, r in runs]
    which = [_bin_of(p, bins) for p in stated]
    # per cluster and bin: count, sum of stated, sum of right
    table = np.zeros((len(runs), 3, bins))
    for c, (w, p, r) in enumerate(zip(which, stated, right, strict=True)):
        table[c, 0] = np.bincount(w, minlength=bins)
        table[c, 1] = np.bincount(w, weights=p, minlength=bins)
        table[c, 2] = np.bincount(w, weights=r, minlength=bins)
    picks = rng.integers(0, len(runs), size=(resamples, len(runs)))
    sums = table[picks].sum(axis=1)  # resamples x 3 x bins
    with np.errstate(invalid="ignore", divide="ignore"):
        gaps = (sums[:, 2] - sums[:, 1]) / sums[:, 0]
    out = []
    for b in calibration(np.concatenate(stated), np.concatenate(right).astype(bool), bins):
        k = round(b["lo"] * bins)
        g = gaps[:, k][np.isfinite(gaps[:, k])]
        se = float(g.std(ddof=1)) if g.size > 1 else float("nan")
        out.append({**b, "clusters": int(np.count_nonzero(table[:, 0, k])), "se": se})
    return out


def _subject_grids(config: ExperimentConfig, objectives: FloatArray, name: str) -> list[FloatArray]:
    """One flat utility grid per subject from ``S x grid`` (or ``S x`` the grid's shape);
    ValueError names the array's shape, or the subject whose grid cannot be used."""
    arr = np.asarray(objectives)
    space = config.space
    if arr.ndim != 1 + len(space.shape) and arr.ndim != 2:
        raise ValueError(
            f"{name}: expected one utility grid per subject, S x {len(space)} or S x "
            f"{' x '.join(map(str, space.shape))}, got an array of shape {arr.shape}"
        )
    out = []
    for k, grid in enumerate(arr):
        try:
            out.append(objective_on_grid(space, grid))
        except ValueError as exc:
            raise ValueError(f"{name}: subject {k} (row {k} of the array): {exc}") from None
    return out


def population_bench(
    config: ExperimentConfig,
    objectives: FloatArray,
    trials: int,
    *,
    seed: int = 0,
    jobs: int = 1,
    tolerance: float = 0.05,
    samples: int = 300,
    user_noise: float = 0.0,
    relearn_every: int = RELEARN_EVERY,
    truths: FloatArray | None = None,
    partial: str | Path | None = None,
    resume: bool = False,
    progress: Callable[[int], None] | None = None,
) -> dict[str, object]:
    """The JSON of ``gaitpref bench population`` (module docstring); ``user_noise``: the
    simulated subjects' probit noise in the objectives' units (``simulate/users.py``);
    ``relearn_every``: the warm runs re-learn the new subject's share every so many answers
    (0: ``rho`` held, as warm starts recorded before share refits; otherwise the new subject
    starts alone and the share is gated as sessions' warm starts, ``loop/warm.py``);
    ``truths``: the grids on which the recommendation is judged (``S x A``; None: the
    objectives; :func:`gp_population` gives the smooth parts of prior draws).

    A run that fails stops the bench with :class:`~gaitpref.simulate.partial.RunError` naming
    it (subject, cold or warm, seed), its error the ``__cause__``, the finished runs on it as
    :func:`walked_record` records; ``partial``: a new file each finished run's record is
    appended to as it finishes (JSON lines), removed once every run has finished (one that
    exists is refused, ``FileExistsError``, not written over).  The file's first line names the
    bench (:func:`population_sweep`); ``resume``: ``partial`` is such a file, left by this bench
    when it stopped: its runs are kept (a cold run's preferences with it, from which the warm
    runs start), only the others run, and the results are those of a bench that never stopped;
    a file of another bench is refused (:class:`~gaitpref.simulate.resume.ResumeError` naming
    what differs), a last line cut short dropped with a
    :class:`~gaitpref.simulate.resume.PartialRunsWarning` (its run runs again).

    ``progress``: called with the number of runs finished (of ``2 x`` subjects, those a resume
    kept included) as each run finishes, and once before any runs.

    ``trials`` is at most :data:`~gaitpref.limits.MAX_TRIALS`, and subjects x the gaits each
    run may visit at most :data:`~gaitpref.limits.MAX_POPULATION_NODES`: refused (a ValueError)
    before any run."""
    grids = _subject_grids(config, objectives, "objectives")
    if len(grids) < 2:
        raise ValueError(f"a population needs at least 2 subjects, got {len(grids)}")
    if truths is None:
        judged = grids
    else:
        judged = _subject_grids(config, truths, "truths")
        if len(judged) != len(grids):
            raise ValueError(f"truths: one grid per subject ({len(grids)}), got {len(judged)}")
    if not 1 <= trials <= MAX_TRIALS:  # every trial runs: 10**12 ran until the memory was full
        raise ValueError(f"trials must be 1 to {MAX_TRIALS}, got {trials}")
    if not 0 <= seed <= MAX_SEED:
        raise ValueError(f"seed must be 0 to {MAX_SEED}, got {seed}")
    gaits = min(len(config.space), trials + config.n - 1)  # the most one subject's run visits
    if len(grids) * gaits > MAX_POPULATION_NODES:  # a warm run's fit is dense in them
        raise ValueError(
            f"{len(grids)} subjects x up to {gaits} gaits each ({trials} trials) is "
            f"{len(grids) * gaits} (gait, subject) nodes in a warm run's model, more than "
            f"{MAX_POPULATION_NODES} (its fit, dense in them, is refitted after every answer); "
            "give fewer subjects or trials"
        )
    check_user_noise(user_noise)  # refused here, not as every run's failure
    check_tolerance(tolerance)  # likewise (a run failure, status 1, before)
    S = len(grids)
    sweep = population_sweep(
        config, objectives, trials, seed=seed, tolerance=tolerance, samples=samples,
        user_noise=user_noise, relearn_every=relearn_every, truths=truths,
    )  # fmt: skip
    kept: dict[tuple[str, int], Walked] = {}
    sink: JsonLines | None = None
    if resume:
        if partial is None:
            raise ValueError("resume: give the partial file the bench stopped with")
        kept = _kept_runs(Path(partial), sweep, S, trials, seed)
        sink = JsonLines(partial, existing=len(kept))
    elif partial is not None:
        sink = JsonLines(partial, first=first_line(sweep))
    walked: dict[str, list[Walked | None]] = {
        arm: [kept.get((arm, k)) for k in range(S)] for arm in ARMS
    }

    def run(arm: str, others: Sequence[Others | None]) -> list[Walked]:
        """Every subject's ``arm`` run not kept; a failure is a RunError keeping the finished
        runs."""
        todo = [k for k in range(S) if walked[arm][k] is None]
        args = [
            (config, grids[k], judged[k], trials, (seed, k), others[k], tolerance, samples,
             user_noise, relearn_every)
            for k in todo
        ]  # fmt: skip

        def done(index: int, w: Walked) -> None:
            walked[arm][todo[index]] = w
            if sink is not None:
                sink.append(walked_record(todo[index], arm, seed, w))
            if progress is not None:
                progress(sum(x is not None for a in ARMS for x in walked[a]))

        _, failure = run_tasks(_walk_args, args, jobs, done=done)
        if failure is not None:
            records = [
                walked_record(k, a, seed, w)
                for a in ARMS
                for k, w in enumerate(walked[a])
                if w is not None
            ]
            names = [f"subject {k} ({arm}), seed {seed}" for k in todo]
            raise run_error(failure, names, records, 2 * S, None if sink is None else sink.path)
        return [w for w in walked[arm] if w is not None]

    if progress is not None:
        progress(len(kept))
    with partial_file(sink):
        cold = run("cold", [None] * S)
        warm = run("warm", [[c.preferences for j, c in enumerate(cold) if j != k]
                            for k in range(S)])  # fmt: skip
    stated = [p for w in (*cold, *warm) for p in w.stated]
    right = [r for w in (*cold, *warm) for r in w.right]
    return {
        "subjects": [
            {
                "subject": k,
                "cold": c.scores,
                "warm": w.scores,
                "rho": w.rho,
                "share": w.share,
                "alone": w.alone,
                "stated": {"cold": c.stated, "warm": w.stated},
                "right": {"cold": c.right, "warm": w.right},
            }
            for k, (c, w) in enumerate(zip(cold, warm, strict=True))
        ],
        "calibration": calibration(stated, right),
        "trials": trials,
        "tolerance": tolerance,
        "seed": seed,
        "user_noise": user_noise,
        "relearn_every": relearn_every,
        "share": config.learning.share,
    }


def synthetic_population(
    objectives: FloatArray, rho: float, subjects: int, shared: int = 0, first: int = 1
) -> FloatArray:
    """``subjects`` utilities ``sqrt(rho) z_shared + sqrt(1 - rho) z_(first + s)`` from
    standardised objectives ``z`` (rows of ``objectives``, each flattened)."""
    flat = np.asarray(objectives, dtype=np.float64).reshape(len(objectives), -1)
    z = (flat - flat.mean(axis=1, keepdims=True)) / flat.std(axis=1, keepdims=True)
    own = z[first : first + subjects]
    if own.shape[0] != subjects:
        raise ValueError(f"need {first + subjects} objectives, got {len(objectives)}")
    out: FloatArray = np.sqrt(rho) * z[shared] + np.sqrt(1.0 - rho) * own
    return out


def gp_population(
    config: ExperimentConfig, rho: float, subjects: int, rng: np.random.Generator
) -> tuple[FloatArray, FloatArray]:
    """``subjects`` utilities drawn from the config's own population prior: ``sqrt(rho) f_0 +
    sqrt(1 - rho) f_s`` with ``f ~ GP(0, k)`` the config's kernel (its signal variance and
    jitter), i.e. ``k((x, s), (x', s')) = k(x, x') (rho + (1 - rho) [s = s'])``
    (``model/population.py``); and their smooth parts (the same without the jitter's
    independent per-gait term), on which the confidence's recommendation is judged.  Answering
    with the config's noise (``user_noise = noise``), such subjects are the model's own
    assumption: its stated confidence should be calibrated on them."""
    if not 0.0 <= rho <= 1.0:
        raise ValueError(f"rho must lie in [0, 1], got {rho!r}")
    if subjects < 1:
        raise ValueError(f"subjects must be >= 1, got {subjects!r}")
    engine = config.make_loop(seed=0).posterior.engine
    full, jitter = engine.prior_parts(rng, subjects + 1)
    smooth = full if jitter is None else full - jitter
    a, b = np.sqrt(rho), np.sqrt(1.0 - rho)
    return a * full[0] + b * full[1:], a * smooth[0] + b * smooth[1:]


__all__ = [
    "Walked",
    "calibration",
    "cluster_bootstrap",
    "gp_population",
    "population_bench",
    "population_sweep",
    "synthetic_population",
    "walked_record",
]
