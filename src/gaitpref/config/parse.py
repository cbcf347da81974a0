"""Experiment configs: a TOML file describing the grid, the model and the CoSpar settings.

    [space.step_length]            # one table per feature, in grid order (C order)
    min = 0.08                     # or: values = [...]
    max = 0.18
    num = 15
    unit = "m"
    coactive = [0.1, 0.2]          # small and big moves, fractions of the range
    words = ["longer", "shorter"]  # optional: how an operator says + and -

    [model]
    lengthscale = { step_length = 0.03 }   # per feature, in its own units (or one number)
    signal_variance = 0.005
    jitter = 1e-7
    noise = 0.02
    sampler = "auto"               # optional: "auto", "dense" or "scalable" (posterior samples)
    ties = "drop"                  # optional: "drop" (the paper) or "model" (ordered probit)
    # tie_band = "fit"             # with ties = "model": a number, or "fit"
    fit = "evidence"               # optional: "fixed" (the paper) or "evidence"
    refit_every = 20               # optional: answers between hyperparameter refits

    [model.prior]                  # optional: log-normal priors as [median, sd of the log]
    lengthscale = { step_length = [0.025, 0.7] }
    signal_variance = [0.005, 0.0] # sd 0 holds the parameter fixed

    [cospar]
    n = 1
    buffer = 1
    coactive_weight = 1.0
    seed = 0
    strategy = "gated-eubo"        # optional: see gaitpref.strategies.STRATEGIES

Instead of ``[space]``, a config can name a gait library built by ``gaitpref gaits build``; the
features then come from the library's axes and every action has a gait id:

    [gaits]
    library = "gaits.json"         # relative to the config file's folder

Every error names the key and what is allowed.  The optional learning keys default to
:data:`DEFAULT_TIES`, :data:`DEFAULT_FIT` and :data:`DEFAULT_STRATEGY` (``docs/learning.md``
says why); the shipped paper configs set them explicitly to the paper's choices.  Shipped configs
(the paper's settings) live in ``gaitpref/configs/`` and load by name:
``load_config("exo-1d-step-length")``.
"""

from __future__ import annotations

import hashlib
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from gaitpref.errors import ConfigError
from gaitpref.loop.cospar import CoSpar
from gaitpref.loop.learning import FIT_MODES, TIES_MODES, FitMode, Learning, TiesMode
from gaitpref.model.engines import SAMPLERS, resolve_sampler
from gaitpref.model.hyperfit import HyperPrior, LogNormal, default_prior
from gaitpref.model.kernels import SquaredExponential
from gaitpref.space import Feature, Space
from gaitpref.strategies import STRATEGIES, make_strategy

if TYPE_CHECKING:
    from gaitpref.gaits.library import (
        GaitLibrary,
    )


_TOP_KEYS = {"name", "description", "space", "gaits", "model", "cospar"}
_GAITS_KEYS = {"library"}
_FEATURE_KEYS = {"min", "max", "num", "values", "unit", "coactive", "words"}
_MODEL_KEYS = {
    "lengthscale",
    "signal_variance",
    "jitter",
    "noise",
    "ties",
    "tie_band",
    "fit",
    "refit_every",
    "prior",
    "sampler",
}
_PRIOR_KEYS = {"lengthscale", "signal_variance", "tie_band"}
_COSPAR_KEYS = {"n", "buffer", "coactive_weight", "seed", "strategy"}

#: What a config that omits the learning keys gets (the study in docs/results/learning).
DEFAULT_TIES: TiesMode = "drop"
DEFAULT_FIT: FitMode = "evidence"
DEFAULT_REFIT_EVERY = 20
DEFAULT_STRATEGY = "gated-eubo"


