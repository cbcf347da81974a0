"""Experiment configs: one TOML file per experiment (space, gaits, model, loop), checked once.

:func:`load_config` reads a shipped config by name (``shipped/``) or a TOML path;
:func:`parse_config` parses text.  Every error is a :class:`ConfigError` that names the table
and the key.  ``schema.py`` declares every key once; :data:`DEFAULTS` is the table of defaults
and :data:`LIMITS` the sizes a config may ask for.
"""

from gaitpref.config.draws import check_draws, draw_size
from gaitpref.config.experiment import ExperimentConfig
from gaitpref.config.new import check_new
from gaitpref.config.parse import (
    DEFAULT_BUFFER,
    DEFAULT_FIT,
    DEFAULT_REFIT_EVERY,
    DEFAULT_STRATEGY,
    DEFAULT_TIES,
    check_description,
    check_ignored,
    check_labels,
    check_name,
    load_config,
    parse_config,
    read_toml,
    shipped_configs,
)
from gaitpref.config.schema import DEFAULTS, DEFAULTS_VERSION, LIMITS
from gaitpref.errors import ConfigError

__all__ = [
    "DEFAULTS",
    "DEFAULTS_VERSION",
    "DEFAULT_BUFFER",
    "DEFAULT_FIT",
    "DEFAULT_REFIT_EVERY",
    "DEFAULT_STRATEGY",
    "DEFAULT_TIES",
    "LIMITS",
    "ConfigError",
    "ExperimentConfig",
    "check_description",
    "check_draws",
    "check_ignored",
    "check_labels",
    "check_name",
    "check_new",
    "draw_size",
    "load_config",
    "parse_config",
    "read_toml",
    "shipped_configs",
]
