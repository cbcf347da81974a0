"""A simulation study as data, and one run of it as a pure function.

A study is *settings x objectives x seeds* (the paper's Fig. 4: six CoSpar settings, the authors'
100 objectives, one run per objective).  Every run is independent: :func:`run_one` takes a
:class:`RunTask` (everything the run needs, nothing else) and returns its executed actions and
their normalised objective.  Its random generators come from
``numpy.random.SeedSequence(study seed, spawn_key=(setting, objective, seed))``, never from a
worker's identity or the order runs finish in, so a study gives the same numbers sequentially, on
joblib processes or on a Ray cluster.

Strategies: ``"cospar"`` (Algorithm 1 with ``n``, ``b`` and optionally the paper's simulated
coactive feedback, :class:`~gaitpref.simulate.users.GradientCoactive`) and ``"random"`` (each
trial a grid action drawn uniformly: the floor to read learning curves against).

Ratings and safety as arms: a setting with ``rating_quantiles`` has the simulated subject rate
every executed gait (:class:`~gaitpref.simulate.raters.OrdinalRater`, boundaries at those
quantiles of the objective, ordinal noise ``rating_noise``), and ``config`` carries the
``[feedback.rating]`` and ``[safety]`` tables of a config as TOML text (parsed as a config's,
with the study's ``noise`` as the default rating noise): the loop's rating scale and its region
of avoidance.  ``[safety] unsafe_radius`` is refused there: simulated subjects never flag a
trial unsafe, so it would do nothing.  A run's ratings go to the run table's ``rating`` column.

Notation: ``A`` grid actions, ``K`` objectives (rows of ``Study.objectives``, ``K x A``),
``T`` trials per run (a trial is one executed action).
"""

from __future__ import annotations

import hashlib
import itertools
import operator
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from gaitpref.checks import is_noise, is_number
from gaitpref.config import ExperimentConfig, read_toml
from gaitpref.config.feedback import parse_rating, parse_safety
from gaitpref.config.schema import MAX_QUERY
from gaitpref.errors import ConfigError, NoSafeGaitError
from gaitpref.limits import MAX_RUNS, MAX_SEED, MAX_STUDY_TRIALS, MAX_TRIALS
from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.safety import Safety
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.ordinal import Ordinal
from gaitpref.simulate.raters import OrdinalRater
from gaitpref.simulate.run import run_simulation
from gaitpref.simulate.users import GradientCoactive, SimulatedUser
from gaitpref.space import FloatArray, IntArray, Space

Strategy = Literal["cospar", "random"]


_CONFIG_TABLES = ("feedback", "safety")


def parse_setting_config(
    text: str, noise: float, where: str, space: Space | None = None
) -> tuple[Ordinal | None, Safety]:
    """The rating scale and safety settings of a setting's ``config`` text.

    ``text`` holds only ``[feedback.rating]`` and ``[safety]`` tables; ``noise`` is the default
    rating noise (the study's).  ``[safety] start`` names gaits of ``space``, the study's grid
    (by feature values or action index); without ``space`` (a setting alone, before it joins a
    study) its start gaits are left out here and checked by the study.  Errors are
    :class:`~gaitpref.errors.ConfigError` naming ``where`` (the setting) and the table and key.
    """
    try:
        top = read_toml(text)
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}") from None
    extra = sorted(set(top) - set(_CONFIG_TABLES))
    if extra:
        raise ConfigError(
            f"{where}: config text may hold only [feedback.rating] and [safety] tables, "
            f"got {', '.join(extra)}",
            table=extra[0],
        )
    try:
        ordinal = parse_rating(top.get("feedback", {}), noise)
        safety = top.get("safety", {})
        if space is None and isinstance(safety, dict) and "start" in safety:
            # it names gaits of the study's grid: refused before as on the line path
            safety = {k: v for k, v in safety.items() if k != "start"}
        return ordinal, parse_safety(safety, ordinal, space=space)[0]
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}", table=exc.table, key=exc.key) from None


