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
    hyper = "map"                  # optional: "average" weighs lengthscale hypotheses
    # hypotheses = [0.5, 0.71, 1, 1.41, 2]  # with hyper = "average": their factors of the
                                   # fitted lengthscales
    share = "average"              # optional: a warm start's share, a mixture, or "map"

    [model.prior]                  # optional: log-normal priors as [median, sd of the log]
    lengthscale = { step_length = [0.025, 0.7] }
    signal_variance = [0.005, 0.0] # sd 0 holds the parameter fixed

    [cospar]                       # optional, and so is every key in it
    n = 1                          # actions per query (1..64, at most the grid's size)
    buffer = 1                     # previous trials compared with (0..64; default 1, the paper)
    coactive_weight = 1.0
    seed = 0
    strategy = "gated-eubo"        # optional: see gaitpref.strategies.STRATEGIES

    [cospar.strategy_settings]     # optional: the chosen strategy's settings
    gates = 1                      # gated-eubo (default 1), plausible-eubo (default 3): draws read
                                   # by the gate (1..1000)
    # samples = 32                 # plausible-eubo: joint draws whose argmaxes may run (1..4096)
    # trials = 20                  # eubo-then-sparring: trials of EUBO before self-sparring
    # beta = 1.0                   # confident-eubo: width of the confidence bounds (0..100)
    # candidates = 64              # eubo, confident-eubo: top actions for the first pair

Ordinal ratings (``[feedback.rating]``) and the region of avoidance (``[safety]``) are in
``feedback.py``; the stopping rule (``[stop]``) in ``stop.py``.

Instead of ``[space]``, a config can name a gait library built by ``gaitpref gaits build``; the
features then come from the library's axes and every action has a gait id:

    [gaits]
    library = "gaits.json"         # relative to the config file's folder ("../x.json" too)

Or a config keeps its ``[space]`` and names a gait generator: each proposed point gets its gait
made when first proposed (``generator.py``; ``docs/gaits.md``, "Gaits on demand"):

    [gaits]
    generator = "compass-hzd"      # the HZD optimisation of gaitpref.gaits
    speed = 0.2                    # its fixed settings (m/s; or a step_duration feature)
    avoid_radius = 0.05            # optional: taken out around a gait that cannot be made
    max_iterations = 60            # optional: solver iterations one gait may take (defaults 0.5)
    max_infeasible = 20            # optional: proposals without a gait one ask may make (1..1000;
                                   # max_iterations x max_infeasible at most 200,000)
    recommend = "made"             # optional: recommend the best gait made (defaults 0.13), or
                                   # "any" point of the model, made or not

Every key, its type, default and allowed values are declared once in ``schema.py``
(:data:`~gaitpref.config.schema.DEFAULTS` is the table of defaults); every error is a
:class:`ConfigError` that reads ``[table].key: what is wrong (allowed: ...)`` and carries
``table`` and ``key``.  Sizes are checked from the config's numbers before anything is built
(``grid.py``), ``n`` and ``buffer`` against the grid, and the scales against each other
(``model.py``).  The optional learning keys default to :data:`DEFAULT_TIES`,
:data:`DEFAULT_FIT` and :data:`DEFAULT_STRATEGY` (``docs/learning.md`` says why); the shipped
paper configs set them explicitly to the paper's choices.  Shipped configs (the paper's settings)
live in ``gaitpref/config/shipped/`` and load by name: ``load_config("exo-1d-step-length")``.

