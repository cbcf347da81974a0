"""How CoSpar picks the actions of a query: the strategy protocol and its context.

The paper's Algorithm 1 (Tucker, Novoseller et al., ICRA 2020) proposes the argmaxes of ``n``
posterior samples (self-sparring).  A :class:`Strategy` replaces only that step: the query's
buffer, the comparisons, coactive feedback and the refit are the loop's (``cospar.py``), the same
for every strategy.  A strategy is deterministic given the context's generator, so a loop
replays exactly from its seed.  It proposes only actions in ``context.allowed`` when it is set
(the region of interest and the unsafe flags, ``loop/safety.py``).

Notation: ``A`` actions; ``n`` new actions per query; ``b`` buffered (previously executed) ones.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from gaitpref.checks import check_mask, is_count
from gaitpref.model.posterior import Posterior

#: The most candidates an EUBO search compares (its pairs are a ``c x c`` matrix), the most
#: joint samples a strategy draws per ask (``samples x A`` values) and the most gates: the
#: bounds a config's ``[cospar.strategy_settings]`` has (``config/schema.py``).
MAX_CANDIDATES = 4096
MAX_SAMPLES = 4096
MAX_GATES = 1000


def plain(value: object) -> object:
    """A NumPy scalar as the Python number it holds (others as they are): a setting built from
    NumPy is stored and shown as one given in Python."""
    return value.item() if isinstance(value, np.generic) else value


def check_count(settings: object, name: str, low: int, high: int) -> None:
    """The count setting ``name`` of a (frozen) strategy: an integer (not a bool; a NumPy one is
    kept as an ``int``) in ``low..high``."""
    value = getattr(settings, name)
    if not is_count(value) or not low <= value <= high:
        raise ValueError(f"{name} must be an integer >= {low} and <= {high}, got {value!r}")
    object.__setattr__(settings, name, int(value))


@dataclass(frozen=True)
class AskContext:
    """What a strategy may use: the posterior, the query's shape, the trial count, the RNG."""

    posterior: Posterior
    n: int
    buffer: tuple[int, ...]
    trial: int  # actions executed before this query
    rng: np.random.Generator
    allowed: NDArray[np.bool_] | None = None  # None: every action may be proposed
    #: The same answers refitted with every lengthscale times the factor given (the loop's data,
    #: model and warm start otherwise unchanged), read over the same actions as ``posterior``
    #: (on the line path: the table and the query's line); None where the loop offers none.  A
    #: strategy may choose with it; the loop's own posterior stays the configured one.
    rescaled: Callable[[float], Posterior] | None = None

    def __post_init__(self) -> None:
        # Every proposal loop runs at most ``n`` rounds: bound it by the grid, so that no query
        # (a config's ``n``, or a loop built by hand) can keep a strategy busy without end.
        if not isinstance(self.posterior, Posterior):
            raise TypeError(f"posterior must be a gaitpref Posterior, got {self.posterior!r}")
        size = len(self.posterior.space)
        if not is_count(self.n) or not 1 <= self.n <= size:
            raise ValueError(
                f"a query needs 1 to {size} new actions (the grid's size), got n = {self.n!r}"
            )
        object.__setattr__(self, "n", int(self.n))
        # A context built by hand (a strategy scripted outside the loop) is checked as the
        # loop's own: an off-grid buffer was a raw NumPy IndexError (a negative one wrapped), an
        # integer seed an AttributeError, and an all-false mask let EUBO propose a gait the mask
        # forbids.
        buffer = self.buffer
        if isinstance(buffer, str | bytes) or not isinstance(buffer, tuple | list):
            raise TypeError(f"buffer must be a tuple of action indices, got {buffer!r}")
        for k, a in enumerate(buffer):
            if not is_count(a) or not 0 <= a < size:
                raise ValueError(f"buffer[{k}] = {a!r} is not an action (0..{size - 1})")
        object.__setattr__(self, "buffer", tuple(int(a) for a in buffer))
        if not is_count(self.trial) or self.trial < 0:
            raise ValueError(f"trial must be an integer >= 0, got {self.trial!r}")
        object.__setattr__(self, "trial", int(self.trial))
        if not isinstance(self.rng, np.random.Generator):
            raise TypeError(
                "rng must be a numpy.random.Generator (numpy.random.default_rng(seed)), "
                f"got {self.rng!r}"
            )
        if self.allowed is not None:
            empty = "allowed allows no action: there is nothing to propose"
            check_mask(self.allowed, size, optional=True, empty=empty)


class Strategy(Protocol):
    """Proposes the ``n`` actions of the next query."""

    @property
    def name(self) -> str: ...

    def propose(self, context: AskContext) -> tuple[int, ...]:
        """``context.n`` grid indices (repeats allowed only where the strategy says so)."""
        ...


def joint_draws(strategy: Strategy, n: int) -> tuple[int, str | None]:
    """The most joint posterior samples one ask of ``strategy`` draws at once (``samples x A``
    values, checked against the sampling budget) with ``n`` new actions a query, and the setting
    that sets the number (``"n"``, a setting's name, or None).  The registered strategies say it
    (their ``joint_draws``); one that does not is taken to draw as self-sparring, ``n``."""
    says = getattr(strategy, "joint_draws", None)
    if says is None:
        return n, "n"
    count, setting = says(n)
    return int(count), setting


@dataclass(frozen=True)
class SelfSparring:
    """The paper's rule: the argmax of each of ``n`` joint posterior samples (Thompson
    sampling; exact ties broken at random).  An action may repeat the buffered one."""

    name: str = "self-sparring"

    def propose(self, context: AskContext) -> tuple[int, ...]:
        picks = context.posterior.argmax_samples(context.rng, context.n, context.allowed)
        return tuple(int(a) for a in picks)

    def joint_draws(self, n: int) -> tuple[int, str | None]:
        """The most joint posterior samples one ask draws at once (``n`` new actions a query)
        and the setting that sets that number (``"n"``: the query's; None: fixed)."""
        return n, "n"