@dataclass(frozen=True)
class Setting:
    """One arm of a study: CoSpar with ``(n, b)`` and coactive feedback or not, or random.

    ``rating_quantiles``: the simulated subject rates every executed gait, category boundaries
    at these quantiles of the objective (ordinal noise ``rating_noise`` on the normalised
    objective).  ``config``: ``[feedback.rating]`` (needed with ratings, one label more than
    quantiles) and ``[safety]`` tables as TOML text, e.g. ``[safety] avoid = ["very bad"]``
    (not ``unsafe_radius``: a simulated subject flags no trial unsafe, so it is refused).
    ``n`` and ``buffer`` are at most :data:`~gaitpref.config.schema.MAX_QUERY`, as a config's.
    """

    name: str
    n: int = 1
    buffer: int = 0
    coactive: bool = False
    strategy: Strategy = "cospar"
    coactive_weight: float = 1.0
    rating_quantiles: tuple[float, ...] = ()
    rating_noise: float = 0.0
    config: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str):  # a TypeError from 'in' (an int), or "None" below
            raise ValueError(f"setting name must be text, got {self.name!r}")
        where = f"setting {self.name!r}"
        if not isinstance(self.config, str):  # an AttributeError from the TOML reader
            raise ValueError(f"{where}: config must be TOML text, got {self.config!r}")
        for key in ("n", "buffer"):
            value = _integer(getattr(self, key), f"{where}: {key}")
            if value > MAX_QUERY:  # as a config's [cospar] n and buffer: a buffer of 10**9
                # kept every trial's actions, each trial compared with all of them
                raise ValueError(
                    f"{where}: {key} must be at most {MAX_QUERY} (as a config's [cospar] {key}), "
                    f"got {value}"
                )
            object.__setattr__(self, key, value)
        if not isinstance(self.coactive, bool | np.bool_):
            raise ValueError(f"{where}: coactive must be true or false, got {self.coactive!r}")
        if not _real(self.coactive_weight) or not 0 < self.coactive_weight < np.inf:
            weight = self.coactive_weight
            raise ValueError(
                f"{where}: coactive_weight must be a finite number > 0, got {weight!r}"
            )
        if not _real(self.rating_noise):
            raise ValueError(f"{where}: rating_noise must be a number, got {self.rating_noise!r}")
        given = self.rating_quantiles
        if isinstance(given, str | bytes) or not hasattr(given, "__iter__"):
            # a float or None: a TypeError naming no setting; "0.5": three characters
            raise ValueError(
                f"{where}: rating_quantiles must be a sequence of numbers, got {given!r}"
            )
        quantiles = tuple(given)
        if not all(_real(q) for q in quantiles):
            raise ValueError(f"{where}: rating_quantiles must be numbers, got {quantiles!r}")
        object.__setattr__(self, "rating_quantiles", tuple(float(q) for q in quantiles))
        self._check_ratings()
        if not self.name or any(c in self.name for c in ",\n\"'"):
            raise ValueError(f"setting name must be non-empty without commas/quotes: {self.name!r}")
        if self.strategy not in ("cospar", "random"):
            raise ValueError(f"setting {self.name!r}: strategy must be 'cospar' or 'random'")
        if self.strategy == "random" and self.coactive:
            raise ValueError(f"setting {self.name!r}: random selection takes no coactive feedback")
        if self.strategy == "cospar" and (
            self.n < 1 or self.buffer < 0 or (self.n == 1 and self.buffer == 0)
        ):
            why = (  # Setting(name) alone is this: its defaults are n = 1, buffer = 0
                ": one gait a query and none remembered compares nothing; give buffer=1 (the "
                "paper's human protocol) or n >= 2 (buffer defaults to 0 here, not to a "
                "config's 1)"
                if self.n == 1 and self.buffer == 0
                else ""
            )
            raise ValueError(
                f"setting {self.name!r}: needs n >= 1, b >= 0 and not n = 1 with b = 0, "
                f"got n = {self.n}, b = {self.buffer}{why}"
            )

    def _check_ratings(self) -> None:
        where = f"setting {self.name!r}"
        q = self.rating_quantiles
        if q and (any(not 0 < v < 1 for v in q) or any(b <= a for a, b in itertools.pairwise(q))):
            raise ValueError(f"{where}: rating_quantiles must increase inside (0, 1), got {q}")
        if not (np.isfinite(self.rating_noise) and self.rating_noise >= 0):
            raise ValueError(f"{where}: rating_noise must be >= 0, got {self.rating_noise!r}")
        if self.rating_noise and not q:
            raise ValueError(f"{where}: rating_noise needs rating_quantiles (the rater)")
        ordinal, safety = parse_setting_config(self.config, 0.01, where)
        if q and (ordinal is None or ordinal.size != len(q) + 1):
            has = "no [feedback.rating]" if ordinal is None else f"{ordinal.size} labels"
            raise ValueError(
                f"{where}: {len(q)} rating_quantiles need a [feedback.rating] table with "
                f"{len(q) + 1} labels in config, which has {has}"
            )
        raw = read_toml(self.config).get("safety") or {}
        starts = "start" in raw
        if "unsafe_radius" in raw:  # a setting that silently did nothing
            raise ConfigError(
                f"{where}: [safety].unsafe_radius: is the neighbourhood kept away from a trial "
                "flagged unsafe, and a simulated subject never flags a trial, so it would do "
                f"nothing here (unsafe_radius = {raw['unsafe_radius']!r}); leave it out",
                table="safety",
                key="unsafe_radius",
            )
        for key in ("risk", "lambda"):  # as a new session's config (config.check_ignored)
            if key in raw and not raw.get("avoid"):
                raise ConfigError(
                    f"{where}: [safety].{key}: is a setting of the region of avoidance, which is "
                    f'off without avoid = ["..."] (the worst [feedback.rating] labels): {key} = '
                    f"{raw[key]!r} would be ignored; give avoid, or leave {key} out",
                    table="safety",
                    key=key,
                )
        if self.strategy == "random" and (safety.avoid or starts):
            raise ValueError(f"{where}: random selection takes no [safety] settings")

    @classmethod
    def random(cls, name: str = "random") -> Setting:
        return cls(name, strategy="random")


