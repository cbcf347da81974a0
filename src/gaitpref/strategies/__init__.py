"""Query strategies for the CoSpar loop, selectable by name (``[cospar] strategy`` in a config).

Each strategy's settings (``STRATEGY_SETTINGS``) are settable from a config's
``[cospar.strategy_settings]`` table; every proposal loop is bounded by ``n`` (the query's size),
which :class:`AskContext` checks against the grid.
"""

from __future__ import annotations

from typing import Any

from gaitpref.strategies.acquire import ConfidentEubo, Eubo
from gaitpref.strategies.base import AskContext, SelfSparring, Strategy, joint_draws
from gaitpref.strategies.hybrid import GatedEubo, Switch
from gaitpref.strategies.infogain import InformationGain
from gaitpref.strategies.plausible import PlausibleEubo

#: Every strategy by name: the class, constructed with its settings as keywords.
STRATEGY_CLASSES: dict[str, type[Any]] = {
    "self-sparring": SelfSparring,
    "eubo": Eubo,
    "gated-eubo": GatedEubo,
    "eubo-then-sparring": Switch,
    "confident-eubo": ConfidentEubo,
    "information-gain": InformationGain,
    "plausible-eubo": PlausibleEubo,
}
STRATEGIES: tuple[str, ...] = tuple(STRATEGY_CLASSES)
#: The settings a config may give each strategy (``[cospar.strategy_settings]``); the defaults
#: are the classes' own.
STRATEGY_SETTINGS: dict[str, tuple[str, ...]] = {
    "self-sparring": (),
    "eubo": ("candidates",),
    "gated-eubo": ("gates", "early_scale", "early_trials", "sparring_from", "sparring_until"),
    "eubo-then-sparring": ("trials",),
    "confident-eubo": ("beta", "candidates"),
    "information-gain": ("candidates",),
    "plausible-eubo": ("samples", "gates"),
}


def make_strategy(name: str, **settings: Any) -> Strategy:
    """The strategy called ``name`` (one of :data:`STRATEGIES`) with ``settings``.

    Settings not given keep the strategy's defaults.  An unknown name or setting, or a setting's
    bad value, raises ``ValueError`` naming it.
    """
    if not isinstance(name, str) or name not in STRATEGY_CLASSES:
        raise ValueError(f"unknown strategy {name!r}; strategies are {', '.join(STRATEGIES)}")
    allowed = STRATEGY_SETTINGS[name]
    for setting in settings:
        if setting not in allowed:
            raise ValueError(
                f"strategy {name!r} has no setting {setting!r} "
                f"(its settings: {', '.join(allowed) or 'none'})"
            )
    strategy: Strategy = STRATEGY_CLASSES[name](**settings)
    return strategy


__all__ = [
    "STRATEGIES",
    "STRATEGY_CLASSES",
    "STRATEGY_SETTINGS",
    "AskContext",
    "ConfidentEubo",
    "Eubo",
    "GatedEubo",
    "InformationGain",
    "PlausibleEubo",
    "SelfSparring",
    "Strategy",
    "Switch",
    "joint_draws",
    "make_strategy",
]
