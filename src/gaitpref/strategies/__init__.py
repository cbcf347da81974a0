"""Query strategies for the CoSpar loop, selectable by name (``[cospar] strategy`` in a config)."""

from __future__ import annotations

from collections.abc import Callable

from gaitpref.strategies.acquire import ConfidentEubo, Eubo
from gaitpref.strategies.base import AskContext, SelfSparring, Strategy
from gaitpref.strategies.hybrid import GatedEubo, Switch

_FACTORIES: dict[str, Callable[[], Strategy]] = {
    "self-sparring": SelfSparring,
    "eubo": Eubo,
    "gated-eubo": GatedEubo,
    "eubo-then-sparring": Switch,
    "confident-eubo": ConfidentEubo,
}
STRATEGIES: tuple[str, ...] = tuple(_FACTORIES)


def make_strategy(name: str) -> Strategy:
    """The strategy called ``name`` (one of :data:`STRATEGIES`) with its default settings."""
    try:
        return _FACTORIES[name]()
    except KeyError:
        raise ValueError(
            f"unknown strategy {name!r}; strategies are {', '.join(STRATEGIES)}"
        ) from None


__all__ = [
    "STRATEGIES",
    "AskContext",
    "ConfidentEubo",
    "Eubo",
    "GatedEubo",
    "SelfSparring",
    "Strategy",
    "Switch",
    "make_strategy",
]