@dataclass(frozen=True, eq=False)
class RunTask:
    """Everything one run needs (small enough to ship to a worker process)."""

    space: Space
    kernel: SquaredExponential
    noise: float
    setting: Setting
    objective: FloatArray  # (A,)
    objective_id: int
    seed: int
    trials: int
    minimize: bool
    study_seed: int
    user_noise: float = 0.0


@dataclass(frozen=True, eq=False)
class RunResult:
    """One run: the executed action and its normalised objective at every trial."""

    setting: str
    objective_id: int
    seed: int
    actions: IntArray  # (T,)
    normalized: FloatArray  # (T,)
    ratings: IntArray | None = None  # (T,) when the setting rates: 1 (worst) to K


def _integer(value: object, what: str) -> int:
    """``value`` as an ``int`` if it is an integer (NumPy's too, not a bool or a float): a
    ValueError naming ``what`` otherwise (``int()`` cut 1.5 to 1 silently)."""
    if isinstance(value, bool | np.bool_):
        raise ValueError(f"{what} must be an integer, got {value!r}")
    try:
        return operator.index(value)  # type: ignore[arg-type]
    except TypeError:
        raise ValueError(f"{what} must be an integer, got {value!r}") from None


def _real(value: object) -> bool:
    """Whether ``value`` is a real number (not a bool, a text or None)."""
    return isinstance(value, int | float | np.integer | np.floating) and not isinstance(
        value, bool | np.bool_
    )


def _name_key(name: str) -> tuple[int, ...]:
    """A setting name as four 32-bit words (stable across processes and Python versions)."""
    digest = hashlib.sha256(name.encode("utf-8")).digest()[:16]
    return tuple(int.from_bytes(digest[i : i + 4], "little") for i in range(0, 16, 4))


def run_seed_sequence(
    study_seed: int, setting: str, objective_id: int, seed: int
) -> np.random.SeedSequence:
    """The seed sequence of one run, from its coordinates in the study only."""
    return np.random.SeedSequence(study_seed, spawn_key=(*_name_key(setting), objective_id, seed))


