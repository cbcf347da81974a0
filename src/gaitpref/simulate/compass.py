"""The paper's compass-gait study (Fig. 2): CoSpar learns the step length of lowest COT.

Section "Optimizing the Compass-Gait Biped's Cost of Transport": 24 step lengths in
[0.08, 0.18] m, preferences from comparing COT (lower preferred), ``n = 2``, ``b = 0``, no
coactive feedback, the ``compass-gait`` config's kernel (lengthscale 0.025 m, signal variance
1e-4, jitter 1e-8) and noise 0.01.  The objective is the authors' COT polynomial (``"poly"``) or
the project's own HZD gaits at 0.2 m/s (``"hzd"``, :mod:`gaitpref.simulate.hzd`: a saved gait
library, or one built on the grid's step lengths).

:func:`posterior_snapshots` replays run ``seed`` of the study's CoSpar setting (the same seed
sequence as :func:`~gaitpref.simulate.study.run_one`) and records the posterior after given
iteration counts, with joint samples drawn from a third generator spawned from it.

Notation: ``A`` step lengths; utilities are ``A``-vectors (higher = lower COT is preferred).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from gaitpref.config import ExperimentConfig, load_config
from gaitpref.limits import MAX_RUNS, MAX_SNAPSHOTS, MAX_TRIALS
from gaitpref.loop.cospar import CoSpar
from gaitpref.simulate.hzd import build_cot_curve, library_objective, read_cot_curve
from gaitpref.simulate.objectives import cot_polynomial
from gaitpref.simulate.study import RunTask, Setting, Study, run_seed_sequence
from gaitpref.simulate.users import SimulatedUser
from gaitpref.space import FloatArray, IntArray, Space

ObjectiveKind = Literal["poly", "hzd"]
COMPASS_SETTING = Setting("n2_b0", n=2, buffer=0)


@dataclass(frozen=True, eq=False)
class Snapshot:
    """The posterior after ``iteration`` iterations: mean, sd, joint samples, trials so far."""

    iteration: int
    mean: FloatArray
    std: FloatArray
    samples: FloatArray  # (k, A)
    trials: IntArray  # executed actions so far


@dataclass(frozen=True, eq=False)
class CompassObjective:
    """The COT over the study's step lengths, and where it came from."""

    space: Space
    cot: FloatArray
    label: str
    note: str = ""


def compass_objective(
    kind: ObjectiveKind = "poly",
    library: str | Path | None = None,
    *,
    build_jobs: int = 1,
    save_library: str | Path | None = None,
) -> CompassObjective:
    """COT on the ``compass-gait`` grid: the authors' polynomial (``poly``) or HZD gaits (``hzd``).

    ``hzd`` reads ``library`` (a saved gait library, or a CSV/NPZ export), or without one builds
    a 0.2 m/s library on the grid's step lengths with ``build_jobs`` processes (about 0.5 s a
    gait) and saves it to ``save_library`` when given.
    """
    config = load_config("compass-gait")
    if kind == "poly":
        if library is not None:
            raise ValueError("--library is for --objective hzd")
        x = config.space.features[0].array
        return CompassObjective(config.space, cot_polynomial(x), "COT (authors' polynomial)")
    if kind == "hzd":
        if library is None:
            x = config.space.features[0].array
            curve = build_cot_curve(x, n_jobs=build_jobs, save=save_library)
            source = "the built library"
        else:
            curve, source = read_cot_curve(library), str(library)
        space, cot, note = library_objective(curve, config.space, source)
        return CompassObjective(space, cot, "COT (HZD gaits, 0.2 m/s)", note)
    raise ValueError(f"objective must be 'poly' or 'hzd', got {kind!r}")


def compass_gait_study(
    objective: CompassObjective,
    runs: int = 100,
    trials: int = 60,
    baseline: bool = True,
    seed: int = 0,
) -> Study:
    """``runs`` seeded CoSpar runs (and random selection) minimising the COT."""
    if not 1 <= runs <= MAX_RUNS:
        raise ValueError(f"runs must be 1 to {MAX_RUNS}, got {runs}")
    config = _config()
    settings = [COMPASS_SETTING, *([Setting.random()] if baseline else [])]
    return Study(
        "compass-gait",
        objective.space,
        config.kernel,
        config.noise,
        tuple(settings),
        objective.cot.reshape(1, -1),
        seeds=tuple(range(runs)),
        trials=trials,
        minimize=True,
        seed=seed,
    )


def _config() -> ExperimentConfig:
    return load_config("compass-gait")


def posterior_snapshots(
    study: Study,
    iterations: Sequence[int] = (1, 5, 10, 20),
    run_seed: int = 0,
    samples: int = 3,
) -> list[Snapshot]:
    """Posterior after each of ``iterations`` in run ``run_seed`` of the study's CoSpar setting
    (at most :data:`~gaitpref.limits.MAX_SNAPSHOTS` of them, each at most
    :data:`~gaitpref.limits.MAX_TRIALS`: the run replays up to the last, each one a panel)."""
    its = sorted(set(int(i) for i in iterations))
    if not its or its[0] < 0:
        raise ValueError(f"iterations must be non-negative counts, got {list(iterations)}")
    if len(its) > MAX_SNAPSHOTS:  # a figure panel each
        raise ValueError(f"iterations: at most {MAX_SNAPSHOTS} counts, got {len(its)}")
    if its[-1] > MAX_TRIALS:  # replayed one by one: 10**12 ran until the memory was full
        raise ValueError(f"iterations must be at most {MAX_TRIALS}, got {its[-1]}")
    setting = next((s for s in study.settings if s.strategy == "cospar"), None)
    if setting is None:
        raise ValueError("the study has no CoSpar setting to replay")
    task = RunTask(
        study.space,
        study.kernel,
        study.noise,
        setting,
        study.objectives[0],
        study.objective_ids[0],
        run_seed,
        study.trials,
        study.minimize,
        study.seed,
    )
    ss = run_seed_sequence(task.study_seed, setting.name, task.objective_id, run_seed)
    loop_ss, user_ss, sample_ss = ss.spawn(3)
    user = SimulatedUser(task.space, task.objective, np.random.default_rng(user_ss), task.minimize)
    loop = CoSpar(
        task.space,
        task.kernel,
        task.noise,
        n=setting.n,
        buffer=setting.buffer,
        seed=np.random.default_rng(loop_ss),
    )
    draw = np.random.default_rng(sample_ss)
    out: list[Snapshot] = []
    for it in range(its[-1] + 1):
        if it in its:
            post = loop.posterior
            out.append(
                Snapshot(
                    it,
                    np.array(post.mean),
                    np.array(post.std),
                    post.sample(draw, samples),
                    np.asarray(loop.executed, dtype=np.intp),
                )
            )
        if it < its[-1]:
            query = loop.ask()
            loop.tell(query, user.answer(query))
    return out