@dataclass(frozen=True)
class ExperimentConfig:
    """A parsed experiment config and the exact text it came from."""

    name: str
    space: Space
    kernel: SquaredExponential
    noise: float
    n: int
    buffer: int
    coactive_weight: float
    seed: int
    text: str = field(repr=False)
    description: str = ""
    strategy: str = "self-sparring"
    learning: Learning = field(default_factory=Learning)
    sampler: str = "auto"
    library: GaitLibrary | None = field(default=None, repr=False, compare=False)
    library_path: str | None = None

    @property
    def sha256(self) -> str:
        """Hash of the config text as given (sessions store it to detect changes)."""
        return hashlib.sha256(self.text.encode()).hexdigest()

    @property
    def library_sha256(self) -> str | None:
        """Hash of the gait library file, if the config names one."""
        if self.library_path is None:
            return None
        return hashlib.sha256(Path(self.library_path).read_bytes()).hexdigest()

    def gait_id(self, index: int) -> str | None:
        """The gait id of grid action ``index`` when the config names a gait library."""
        return None if self.library is None else self.library.gait_id(index)

    def make_loop(self, seed: int | np.random.Generator | None = None) -> CoSpar:
        """A fresh :class:`CoSpar` loop with these settings (``seed`` overrides the config's)."""
        return CoSpar(
            self.space,
            self.kernel,
            self.noise,
            n=self.n,
            buffer=self.buffer,
            coactive_weight=self.coactive_weight,
            seed=self.seed if seed is None else seed,
            strategy=make_strategy(self.strategy),
            learning=self.learning,
            sampler=self.sampler,
        )


def shipped_configs() -> list[str]:
    """Names of the configs shipped with gaitpref."""
    root = resources.files("gaitpref.config") / "shipped"
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


def _read(source: str | Path) -> tuple[str, str, Path | None]:
    path = Path(source)
    if path.is_file():
        return path.read_text(encoding="utf-8"), path.stem, path.resolve().parent
    name = str(source)
    if path.suffix == "" and "/" not in name and name in shipped_configs():
        text = (resources.files("gaitpref.config") / "shipped" / f"{name}.toml").read_text("utf-8")
        return text, name, None
    hint = f"; shipped configs are {', '.join(shipped_configs())}"
    raise ConfigError(f"config {name!r}: no such file{hint}")


def load_config(source: str | Path) -> ExperimentConfig:
    """Load a config file, or a shipped config by name."""
    text, stem, folder = _read(source)
    return parse_config(text, default_name=stem, base_dir=folder)


def parse_config(
    text: str, default_name: str = "experiment", base_dir: str | Path | None = None
) -> ExperimentConfig:
    """Parse config TOML text (see the module docstring for the format).

    A relative ``[gaits].library`` path is taken from ``base_dir`` (default: the working folder).
    """
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"config is not valid TOML: {exc}") from None
    _only(raw, _TOP_KEYS, "top level")
    library, library_path = _parse_gaits(raw, base_dir)
    space = library.space() if library is not None else _parse_space(raw.get("space"))
    model = _table(raw, "model")
    _only(model, _MODEL_KEYS, "[model]")
    kernel = SquaredExponential(
        _lengthscales(model, space),
        _positive(model, "signal_variance", "[model]"),
        _number(model, "jitter", "[model]", default=0.0, minimum=0.0),
    )
    noise = _positive(model, "noise", "[model]")
    learning = _learning(model, space, kernel.variance, noise)
    cospar = _table(raw, "cospar")
    _only(cospar, _COSPAR_KEYS, "[cospar]")
    n = _integer(cospar, "n", "[cospar]", default=1, minimum=1)
    buffer = _integer(cospar, "buffer", "[cospar]", default=0, minimum=0)
    return ExperimentConfig(
        name=str(raw.get("name", default_name)),
        description=str(raw.get("description", "")),
        space=space,
        kernel=kernel,
        noise=noise,
        n=n,
        buffer=buffer,
        coactive_weight=_number(cospar, "coactive_weight", "[cospar]", default=1.0, minimum=0.0)
        or _fail("[cospar].coactive_weight must be > 0"),
        seed=_integer(cospar, "seed", "[cospar]", default=0, minimum=0),
        text=text,
        strategy=_choice(cospar, "strategy", "[cospar]", STRATEGIES, DEFAULT_STRATEGY),
        learning=learning,
        sampler=_sampler(model, len(space)),
        library=library,
        library_path=library_path,
    )