def run_one(task: RunTask) -> RunResult:
    """Run one simulated experiment (pure: the result depends on ``task`` only)."""
    s = task.setting
    loop_ss, user_ss, rater_ss = run_seed_sequence(
        task.study_seed, s.name, task.objective_id, task.seed
    ).spawn(3)  # the first two children are those of spawn(2): runs without ratings unchanged
    user = SimulatedUser(
        task.space, task.objective, np.random.default_rng(user_ss), task.minimize, task.user_noise
    )
    ordinal, safety = parse_setting_config(s.config, task.noise, f"setting {s.name!r}", task.space)
    rater = None
    if s.rating_quantiles:
        rater = OrdinalRater(
            task.space,
            task.objective,
            s.rating_quantiles,
            np.random.default_rng(rater_ss),
            s.rating_noise,
            task.minimize,
        )
    ratings: IntArray | None = None
    if s.strategy == "random":
        actions = np.random.default_rng(loop_ss).integers(0, len(task.space), size=task.trials)
        actions = actions.astype(np.intp)
        normalized = user.normalized(actions)
        if rater is not None:
            ratings = np.array([rater.rate(int(a)) for a in actions], dtype=np.intp)
    else:
        loop = CoSpar(
            task.space,
            task.kernel,
            task.noise,
            n=s.n,
            buffer=s.buffer,
            coactive_weight=s.coactive_weight,
            seed=np.random.default_rng(loop_ss),
            ordinal=ordinal,
            safety=safety,
        )
        coactive = (
            GradientCoactive(task.space, task.objective, task.minimize) if s.coactive else None
        )
        try:
            result = run_simulation(loop, user, task.trials, coactive, rater=rater)
        except NoSafeGaitError as exc:  # a run cannot end early: its table row would be short
            raise NoSafeGaitError(
                f"setting {s.name!r}, objective {task.objective_id}, seed {task.seed}: {exc}"
            ) from None
        actions, normalized, ratings = result.actions, result.normalized_objective, result.ratings
    return RunResult(s.name, task.objective_id, task.seed, actions, normalized, ratings)


