"""Experiment configs: one TOML file per experiment (space, gaits, model, loop), checked once.

:func:`load_config` reads a shipped config by name (``shipped/``) or a TOML path;
:func:`parse_config` parses text.  Every error is a :class:`ConfigError` that names the table
and the key.
"""

from gaitpref.config.parse import (
    DEFAULT_FIT,
    DEFAULT_REFIT_EVERY,
    DEFAULT_STRATEGY,
    DEFAULT_TIES,
    ExperimentConfig,
    load_config,
    parse_config,
    shipped_configs,
)
from gaitpref.errors import ConfigError

__all__ = [
    "DEFAULT_FIT",
    "DEFAULT_REFIT_EVERY",
    "DEFAULT_STRATEGY",
    "DEFAULT_TIES",
    "ConfigError",
    "ExperimentConfig",
    "load_config",
    "parse_config",
    "shipped_configs",
]
