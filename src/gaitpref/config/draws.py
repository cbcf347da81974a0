"""A new config's largest joint draw, checked against the sampling budget before it runs.

Every ask of the grid path draws joint posterior samples over the whole grid (self-sparring's
``n``, plausible-eubo's ``samples``, gated-eubo's ``gates``: ``strategies.joint_draws``), and the
numerics refuse a draw of more than :data:`~gaitpref.model.kronecker.SAMPLE_LIMIT_ELEMENTS`
values (``samples x actions``; 1 GiB of float64, a draw peaking near
:data:`~gaitpref.model.kronecker.SAMPLE_PEAK_ARRAYS` times that).  A config past it parsed and
made a session, and the operator learnt of it at the first ask, with the subject waiting.
:func:`check_draws` says it when a session is created (and ``gaitpref simulate`` loads a
config), naming the setting to lower.  Like :func:`~gaitpref.config.parse.check_name` it is not
part of :func:`~gaitpref.config.parse.parse_config`: a stored config is never refused on replay.

It also checks a ``[stop] samples`` given in the text against the confidence's budget
(:data:`~gaitpref.loop.stopping.CONFIDENCE_VALUES` sampled values after each answer): past it a
session would read fewer samples than the config says (``StopRule.samples_for``), so a value
given is refused there, naming the most the grid allows; the default is sized to the grid.
"""

from __future__ import annotations

from gaitpref.config.experiment import ExperimentConfig
from gaitpref.config.specs import fail
from gaitpref.loop.stopping import CONFIDENCE_VALUES
from gaitpref.model.kronecker import SAMPLE_LIMIT_ELEMENTS, SAMPLE_PEAK_ARRAYS
from gaitpref.strategies import joint_draws, make_strategy


def draw_size(config: ExperimentConfig) -> tuple[int, int, str | None]:
    """The most joint samples one ask of ``config`` draws at once, the points each covers (the
    grid's actions; on the line path the first query's lines, a table that then grows by the
    points run) and the setting that sets the number of samples (``"n"``, a strategy setting's
    name, or None)."""
    strategy = make_strategy(config.strategy, **config.strategy_settings)
    samples, setting = joint_draws(strategy, config.n)
    if config.subspace == "line":
        points = config.line.lines * config.line.points
    else:
        points = len(config.space)
    return samples, points, setting


def check_stop_samples(config: ExperimentConfig) -> None:
    """A :class:`~gaitpref.config.ConfigError` naming ``[stop] samples`` when the text gives more
    than the grid lets a confidence read (module docstring); nothing otherwise (the line path's
    table grows with the run: its rule reads fewer samples once it passes the budget)."""
    if "stop.samples" in config.defaulted or config.subspace == "line":
        return
    actions = len(config.space)
    rule = config.stop
    most = rule.samples_for(actions)
    if rule.samples > most:
        fail(
            "stop",
            "samples",
            f"is {rule.samples}: a confidence after each answer draws every sample over the "
            f"{actions:,} gaits, and past {CONFIDENCE_VALUES:,} sampled values it takes seconds "
            f"to minutes; set samples to at most {most}, or leave it out (the default is sized "
            "to the grid)",
        )


def check_draws(config: ExperimentConfig) -> None:
    """A :class:`~gaitpref.config.ConfigError` naming the setting when one ask of ``config``
    would draw more than the sampling budget, or its ``[stop] samples`` more than the
    confidence's (module docstring); nothing otherwise."""
    check_stop_samples(config)
    samples, points, setting = draw_size(config)
    values = samples * points
    if values <= SAMPLE_LIMIT_ELEMENTS:
        return
    most = SAMPLE_LIMIT_ELEMENTS // points
    over = (
        f"each ask draws {samples} joint posterior samples over the {points:,} actions, "
        f"{values:,} values, more than the sampling budget of {SAMPLE_LIMIT_ELEMENTS:,} (1 GiB "
        f"of float64; a draw at the budget peaks near {SAMPLE_PEAK_ARRAYS} GiB), so the first "
        "ask would fail"
    )
    fewer = "or use a smaller grid ([space]) or [cospar] subspace = 'line'"
    if setting == "n":
        fail("cospar", "n", f"is {samples}: {over}; set n to at most {most}, {fewer}")
    if setting is not None:
        fail(
            "cospar.strategy_settings",
            setting,
            f"is {samples} (strategy {config.strategy!r}): {over}; set {setting} to at most "
            f"{most}, {fewer}",
        )
    fail("cospar", "strategy", f"is {config.strategy!r}: {over}; {fewer.removeprefix('or ')}")
