"""Every key of an experiment config, declared once: its type, its default and what is allowed.

A config is TOML with the tables below (``parse.py`` documents the format).  Each table is a
mapping ``key -> Key(spec, default)``; a spec (``specs.py``) checks one value and says in words
what it allows, so every error reads ``[table].key: must be <allowed>, got <value>``.
:data:`DEFAULTS` is the one table of defaults (the docs show it), :data:`LIMITS` the sizes a
config may ask for: they are checked from the config's numbers before anything is built, so
no config can make the process allocate or loop without bound (issue 15, items 1 and 2).  The
bound on gait solver iterations an ask (``MAX_ASK_ITERATIONS``) is checked for a new session or
run only (``config/new.py``), so that a session stored with a larger product reopens.

The strategies' settings (``[cospar.strategy_settings]``) take their defaults from the strategy
classes themselves (``gaitpref.strategies``); only their bounds are declared here.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any, Final

from gaitpref.config.specs import (
    MAX_MAGNITUDE,
    MAX_NAME,
    MIN_SCALE,
    SCALE,
    Choice,
    Coactive,
    Gaits,
    Integer,
    Labels,
    LogNormalPair,
    Number,
    Numbers,
    ScaleOrFit,
    ScaleOrTable,
    Spec,
    Table,
    Text,
    Words,
    clipped,
    fail,
    shown,
)
from gaitpref.errors import ConfigError
from gaitpref.loop.cospar import GRID_LIMIT_VALUES, QUERY_LIMIT
from gaitpref.loop.learning import (
    FIT_MODES,
    HYPER_MODES,
    HYPOTHESES,
    HYPOTHESIS_FACTORS,
    MAX_HYPOTHESES,
    SHARE_MODES,
    TIES_MODES,
    WARM_FIRST,
)
from gaitpref.loop.lines import (
    BOUNDARIES,
    COACTIVE_SOURCES,
    DIRECTIONS,
    MAX_LINES,
    MAX_STAR_POINTS,
)
from gaitpref.loop.stopping import MAX_SAMPLES as MAX_CONFIDENCE_SAMPLES
from gaitpref.model.engines import SAMPLERS
from gaitpref.strategies import STRATEGIES, STRATEGY_CLASSES, STRATEGY_SETTINGS
from gaitpref.strategies.base import MAX_CANDIDATES, MAX_GATES, MAX_SAMPLES

#: A grid (the product of every feature's ``num`` or ``values``) has at most this many actions.
MAX_ACTIONS: Final = 1_000_000
#: A feature on the full-grid path has at most this many values (its kernel factor is n x n).
MAX_FEATURE_VALUES: Final = GRID_LIMIT_VALUES
#: ``[cospar] subspace``: the full grid, the line path, or the line path when no grid fits.
SUBSPACES: Final = ("auto", "grid", "line")
#: At most this many features (``[space.<feature>]`` tables).
MAX_FEATURES: Final = 32
#: Actions per query (``n``) and remembered trials (``buffer``): each at most this many (the
#: loop's own bound, which ``CoSpar`` built by hand and simulated settings keep too).
MAX_QUERY: Final = QUERY_LIMIT
#: ``signal_variance * max(1, coactive_weight)**2 / noise**2`` at most this: beyond it the
#: likelihood is so nearly deterministic that the Laplace fit's Hessian cannot be factorised.
MAX_SIGNAL_TO_NOISE: Final = 1e6
#: Length of a description.
MAX_TEXT: Final = 10_000
#: ``[gaits] max_iterations``: a gait made on demand may be given at most this many solver
#: iterations (each costs about 10 ms with ``compass-hzd``: past this, a request is not bounded).
MAX_GAIT_ITERATIONS: Final = 10_000
#: ``[gaits] max_infeasible``: one ask may be allowed at most this many proposals whose gait
#: cannot be made (each costs up to ``max_iterations`` solver iterations).
MAX_INFEASIBLE: Final = 1000
#: ``[gaits] max_infeasible``'s default.
DEFAULT_MAX_INFEASIBLE: Final = 20
#: ``[gaits] max_iterations x max_infeasible``: the solver iterations one ask may spend on gaits
#: that cannot be made.  Each key alone is bounded above, their product was not: 10,000 x 1,000
#: iterations at about 10 ms each (``benchmarks/results/gaits_on_demand.md``: 60 iterations took
#: 0.59 s of CPU) is about 28 hours for one ask.  This bound is the largest ``max_iterations``
#: at the default ``max_infeasible``, so every config that raises one key alone still loads:
#: about 2,000 s (33 min) of CPU at most, and ``max_infeasible = 1000`` takes
#: ``max_iterations`` up to 200.
MAX_ASK_ITERATIONS: Final = MAX_GAIT_ITERATIONS * DEFAULT_MAX_INFEASIBLE

LIMITS: Final[dict[str, float]] = {
    "actions": MAX_ACTIONS,
    "values a feature (full grid)": MAX_FEATURE_VALUES,
    "features": MAX_FEATURES,
    "n, buffer": MAX_QUERY,
    "magnitude": MAX_MAGNITUDE,
    "smallest scale": MIN_SCALE,
    "signal to noise": MAX_SIGNAL_TO_NOISE,
    "line points a query": MAX_STAR_POINTS,
    "gait solver iterations an ask (max_iterations x max_infeasible)": MAX_ASK_ITERATIONS,
}


class _Required:
    def __repr__(self) -> str:
        return "required"


REQUIRED: Final[Any] = _Required()


@dataclass(frozen=True)
class Key:
    """One key of a table: how it is checked and its default (:data:`REQUIRED` if none)."""

    spec: Spec
    default: Any = REQUIRED


TOP: Final[dict[str, Key]] = {
    "name": Key(Text(MAX_NAME), None),  # None: the file's name
    "description": Key(Text(MAX_TEXT), ""),
    "space": Key(Table("one table per feature"), None),
    "gaits": Key(Table('library = "FILE" or generator = "NAME"'), None),
    "model": Key(Table("the GP model")),
    "cospar": Key(Table("the loop's settings"), {}),
    "feedback": Key(Table("[feedback.rating]: ordinal ratings"), {}),
    "safety": Key(Table("the region of avoidance and unsafe flags"), {}),
    "stop": Key(Table("the stopping rule: confidence, max_trials, tolerance, samples"), {}),
}
FEEDBACK: Final[dict[str, Key]] = {
    "rating": Key(Table("labels, thresholds, noise"), None),
}
RATING: Final[dict[str, Key]] = {
    "labels": Key(Labels()),
    "thresholds": Key(Numbers(Number(), 1, 9), None),  # None: the prior predictive's quantiles
    "noise": Key(SCALE, None),  # None: [model].noise
}
SAFETY: Final[dict[str, Key]] = {
    "avoid": Key(Labels(1, 9), ()),  # the worst categories, e.g. ["very bad"]
    "lambda": Key(Number(0.0, 100.0), 1.0),  # given: ROIAL's upper-bound rule, this confidence
    # "auto": avoid / K + 0.1 (safety.py)
    "risk": Key(Number(0.0, 1.0, open_lo=True, open_hi=True), "auto"),
    "cautious": Key(Number(0.0, 1.0), 0.6),  # the risk rule's cautious level (safety.py); 0: off
    "explore": Key(Number(0.0, 100.0), 1.0),  # with cautious: mu + explore sd beats known-safe
    "unsafe_radius": Key(Number(0.0, 1.0), 0.0),  # around a flagged gait, fraction of ranges
    "start": Key(Gaits(MAX_QUERY), ()),  # gaits the operator declares safe: executed first
    "reach": Key(Number(0.0, 100.0, open_lo=True), None),  # with cautious: explore only within
    # this many lengthscales of a known-safe gait (None: anywhere)
    # with cautious: explore only where P(avoided) <= frontier x an unrated gait's (None: off)
    "frontier": Key(Number(0.0, 1.0, open_lo=True), None),
}
STOP: Final[dict[str, Key]] = {
    "confidence": Key(Number(0.0, 1.0, open_lo=True), None),  # None: no confidence rule
    "max_trials": Key(Integer(1, 1_000_000), None),  # None: no limit
    "tolerance": Key(Number(0.0, 0.5), 0.05),  # "within 5% of the best" (of the utility's range)
    # posterior samples behind the probability
    "samples": Key(Integer(100, MAX_CONFIDENCE_SAMPLES), 2000),
}
FEATURE: Final[dict[str, Key]] = {
    "min": Key(Number(), None),
    "max": Key(Number(), None),
    "num": Key(Integer(1, 2**62), None),  # None, or past MAX_ACTIONS: continuous
    "values": Key(Numbers(Number(), 1, MAX_ACTIONS), None),
    "unit": Key(Text(MAX_NAME), ""),
    "coactive": Key(Coactive(), (0.1, 0.2)),
    "words": Key(Words(), ("more", "less")),
}
#: ``[gaits] recommend``: with gaits made on demand, the recommendation is the best gait made
#: (and feasible), or the best point of the model, made or not (before defaults 0.13)
RECOMMEND: Final = ("made", "any")
GAITS: Final[dict[str, Key]] = {
    "library": Key(Text(4096), None),  # a gait library file, or:
    "generator": Key(Text(MAX_NAME), None),  # a gait generator (gaits made on demand)
    "speed": Key(Number(0.0, 100.0, open_lo=True), None),  # the generator's fixed speed, m/s
    "avoid_radius": Key(Number(0.0, 1.0), 0.05),  # around an infeasible proposal, of ranges
    # the solver iterations one gait may take, all starts together (None before defaults 0.5)
    "max_iterations": Key(Integer(1, MAX_GAIT_ITERATIONS), 60),
    # proposals whose gait cannot be made that one ask may make before it stops, proposing
    # nothing (only live asks: replay follows the log, so every earlier session replays as it ran)
    # max_iterations x max_infeasible at most MAX_ASK_ITERATIONS (config/generator.py)
    "max_infeasible": Key(Integer(1, MAX_INFEASIBLE), DEFAULT_MAX_INFEASIBLE),
    # the gaits a session may recommend: "made" (the best of the gaits it made, defaults 0.13
    # on) or "any" point of the model (a coactive suggestion's too, whose gait may not exist)
    "recommend": Key(Choice(RECOMMEND), "made"),
}
MODEL: Final[dict[str, Key]] = {
    "lengthscale": Key(ScaleOrTable()),
    "signal_variance": Key(SCALE),
    "noise": Key(SCALE),
    "jitter": Key(Number(0.0, MAX_MAGNITUDE), None),  # None: RELATIVE_JITTER x signal_variance
    "sampler": Key(Choice(SAMPLERS), "auto"),
    "ties": Key(Choice(TIES_MODES), "drop"),
    "tie_band": Key(ScaleOrFit(), None),  # None: "fit" with fit = "evidence", else required
    "fit": Key(Choice(FIT_MODES), "evidence"),
    "refit_every": Key(Integer(1, 1_000_000), 20),
    "hyper": Key(Choice(HYPER_MODES), "map"),  # "average": over lengthscale hypotheses
    "hypotheses": Key(
        Numbers(Number(*HYPOTHESIS_FACTORS, open_lo=True), 1, MAX_HYPOTHESES), HYPOTHESES
    ),
    "share": Key(Choice(SHARE_MODES), "average"),  # a warm start's share: a mixture, or "map"
    # a warm start's first trial: the earlier subjects' recommendation, or the strategy's pick
    "warm_first": Key(Choice(WARM_FIRST), "recommended"),
    "prior": Key(Table("log-normal priors [median, sd]"), {}),
}
PRIOR: Final[dict[str, Key]] = {
    "lengthscale": Key(Table("{feature = [median, sd]}"), None),
    "signal_variance": Key(LogNormalPair(), None),
    "tie_band": Key(LogNormalPair(), None),
}
COSPAR: Final[dict[str, Key]] = {
    "n": Key(Integer(1, MAX_QUERY), 1),
    "buffer": Key(Integer(0, MAX_QUERY), 1),
    "coactive_weight": Key(Number(MIN_SCALE, 1e6), 1.0),
    "seed": Key(Integer(0, 2**63 - 1), 0),
    "strategy": Key(Choice(STRATEGIES), "gated-eubo"),
    "strategy_settings": Key(Table("the strategy's settings"), {}),
    # issue 13: the full grid, or LineCoSpar's lines ("auto": lines when no grid fits)
    "subspace": Key(Choice(SUBSPACES), "auto"),
    "line_points": Key(Integer(2, 4096), 50),
    "line_direction": Key(Choice(DIRECTIONS), "random"),
    # lines per query, all through the best point (a star; 1: LineCoSpar's one line)
    "line_count": Key(Integer(1, MAX_LINES), 4),
    # points around the best point besides the lines (loop/lines.py; 0: none)
    "line_cloud": Key(Integer(0, MAX_STAR_POINTS), 0),
    # a line through a point on the box's boundary that would leave it at once both ways:
    # "fold" its direction into the box, or "clip" it to the point alone (before 0.11)
    "line_boundary": Key(Choice(BOUNDARIES), "fold"),
    # the coactive direction (line_direction = "coactive") from the last answer's suggestions
    # the model "kept" (an excluded trial's left out), or every one "recorded" (before 0.12)
    "line_coactive": Key(Choice(COACTIVE_SOURCES), "kept"),
}

#: Bounds of every strategy setting; the defaults are the strategy classes' own.
_SETTING_SPECS: Final[dict[str, Spec]] = {
    "gates": Integer(1, MAX_GATES),
    "trials": Integer(0, 1_000_000),
    "beta": Number(0.0, 100.0),
    "candidates": Integer(2, MAX_CANDIDATES),
    "samples": Integer(1, MAX_SAMPLES),
    "early_scale": Number(0.01, 100.0),
    "early_trials": Integer(0, 1_000_000),
    "sparring_from": Integer(0, 1_000_000),
    "sparring_until": Integer(0, 1_000_000),
}


def _strategy_table(name: str) -> dict[str, Key]:
    by_field = {f.name: f.default for f in fields(STRATEGY_CLASSES[name])}
    return {s: Key(_SETTING_SPECS[s], by_field[s]) for s in STRATEGY_SETTINGS[name]}


STRATEGY_TABLES: Final[dict[str, dict[str, Key]]] = {s: _strategy_table(s) for s in STRATEGIES}

TABLES: Final[dict[str, dict[str, Key]]] = {
    "": TOP,
    "space.<feature>": FEATURE,
    "gaits": GAITS,
    "model": MODEL,
    "model.prior": PRIOR,
    "cospar": COSPAR,
    "feedback": FEEDBACK,
    "feedback.rating": RATING,
    "safety": SAFETY,
    "stop": STOP,
    **{f"cospar.strategy_settings ({s})": t for s, t in STRATEGY_TABLES.items()},
}

#: The version of the defaults below.  A session records it when its config relies on a default
#: that changed since an earlier version, and replays with the defaults it was recorded with.
DEFAULTS_VERSION: Final = "0.13"
#: What an earlier version's defaults differ in (0.1: a bare config got ``buffer = 0``; 0.1 and
#: 0.2: a region of avoidance without ``lambda`` or ``risk`` got ROIAL's bound, ``risk = None``;
#: 0.1 to 0.3: the ``risk`` rule had no cautious level, ``cautious = 0``; 0.1 to 0.4: a gait
#: made on demand had no iteration budget, ``[gaits] max_iterations = None``; 0.1 to 0.5: a warm
#: start re-learned the new subject's share as one MAP value, ``[model] share = "map"``; 0.1 to
#: 0.6: a config without ``[model] jitter`` had none, ``jitter = 0``; 0.1 to 0.7: a warm start's
#: first trial was the strategy's, ``[model] warm_first = "strategy"``; 0.1 to 0.8: the line path
#: drew one line per query, ``[cospar] line_count = 1``; 0.1 to 0.10: a line through a point on
#: the box's boundary that left it at once both ways held that point alone,
#: ``[cospar] line_boundary = "clip"``; 0.1 to 0.11: the coactive line direction followed the
#: last answer's suggestions even when its trial was excluded since,
#: ``[cospar] line_coactive = "recorded"``; 0.1 to 0.12: a session with gaits made on demand
#: recommended the best point of the model, made or not, ``[gaits] recommend = "any"``).
#: "0.9" is not a version: a commit named it for a default that was withdrawn before release,
#: and it stays unknown, so that a database written in between fails to open instead of
#: replaying with other defaults.
_ANY_POINT: Final[dict[str, Any]] = {"recommend": "any"}
_UNBOUNDED_GAITS: Final[dict[str, Any]] = {"max_iterations": None, **_ANY_POINT}
_MODEL_BEFORE_0_6: Final[dict[str, Any]] = {
    "share": "map",
    "jitter": 0.0,
    "warm_first": "strategy",
}
_RECORDED: Final[dict[str, Any]] = {"line_coactive": "recorded"}
_CLIPPED: Final[dict[str, Any]] = {"line_boundary": "clip", **_RECORDED}
_ONE_LINE: Final[dict[str, Any]] = {"line_count": 1, **_CLIPPED}
EARLIER_DEFAULTS: Final[dict[str, dict[str, dict[str, Any]]]] = {
    "0.1": {
        "cospar": {"buffer": 0, **_ONE_LINE},
        "safety": {"risk": None, "cautious": 0.0},
        "gaits": _UNBOUNDED_GAITS,
        "model": _MODEL_BEFORE_0_6,
    },
    "0.2": {
        "cospar": _ONE_LINE,
        "safety": {"risk": None, "cautious": 0.0},
        "gaits": _UNBOUNDED_GAITS,
        "model": _MODEL_BEFORE_0_6,
    },
    "0.3": {
        "cospar": _ONE_LINE,
        "safety": {"cautious": 0.0},
        "gaits": _UNBOUNDED_GAITS,
        "model": _MODEL_BEFORE_0_6,
    },
    "0.4": {"cospar": _ONE_LINE, "gaits": _UNBOUNDED_GAITS, "model": _MODEL_BEFORE_0_6},
    "0.5": {"cospar": _ONE_LINE, "gaits": _ANY_POINT, "model": _MODEL_BEFORE_0_6},
    "0.6": {
        "cospar": _ONE_LINE,
        "gaits": _ANY_POINT,
        "model": {"jitter": 0.0, "warm_first": "strategy"},
    },
    "0.7": {"cospar": _ONE_LINE, "gaits": _ANY_POINT, "model": {"warm_first": "strategy"}},
    "0.8": {"cospar": _ONE_LINE, "gaits": _ANY_POINT},
    "0.10": {"cospar": _CLIPPED, "gaits": _ANY_POINT},
    "0.11": {"cospar": _RECORDED, "gaits": _ANY_POINT},
    "0.12": {"gaits": _ANY_POINT},
}

#: The one table of defaults: table -> key -> default (``None``: see the key's documentation).
DEFAULTS: Final[dict[str, dict[str, Any]]] = {
    table: {k: key.default for k, key in keys.items() if key.default is not REQUIRED}
    for table, keys in TABLES.items()
}


def check_table(
    raw: object,
    table: str,
    keys: dict[str, Key],
    overrides: dict[str, Any] | None = None,
    for_what: str = "",
) -> tuple[dict[str, Any], frozenset[str]]:
    """Every declared key of ``raw`` checked (defaults filled in) and the keys that defaulted.

    Unknown keys, a missing required key and a bad value raise :class:`ConfigError`.
    """
    if not isinstance(raw, dict):
        fail(table, None, f"must be a table, got {shown(raw)}")
    unknown = sorted(set(raw) - set(keys))
    if unknown:
        allowed = ", ".join(clipped(k) for k in keys) or "none"
        fail(table, None, f"unknown key {shown(unknown[0])}{for_what} (allowed: {allowed})")
    out: dict[str, Any] = {}
    defaulted = set()
    for name, key in keys.items():
        if name in raw:
            out[name] = key.spec.check(raw[name], table, name)
        elif key.default is REQUIRED:
            fail(table, name, f"missing (required: {key.spec.allowed})")
        else:
            defaults = overrides or {}
            out[name] = defaults.get(name, key.default)
            defaulted.add(name)
    return out, frozenset(defaulted)


def defaults_for(version: str, table: str) -> dict[str, Any]:
    """The defaults of ``table`` that differ in defaults ``version`` (empty for the current)."""
    if version == DEFAULTS_VERSION:
        return {}
    if version not in EARLIER_DEFAULTS:
        known = ", ".join([*EARLIER_DEFAULTS, DEFAULTS_VERSION])
        raise ConfigError(f"unknown config defaults version {version!r} (known: {known})")
    return EARLIER_DEFAULTS[version].get(table, {})