A bare config (no ``[cospar]``) gets ``buffer = 1``, so that every trial after the first is
compared with the one before and the loop learns without coactive feedback; 0.1 gave
``buffer = 0``.  Sessions recorded with a config that relied on that default replay with it
(``parse_config(..., defaults="0.1")``).
"""

from __future__ import annotations

import tomllib
from importlib import resources
from pathlib import Path
from typing import Any, Final

from gaitpref.checks import char_name, hidden_in
from gaitpref.config.experiment import ExperimentConfig
from gaitpref.config.feedback import parse_rating, parse_safety
from gaitpref.config.generator import parse_generator
from gaitpref.config.grid import grid_too_large, parse_gaits, parse_space
from gaitpref.config.model import (
    check_model,
    check_sampler,
    check_scales,
    make_kernel,
    make_learning,
)
from gaitpref.config.schema import (
    COSPAR,
    DEFAULTS,
    DEFAULTS_VERSION,
    GAITS,
    MAX_ACTIONS,
    MAX_SIGNAL_TO_NOISE,
    STRATEGY_TABLES,
    TOP,
    check_table,
    defaults_for,
)
from gaitpref.config.specs import MAX_NAME, fail, shown
from gaitpref.config.stop import parse_stop
from gaitpref.errors import ConfigError
from gaitpref.loop.learning import FitMode, TiesMode
from gaitpref.loop.lines import MAX_STAR_POINTS, LineSettings
from gaitpref.space import Space
from gaitpref.strategies import make_strategy

#: What a config that omits the learning keys gets (the study in docs/results/learning).
DEFAULT_TIES: TiesMode = DEFAULTS["model"]["ties"]
DEFAULT_FIT: FitMode = DEFAULTS["model"]["fit"]
DEFAULT_REFIT_EVERY: int = DEFAULTS["model"]["refit_every"]
DEFAULT_STRATEGY: str = DEFAULTS["cospar"]["strategy"]
DEFAULT_BUFFER: int = DEFAULTS["cospar"]["buffer"]
#: ``[cospar]`` keys only the line path reads: a grid config does not rely on their defaults
LINE_KEYS: Final = frozenset(
    {"line_points", "line_direction", "line_count", "line_cloud", "line_boundary", "line_coactive"}
)


def shipped_configs() -> list[str]:
    """Names of the configs shipped with gaitpref."""
    root = resources.files("gaitpref.config") / "shipped"
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


#: the most bytes of a config file read (a config of 32 features with a long ``values`` list
#: each is well under it; the whole file was read, and 32 lists of 10**6 values parsed to
#: gigabytes).  The console takes 200,000 characters of config text.
MAX_CONFIG_BYTES = 16 * 2**20


def _read(source: str | Path) -> tuple[str, str, Path | None]:
    path = Path(source)
    if path.is_file():
        with path.open("rb") as fh:
            data = fh.read(MAX_CONFIG_BYTES + 1)
        if len(data) > MAX_CONFIG_BYTES:
            raise ConfigError(
                f"config {str(path)!r} is larger than the {MAX_CONFIG_BYTES:,} bytes a config "
                "file may hold; it was not read"
            )
        try:
            text = data.decode("utf-8").replace("\r\n", "\n").replace("\r", "\n")  # as read_text
            return text, path.stem, path.resolve().parent
        except UnicodeDecodeError as exc:
            raise ConfigError(
                f"config {str(path)!r} is not UTF-8 text (byte {exc.start}: {exc.reason})"
            ) from None
    name = str(source)
    if path.is_dir():  # was reported as "no such file"
        raise ConfigError(f"config {name!r} is a folder; give a TOML file or a shipped config name")
    if path.suffix == "" and "/" not in name and name in shipped_configs():
        text = (resources.files("gaitpref.config") / "shipped" / f"{name}.toml").read_text("utf-8")
        return text, name, None
    hint = f"; shipped configs are {', '.join(shipped_configs())}"
    raise ConfigError(f"config {name!r}: no such file{hint}")


def read_toml(text: str) -> dict[str, Any]:
    """``text`` as TOML, or a :class:`ConfigError`: besides a syntax error, a number past
    Python's integer digits limit (a ValueError from tomllib) and arrays or tables nested past
    the interpreter's recursion limit (a RecursionError, not a crash of the server).  A text
    that starts with a byte order mark (Windows editors' "UTF-8 with BOM") is named so: TOML
    refused it as "Invalid statement (at line 1, column 1)", naming an invisible character."""
    if text.startswith("\ufeff"):
        raise ConfigError(
            "config is not valid TOML: it starts with a byte order mark (U+FEFF, an editor's "
            '"UTF-8 with BOM"), which TOML does not allow; save it as UTF-8 without one'
        )
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"config is not valid TOML: {exc}") from None
    except RecursionError:
        raise ConfigError("config is not valid TOML: arrays or tables nested too deeply") from None
    except ValueError as exc:  # an integer of more than 4300 digits
        why = str(exc).split(";")[0]  # not the advice to raise the interpreter's limit
        raise ConfigError(f"config is not valid TOML: {why}") from None


def load_config(source: str | Path, *, max_actions: int = MAX_ACTIONS) -> ExperimentConfig:
    """Load a config file, or a shipped config by name."""
    text, stem, folder = _read(source)
    if folder is not None:  # a file: a syntax error named neither it nor a key
        try:
            read_toml(text)
        except ConfigError as exc:
            raise ConfigError(f"config {str(source)!r}{str(exc).removeprefix('config')}") from None
        try:  # which file, where several are in play (a sweep's, a session's)
            return parse_config(text, default_name=stem, base_dir=folder, max_actions=max_actions)
        except ConfigError as exc:
            raise ConfigError(
                f"config {str(source)!r}: {exc}", table=exc.table, key=exc.key
            ) from None
    return parse_config(text, default_name=stem, base_dir=folder, max_actions=max_actions)


def check_name(config: ExperimentConfig) -> None:
    """Refuse a blank name (empty, or spaces only) for a *new* session's config: the name is how
    session lists, the console and exports tell configs apart; and a name holding a control,
    format or line-break character (:data:`~gaitpref.checks.NAME_HIDDEN`: a newline, ESC, NUL,
    a bidirectional override, a line separator, ...), which would reach terminals, the
    console's pages and exports as it is.  A :class:`ConfigError` naming the key.  Not checked by
    :func:`parse_config`: sessions stored with such a name (earlier releases took it) parse,
    reopen and replay as they were."""
    if not config.name.strip():
        fail(
            "",
            "name",
            f"must name the config (session lists and exports show it), got {config.name!r}; "
            "give a name, or leave the key out to use the file's name",
        )
    hidden = hidden_in(config.name, name=True)
    if hidden:
        at, char = hidden[0]
        named = char_name(char)
        fail(
            "",
            "name",
            f"must not hold control, format or line-break characters (newlines, tabs, ESC, NUL, "
            f"bidirectional overrides, ...); {shown(config.name)} holds {len(hidden)}, the first "
            f"{named} at character {at + 1}: terminals, the console and exports would show it as "
            "it is",
        )


def check_description(config: ExperimentConfig) -> None:
    """Refuse a description holding a character that would garble a terminal or the text shown
    around it, for a *new* session's config: a control character other than a tab or a newline
    (ESC, NUL, a carriage return, DEL, C1 controls), a surrogate, a line or paragraph
    separator, or a bidirectional formatting character (U+202E and the like).  Newlines and
    tabs stay (a description may run over lines), and so do other format characters (zero
    width joiners, which Persian and emoji sequences need).  A :class:`ConfigError` naming
    the key.  Like :func:`check_name`, not checked by :func:`parse_config`: sessions stored
    with such a description parse, reopen and replay as they were."""
    text = config.description
    hidden = hidden_in(text)
    if hidden:
        at, char = hidden[0]
        named = char_name(char)
        fail(
            "",
            "description",
            f"must not hold control characters other than newlines and tabs (ESC, NUL, a "
            f"carriage return, ...), line separators or bidirectional overrides; "
            f"{shown(text)} holds {len(hidden)}, the first {named} at character {at + 1}: "
            "terminals, the console and exports would show it as it is",
        )


def check_labels(config: ExperimentConfig) -> None:
    """Refuse, for a *new* session's config, a label shown to the operator with each trial that
    holds a control, format or line-break character (as :func:`check_name`):
    a feature's ``unit`` and ``words`` (``[space.F]``) and the rating ``labels``
    (``[feedback.rating]``); and a feature's name (``[space.F]``, shown with each trial too)
    longer than a unit or a word may be (:data:`~gaitpref.config.specs.MAX_NAME` characters);
    ``words`` whose two words are the same (ignoring case and spaces at the ends), rating
    ``labels`` two of which are, and a word or a label that is blank (spaces only).
    A :class:`ConfigError` naming the table and key.  Not checked by :func:`parse_config`:
    sessions stored with such a label parse, reopen and replay."""
    labels: list[tuple[str, str, str]] = []
    for feature in config.space.features:
        if len(feature.name) > MAX_NAME:
            fail(
                "space",
                None,
                f"the feature name {shown(feature.name)} has {len(feature.name):,} characters; "
                f"at most {MAX_NAME} are allowed (as for a unit or a word): the operator is "
                "shown it with each trial",
            )
        table = f"space.{feature.name}"
        up, down = feature.words
        if up.strip().casefold() == down.strip().casefold():
            fail(
                table,
                "words",
                f"must be two different words (how the operator says + and -), got "
                f"{shown(list(feature.words))}: the suggestions 'slightly {up}' and 'slightly "
                f"{down}' would read the same",
            )
        labels += [(table, "unit", feature.unit)] + [(table, "words", w) for w in feature.words]
    if config.ordinal is not None:
        labels += [("feedback.rating", "labels", label) for label in config.ordinal.categories]
        seen: dict[str, str] = {}
        for label in config.ordinal.categories:
            same = seen.setdefault(label.strip().casefold(), label)
            if same != label:
                fail(
                    "feedback.rating",
                    "labels",
                    f"must differ (ignoring case and spaces at the ends): {shown(same)} and "
                    f"{shown(label)} would read the same to the subject",
                )
    for table, key, label in labels:
        if key != "unit" and not label.strip():
            fail(
                table,
                key,
                f"must not be blank (spaces only), got {shown(label)}: the operator is shown it "
                "with each trial",
            )
        hidden = hidden_in(label, name=True)
        if hidden:
            named = char_name(hidden[0][1])
            fail(
                table,
                key,
                f"must not hold control, format or line-break characters (newlines, tabs, ESC, "
                f"NUL, bidirectional overrides, ...); {shown(label)} holds {named}: the operator "
                "is shown it with each trial",
            )


def check_ignored(config: ExperimentConfig) -> None:
    """Refuse, for a *new* session's config, a key its text gives that the config would ignore
    (a silently ignored key is a defect): ``[safety] risk`` or ``lambda`` without a region of
    avoidance (``avoid``); ``[model] refit_every`` or ``[model.prior]`` with ``fit = "fixed"``,
    which never refits; ``[model] hypotheses`` without ``hyper = "average"``; a ``[space.F]``
    with ``num = 1`` and ``max`` other than ``min`` (its one value is ``min``); a line path
    setting (``[cospar] line_points``, ...) with ``subspace = "grid"`` or a gait library, which
    draw no lines; ``[cospar] line_coactive`` without ``line_direction = "coactive"``;
    ``[model] sampler`` other than ``"auto"`` on the line path (point sets take their own);
    gated-eubo's ``sparring_from`` or ``sparring_until`` without ``sparring_until`` the larger,
    ``early_trials`` with ``early_scale = 1`` and ``early_scale`` with ``early_trials = 0``.  A
    :class:`ConfigError` naming the table and key.  Like :func:`check_name`, not checked by
    :func:`parse_config`: sessions stored with such a key (earlier releases took it) parse,
    reopen and replay as they were."""
    raw = read_toml(config.text)
    _check_burst_and_early(config)
    space = raw.get("space")
    for name, feature in space.items() if isinstance(space, dict) else ():
        if isinstance(feature, dict) and feature.get("num") == 1:
            low, high = feature.get("min"), feature.get("max")
            if low != high:
                fail(
                    f"space.{name}",
                    "num",
                    f"is 1: the feature's one value is min ({shown(low)}), and max "
                    f"({shown(high)}) would be ignored; set max = min, or values = [...]",
                )
    cospar = raw.get("cospar")
    grid_only = (
        "a [gaits] library names the gaits of a grid"
        if config.library is not None
        else "subspace = 'grid' draws no lines"
    )
    if isinstance(cospar, dict) and (
        config.library is not None or cospar.get("subspace") == "grid"
    ):
        for key in sorted(LINE_KEYS & set(cospar)):
            fail(
                "cospar",
                key,
                f"is a setting of the line path, and {grid_only}: {key} = "
                f"{shown(cospar[key])} would be ignored; leave it out"
                + ("" if config.library is not None else ", or use subspace = 'auto' or 'line'"),
            )
    if (
        isinstance(cospar, dict)
        and "line_coactive" in cospar
        and config.line.direction != "coactive"
    ):
        fail(
            "cospar",
            "line_coactive",
            "chooses the suggestions that give the coactive line direction, and line_direction "
            f"= {config.line.direction!r} draws none: line_coactive = "
            f"{shown(cospar['line_coactive'])} would be ignored; leave it out, or use "
            'line_direction = "coactive"',
        )
    safety = raw.get("safety")
    if isinstance(safety, dict) and not safety.get("avoid"):
        for key in ("risk", "lambda"):
            if key in safety:
                fail(
                    "safety",
                    key,
                    f"is a setting of the region of avoidance, which is off without avoid = "
                    f'["..."] (the worst [feedback.rating] labels): {key} = '
                    f"{shown(safety[key])} would be ignored; give avoid, or leave {key} out",
                )
    model = raw.get("model")
    if not isinstance(model, dict):
        return
    if config.subspace == "line" and model.get("sampler", "auto") != "auto":
        fail(
            "model",
            "sampler",
            f"is {shown(model['sampler'])}, a grid's sampler, and this config runs on the line "
            "path, whose point sets always sample their own way (PointEngine): it would be "
            'ignored; leave it out, or use sampler = "auto"',
        )
    learning = config.learning
    if learning.fit == "fixed":
        if "refit_every" in model:
            fail(
                "model",
                "refit_every",
                'is the answers between hyperparameter refits, and fit = "fixed" makes none: '
                f"refit_every = {shown(model['refit_every'])} would be ignored; leave it out, or "
                'use fit = "evidence"',
            )
        if "prior" in model:
            fail(
                "model.prior",
                None,
                'is the prior of the hyperparameter refits, and fit = "fixed" makes none: it '
                'would be ignored; leave it out, or use fit = "evidence"',
            )
    if "hypotheses" in model and learning.hyper != "average":
        fail(
            "model",
            "hypotheses",
            f'are weighed only with hyper = "average" (here {learning.hyper!r}): '
            f"hypotheses = {shown(model['hypotheses'])} would be ignored; leave it out, or use "
            'hyper = "average"',
        )


def _check_burst_and_early(config: ExperimentConfig) -> None:
    """Gated-eubo's settings that are off as given (:func:`check_ignored`)."""
    given = config.strategy_settings
    if config.strategy != "gated-eubo" or not given:
        return
    table = STRATEGY_TABLES["gated-eubo"]
    full = {k: given.get(k, key.default) for k, key in table.items()}
    where = "cospar.strategy_settings"
    start, until = full["sparring_from"], full["sparring_until"]
    burst = [k for k in ("sparring_until", "sparring_from") if k in given]
    if burst and not start < until:
        fail(
            where,
            burst[0],
            f"is {full[burst[0]]}, and an exploration burst runs only with sparring_until the "
            f"larger (sparring_from = {start}, sparring_until = {until}): it would be ignored; "
            "leave both out, or set sparring_from < sparring_until",
        )
    scale, trials = full["early_scale"], full["early_trials"]
    if "early_trials" in given and scale == 1:
        fail(
            where,
            "early_trials",
            f"is {trials}, and early_scale = 1 keeps the configured lengthscales (off): it would "
            "be ignored; leave it out, or set early_scale",
        )
    if "early_scale" in given and scale != 1 and trials == 0:
        fail(
            where,
            "early_scale",
            f"is {scale:g}, and early_trials = 0 uses it on no trial: it would be ignored; leave "
            "it out, or set early_trials above 0",
        )


def parse_config(
    text: str,
    default_name: str = "experiment",
    base_dir: str | Path | None = None,
    *,
    defaults: str = DEFAULTS_VERSION,
    max_actions: int = MAX_ACTIONS,
    library_file: str | Path | None = None,
) -> ExperimentConfig:
    """Parse config TOML text (see the module docstring for the format).

    A relative ``[gaits].library`` path is taken from ``base_dir`` (default: the working folder);
    ``library_file`` reads the library from that file instead of the path the text names (a
    session imported with a copy of its library, ``gaitpref.sessions.export``).
    ``defaults`` picks the version of the defaults (``"0.1"`` for sessions recorded with 0.1's);
    ``max_actions`` lowers the limit on the grid's size (a server's own limit).
    """
    raw = read_toml(text)
    top, _ = check_table(raw, "", TOP)
    library, library_path, generator = None, None, None
    library_base: str | None = None
    gaits, gaits_defaulted = (
        check_table(top["gaits"], "gaits", GAITS, defaults_for(defaults, "gaits"))
        if top["gaits"] is not None
        else ({}, frozenset())
    )
    if gaits and gaits["generator"] is not None:
        if gaits["library"] is not None:
            fail("gaits", "generator", "give either library or generator, not both")
        space = parse_space(top["space"], max_actions)
        generator = parse_generator(gaits, space)
    elif gaits:
        if gaits["library"] is None:
            fail("gaits", None, 'needs library = "FILE" or generator = "NAME"')
        given = [
            k
            for k in ("speed", "avoid_radius", "max_iterations", "max_infeasible", "recommend")
            if k not in gaits_defaulted
        ]
        if given:
            fail("gaits", given[0], "is a gait generator's setting; a library takes none")
        if top["space"] is not None:
            fail("gaits", None, "give either [space] or [gaits].library (its axes are the space)")
        library, library_path = parse_gaits(gaits, base_dir, library_file)
        if library_file is None:
            library_base = str(Path(base_dir if base_dir is not None else ".").resolve())
        space = library.space()
        if len(space) > max_actions:
            fail("gaits", "library", f"has {len(space)} gaits; at most {max_actions} are allowed")
    else:
        cospar_raw = top["cospar"]
        grid = isinstance(cospar_raw, dict) and cospar_raw.get("subspace") == "grid"
        space = parse_space(top["space"], max_actions, grid)
    model, model_defaulted = check_model(top["model"], defaults)
    cospar, defaulted = _cospar(top["cospar"], space, defaults, max_actions)
    on_line = cospar["subspace"] == "line"
    if on_line and library is not None:  # Session.create refused it, simulate ran it on lines
        fail(
            "cospar",
            "subspace",
            "runs on the line path, but a [gaits] library names the gaits of a grid: use "
            "subspace = 'grid', or [space] (with [gaits] generator for gaits made on demand)",
        )
    check_scales(model, cospar["coactive_weight"])
    settings = _strategy_settings(cospar)
    ordinal = parse_rating(top["feedback"], model["noise"])
    if ordinal is not None:
        ratio = model["signal_variance"] / ordinal.noise**2
        if ratio > MAX_SIGNAL_TO_NOISE:
            fail(
                "feedback.rating",
                "noise",
                f"[model] signal_variance / noise**2 is {ratio:.3g}, more than "
                f"{MAX_SIGNAL_TO_NOISE:g}: ratings this nearly deterministic cannot be fitted "
                "(as for [model] noise); use a larger rating noise",
            )
    grid = None if on_line else space
    safety, relied = parse_safety(top["safety"], ordinal, defaults, grid, library)
    stop, stop_defaulted = parse_stop(top["stop"])
    return ExperimentConfig(
        name=top["name"] if top["name"] is not None else default_name,
        description=top["description"],
        space=space,
        kernel=make_kernel(model, space),
        noise=model["noise"],
        n=cospar["n"],
        buffer=cospar["buffer"],
        coactive_weight=cospar["coactive_weight"],
        seed=cospar["seed"],
        text=text,
        strategy=cospar["strategy"],
        learning=make_learning(model, space),
        sampler=check_sampler(model, 0 if on_line else len(space)),
        subspace="line" if on_line else "grid",
        line=cospar["line"],
        library=library,
        library_path=library_path,
        base_dir=library_base,
        generator=generator,
        strategy_settings=settings,
        ordinal=ordinal,
        safety=safety,
        stop=stop,
        defaulted=frozenset(f"cospar.{k}" for k in defaulted if on_line or k not in LINE_KEYS)
        | frozenset(f"gaits.{k}" for k in gaits_defaulted if generator is not None)
        | relied
        | model_defaulted
        | stop_defaulted,
        defaults_version=defaults,
    )


def _cospar(
    raw: object, space: Space, defaults: str, max_actions: int
) -> tuple[dict[str, Any], frozenset[str]]:
    """``[cospar]`` checked; ``subspace`` resolved to ``"grid"`` or ``"line"``; ``line`` the
    line path's settings (a grid draws no lines: one line of ``line_points``, unchecked)."""
    cospar, defaulted = check_table(raw, "cospar", COSPAR, defaults_for(defaults, "cospar"))
    why = grid_too_large(space, max_actions)
    if cospar["subspace"] == "grid" and why is not None:
        fail("cospar", "subspace", f"is 'grid' but {why}: use subspace = 'line' (or 'auto')")
    if cospar["subspace"] == "auto":
        cospar["subspace"] = "grid" if why is None else "line"
    if cospar["subspace"] == "line":
        star = cospar["line_count"] * cospar["line_points"]
        if star > MAX_STAR_POINTS:
            fail(
                "cospar",
                "line_count",
                f"is {cospar['line_count']} lines of line_points = {cospar['line_points']}, "
                f"{star} points a query, more than {MAX_STAR_POINTS}: lower line_count "
                "(1: one line, as before defaults 0.10) or line_points",
            )
        if star + cospar["line_cloud"] > MAX_STAR_POINTS:
            fail(
                "cospar",
                "line_cloud",
                f"is {cospar['line_cloud']} points besides {star} on the lines, more than "
                f"{MAX_STAR_POINTS} a query: lower line_cloud, line_count or line_points",
            )
        if all(f.span == 0 for f in space.features):
            fail(
                "cospar",
                "subspace",
                "is 'line' but every feature has a single value: there is no line to draw "
                "(give a feature a range, or use the grid)",
            )
        most = min(cospar["line_points"], space.grid_size or cospar["line_points"])
        if cospar["n"] > most:
            fail(
                "cospar",
                "n",
                f"must be at most {most}, the distinct points a line of the query may hold "
                f"(line_points = {cospar['line_points']}"
                + (f", a grid of {space.grid_size}" if space.grid_size is not None else "")
                + f"), got {cospar['n']}",
            )
        lines, cloud = cospar["line_count"], cospar["line_cloud"]
        cospar["line"] = LineSettings(
            cospar["line_points"],
            cospar["line_direction"],
            lines,
            cloud,
            cospar["line_boundary"],
            cospar["line_coactive"],
        )
        return cospar, defaulted
    cospar["line"] = LineSettings(cospar["line_points"], cospar["line_direction"])
    size = len(space)
    for key in ("n", "buffer"):
        if cospar[key] > size:
            fail("cospar", key, f"must be at most the grid's {size} actions, got {cospar[key]}")
    return cospar, defaulted


def _strategy_settings(cospar: dict[str, Any]) -> dict[str, Any]:
    """The settings given for the strategy (the strategy keeps its defaults for the rest)."""
    name = cospar["strategy"]
    given = cospar["strategy_settings"]
    table, _ = check_table(
        given, "cospar.strategy_settings", STRATEGY_TABLES[name], for_what=f" for strategy {name!r}"
    )
    settings = {k: table[k] for k in given}
    try:  # what one key cannot say alone (plausible-eubo: gates <= samples)
        make_strategy(name, **table)
    except ValueError as exc:
        fail("cospar.strategy_settings", None, f"{exc} (strategy {name!r})")
    return settings