# -- helpers -----------------------------------------------------------------------------------
def _fail(message: str) -> Any:
    raise ConfigError(message)


def _only(table: dict[str, Any], allowed: set[str], where: str) -> None:
    unknown = sorted(set(table) - allowed)
    if unknown:
        raise ConfigError(
            f"{where}: unknown key {unknown[0]!r}; allowed keys are {', '.join(sorted(allowed))}"
        )


def _table(raw: dict[str, Any], key: str) -> dict[str, Any]:
    value = raw.get(key)
    if not isinstance(value, dict):
        raise ConfigError(f"[{key}]: missing table (it is required)")
    return value


def _number(
    table: dict[str, Any], key: str, where: str, default: float | None = None, minimum: float = 0.0
) -> float:
    if key not in table:
        if default is None:
            raise ConfigError(f"{where}.{key}: missing (a number is required)")
        return default
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(value):
        raise ConfigError(f"{where}.{key}: must be a finite number, got {value!r}")
    if value < minimum:
        raise ConfigError(f"{where}.{key}: must be >= {minimum}, got {value!r}")
    return float(value)


def _positive(table: dict[str, Any], key: str, where: str) -> float:
    value = _number(table, key, where)
    if value <= 0:
        raise ConfigError(f"{where}.{key}: must be > 0, got {value!r}")
    return value


def _integer(table: dict[str, Any], key: str, where: str, default: int, minimum: int) -> int:
    value = table.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise ConfigError(f"{where}.{key}: must be an integer >= {minimum}, got {value!r}")
    return value


def _sampler(model: dict[str, Any], size: int) -> str:
    value = model.get("sampler", "auto")
    if value not in SAMPLERS:
        raise ConfigError(f"[model].sampler: must be one of {', '.join(SAMPLERS)}; got {value!r}")
    try:
        resolve_sampler(value, size)
    except ValueError as exc:
        raise ConfigError(f"[model].sampler: {exc}") from None
    return str(value)


def _parse_gaits(
    raw: dict[str, Any], base_dir: str | Path | None
) -> tuple[GaitLibrary | None, str | None]:
    if "gaits" not in raw:
        return None, None
    gaits = raw["gaits"]
    if not isinstance(gaits, dict):
        raise ConfigError('[gaits]: must be a table with library = "FILE"')
    _only(gaits, _GAITS_KEYS, "[gaits]")
    if "space" in raw:
        raise ConfigError("give either [space] or [gaits].library (its axes are the space)")
    name = gaits.get("library")
    if not isinstance(name, str) or not name:
        raise ConfigError("[gaits].library: must be the path of a gait library file")
    path = Path(name)
    if not path.is_absolute():
        path = Path(base_dir if base_dir is not None else ".") / path
    from gaitpref.errors import GaitLibraryError
    from gaitpref.gaits.library import GaitLibrary

    try:
        return GaitLibrary.load(path), str(path.resolve())
    except (GaitLibraryError, OSError) as exc:
        raise ConfigError(f"[gaits].library: {exc}") from None


def _parse_space(raw: object) -> Space:
    if not isinstance(raw, dict) or not raw:
        raise ConfigError("[space]: needs one table per feature, e.g. [space.step_length]")
    features = []
    for name, spec in raw.items():
        where = f"[space.{name}]"
        if not isinstance(spec, dict):
            raise ConfigError(f"{where}: must be a table with min/max/num or values")
        _only(spec, _FEATURE_KEYS, where)
        try:
            if "values" in spec:
                if {"min", "max", "num"} & set(spec):
                    raise ConfigError(f"{where}: give either values or min/max/num, not both")
                values = spec["values"]
                if not isinstance(values, list) or not values:
                    raise ConfigError(f"{where}.values: must be a non-empty list of numbers")
            else:
                lo, hi = (
                    _number(spec, "min", where, minimum=-np.inf),
                    _number(spec, "max", where, minimum=-np.inf),
                )
                num = _integer(spec, "num", where, default=0, minimum=1)
                if num > 1 and hi <= lo:
                    raise ConfigError(f"{where}: max must be greater than min")
                values = np.linspace(lo, hi, num).tolist()
            features.append(
                Feature(
                    name,
                    values,
                    unit=spec.get("unit", ""),
                    coactive=spec.get("coactive", (0.1, 0.2)),
                    words=spec.get("words", ("more", "less")),
                )
            )
        except (ValueError, TypeError) as exc:
            if isinstance(exc, ConfigError):
                raise
            raise ConfigError(f"{where}: {exc}") from None
    return Space(features)