@dataclass(frozen=True, eq=False)
class Study:
    """Settings x objectives x seeds on one grid, model and trial budget.

    ``objectives`` is ``K x A`` (or shaped like the grid per row); ``objective_ids`` labels its
    rows (default ``0..K-1``) and enters each run's seed.  ``minimize``: lower objective is
    better (a cost such as COT).
    """

    name: str
    space: Space
    kernel: SquaredExponential
    noise: float
    settings: tuple[Setting, ...]
    objectives: FloatArray
    objective_ids: tuple[int, ...] = ()
    seeds: tuple[int, ...] = (0,)
    trials: int = 150
    minimize: bool = False
    seed: int = 0
    user_noise: float = 0.0

    def __post_init__(self) -> None:
        settings = tuple(self.settings)
        if not settings:
            raise ValueError(f"study {self.name!r}: needs at least one setting")
        names = [s.name for s in settings]
        if len(set(names)) != len(names):
            raise ValueError(f"study {self.name!r}: setting names repeat: {names}")
        A = len(self.space)
        obj = np.asarray(self.objectives, dtype=np.float64)
        if obj.size == 0:
            raise ValueError(f"study {self.name!r}: objectives must be K x {A}, got none")
        obj = obj.reshape(obj.shape[0], -1) if obj.ndim > 1 else obj.reshape(1, -1)
        if obj.shape[1] != A or obj.shape[0] == 0:
            raise ValueError(f"study {self.name!r}: objectives must be K x {A}, got {obj.shape}")
        if not np.all(np.isfinite(obj)):
            raise ValueError(f"study {self.name!r}: objectives must be finite")
        obj = obj.copy()
        obj.setflags(write=False)
        where = f"study {self.name!r}"
        # refused here, by key, not as every run's failure naming no field (or, for minimize,
        # taken by truth: minimize="no" minimized)
        if not is_noise(self.noise):
            noise = self.noise
            raise ValueError(
                f"{where}: noise must be a number > 0 with a finite square, got {noise!r}"
            )
        if not (is_number(self.user_noise) and 0 <= self.user_noise < np.inf):
            raise ValueError(
                f"{where}: user_noise must be a finite number >= 0, got {self.user_noise!r}"
            )
        if not isinstance(self.minimize, bool | np.bool_):
            raise ValueError(f"{where}: minimize must be true or false, got {self.minimize!r}")
        if not isinstance(self.seeds, Sequence | np.ndarray):  # an iterator: counted once
            try:
                object.__setattr__(self, "seeds", tuple(self.seeds))
            except TypeError:  # seeds=5: "'int' object is not iterable", naming no field
                raise ValueError(
                    f"{where}: seeds must be a sequence of integers, got {self.seeds!r}"
                ) from None
        runs = len(settings) * obj.shape[0] * len(self.seeds)
        if runs > MAX_RUNS:
            raise ValueError(
                f"{where}: {runs} runs (settings x objectives x seeds) is more than {MAX_RUNS}; "
                "split it into several studies"
            )
        ids = tuple(_integer(i, f"{where}: objective_ids") for i in self.objective_ids)
        ids = ids or tuple(range(obj.shape[0]))
        if len(ids) != obj.shape[0] or len(set(ids)) != len(ids) or min(ids) < 0:
            raise ValueError(f"study {self.name!r}: need {obj.shape[0]} distinct ids >= 0")
        if max(ids) > MAX_SEED:  # the run table's int64 column: an OverflowError after the runs
            raise ValueError(f"{where}: objective_ids must be at most {MAX_SEED}, got {max(ids)}")
        seeds = tuple(_integer(s, f"{where}: seeds") for s in self.seeds)
        if not seeds or len(set(seeds)) != len(seeds) or min(seeds) < 0:
            raise ValueError(f"study {self.name!r}: seeds must be distinct integers >= 0")
        if max(seeds) > MAX_SEED:  # likewise
            raise ValueError(f"{where}: seeds must be at most {MAX_SEED}, got {max(seeds)}")
        trials, seed = (
            _integer(self.trials, f"{where}: trials"),
            _integer(self.seed, f"{where}: seed"),
        )
        if trials < 1 or seed < 0:
            raise ValueError(f"study {self.name!r}: trials must be >= 1 and seed >= 0")
        if trials > MAX_TRIALS:  # every trial runs: 10**12 ran until the memory was full
            raise ValueError(f"{where}: trials must be at most {MAX_TRIALS}, got {trials}")
        if runs * trials > MAX_STUDY_TRIALS:  # the run table's rows, all held in memory
            raise ValueError(
                f"{where}: {runs} runs x {trials} trials is {runs * trials} trials, more than "
                f"{MAX_STUDY_TRIALS}; give fewer runs or trials, or split it into several studies"
            )
        if seed > MAX_SEED:
            raise ValueError(f"{where}: seed must be at most {MAX_SEED}, got {seed}")
        for s in settings:  # refused here, not by a worker after other runs (naming no setting)
            if s.strategy == "cospar" and s.n > A:
                raise ValueError(
                    f"{where}: setting {s.name!r}: n = {s.n} is more actions than the grid's {A}"
                )
            # [safety] start names gaits of this grid: checked here (a setting has no grid)
            parse_setting_config(s.config, self.noise, f"{where}: setting {s.name!r}", self.space)
        object.__setattr__(self, "settings", settings)
        object.__setattr__(self, "objectives", obj)
        object.__setattr__(self, "objective_ids", ids)
        object.__setattr__(self, "seeds", seeds)
        object.__setattr__(self, "trials", trials)
        object.__setattr__(self, "seed", seed)

    @classmethod
    def from_config(
        cls,
        config: ExperimentConfig,
        settings: Sequence[Setting],
        objectives: ArrayLike,
        **kwargs: object,
    ) -> Study:
        """A study on a config's grid and model (its ``n``/``b`` are replaced by ``settings``)."""
        return cls(
            kwargs.pop("name", config.name),  # type: ignore[arg-type]
            config.space,
            config.kernel,
            config.noise,
            tuple(settings),
            np.asarray(objectives, dtype=np.float64),
            **kwargs,  # type: ignore[arg-type]
        )

    def __len__(self) -> int:
        return len(self.settings) * len(self.objective_ids) * len(self.seeds)

    def tasks(self) -> list[RunTask]:
        """Every run, ordered by setting, then objective, then seed."""
        return [
            RunTask(
                self.space,
                self.kernel,
                self.noise,
                s,
                self.objectives[k],
                oid,
                seed,
                self.trials,
                self.minimize,
                self.seed,
                self.user_noise,
            )
            for s in self.settings
            for k, oid in enumerate(self.objective_ids)
            for seed in self.seeds
        ]
