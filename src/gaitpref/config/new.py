"""What a config must pass for a *new* session or run, beyond :func:`parse_config`.

A config is parsed the same way whenever it is read, so that a session stored under an earlier
release reopens and replays as it ran.  A new session (``Session.create``, ``gaitpref session
new``) and a new simulated run (``gaitpref simulate``) also refuse what such a stored config
may hold: a name, description or label that would garble the operator's screen, a key the
config would ignore, a draw larger than the model may make, and gaits made on demand whose
one ask may spend more solver iterations than ``MAX_ASK_ITERATIONS`` on gaits that cannot be
made, or over a feature in another unit than the generator reads it in.  :func:`check_new`
runs every one of those checks, in that order, so that both places refuse the same configs.
"""

from __future__ import annotations

from gaitpref.config.draws import check_draws
from gaitpref.config.experiment import ExperimentConfig
from gaitpref.config.generator import check_ask_cost, check_units
from gaitpref.config.parse import check_description, check_ignored, check_labels, check_name


def check_new(config: ExperimentConfig) -> None:
    """Refuse ``config`` for a new session or run: a :class:`ConfigError` naming the table and
    key (:func:`check_name`, :func:`check_description`, :func:`check_labels`,
    :func:`check_ignored`, :func:`check_draws`, :func:`check_ask_cost`, :func:`check_units`)."""
    check_name(config)
    check_description(config)
    check_labels(config)
    check_ignored(config)
    check_draws(config)
    spec = config.generator
    if spec is not None:
        check_ask_cost(spec.settings.get("max_iterations"), spec.max_infeasible)
        check_units(spec, config.space)


__all__ = ["check_new"]