def _lengthscales(model: dict[str, Any], space: Space) -> tuple[float, ...]:
    value = model.get("lengthscale")
    if value is None:
        raise ConfigError("[model].lengthscale: missing (a number or {feature = number})")
    if isinstance(value, dict):
        _only(value, set(space.names), "[model].lengthscale")
        missing = [n for n in space.names if n not in value]
        if missing:
            raise ConfigError(f"[model].lengthscale: missing a value for {', '.join(missing)}")
        return tuple(_positive(value, n, "[model].lengthscale") for n in space.names)
    return (_positive(model, "lengthscale", "[model]"),) * space.ndim


def _choice(
    table: dict[str, Any], key: str, where: str, allowed: tuple[str, ...], default: str
) -> str:
    value = table.get(key, default)
    if value not in allowed:
        raise ConfigError(f"{where}.{key}: must be one of {', '.join(allowed)}; got {value!r}")
    return str(value)


def _log_normal(value: object, where: str) -> LogNormal:
    if (
        not isinstance(value, list)
        or len(value) != 2
        or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
    ):
        raise ConfigError(f"{where}: must be [median, sd] (two numbers), got {value!r}")
    try:
        return LogNormal(float(value[0]), float(value[1]))
    except ValueError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _learning(model: dict[str, Any], space: Space, variance: float, noise: float) -> Learning:
    ties = cast(TiesMode, _choice(model, "ties", "[model]", TIES_MODES, DEFAULT_TIES))
    fit = cast(FitMode, _choice(model, "fit", "[model]", FIT_MODES, DEFAULT_FIT))
    refit_every = _integer(model, "refit_every", "[model]", DEFAULT_REFIT_EVERY, minimum=1)
    raw_band = model.get("tie_band", "fit" if fit == "evidence" else None)
    band: float | None = None
    if ties == "drop":
        if "tie_band" in model:
            raise ConfigError('[model].tie_band: only used with ties = "model"')
    elif raw_band == "fit":
        if fit != "evidence":
            raise ConfigError('[model].tie_band = "fit" needs fit = "evidence"')
    elif raw_band is None:
        raise ConfigError('[model].tie_band: ties = "model" with fit = "fixed" needs a number')
    else:
        band = _positive(model, "tie_band", "[model]")
    prior = default_prior(space, variance, noise, fit_band=ties == "model" and band is None)
    raw_prior = model.get("prior", {})
    if not isinstance(raw_prior, dict):
        raise ConfigError("[model.prior]: must be a table")
    _only(raw_prior, _PRIOR_KEYS, "[model.prior]")
    scales = list(prior.lengthscale)
    if "lengthscale" in raw_prior:
        table = raw_prior["lengthscale"]
        if not isinstance(table, dict):
            raise ConfigError("[model.prior].lengthscale: must be { feature = [median, sd] }")
        _only(table, set(space.names), "[model.prior].lengthscale")
        for name, value in table.items():
            scales[space.feature_index(name)] = _log_normal(
                value, f"[model.prior].lengthscale.{name}"
            )
    var_prior = prior.variance
    if "signal_variance" in raw_prior:
        var_prior = _log_normal(raw_prior["signal_variance"], "[model.prior].signal_variance")
    band_prior = prior.band
    if "tie_band" in raw_prior:
        if band_prior is None:
            raise ConfigError('[model.prior].tie_band: only used with tie_band = "fit"')
        band_prior = _log_normal(raw_prior["tie_band"], "[model.prior].tie_band")
    try:
        return Learning(
            ties, band, fit, refit_every, HyperPrior(tuple(scales), var_prior, band_prior)
        )
    except ValueError as exc:
        raise ConfigError(f"[model]: {exc}") from None
