"""gaitpref: preference-based gait personalization (CoSpar, Tucker, Novoseller et al., ICRA 2020).

The public API::

    space = gaitpref.Space([gaitpref.Feature("step_length", values, unit="m")])
    kernel = gaitpref.SquaredExponential(lengthscale=0.03, variance=0.005, jitter=1e-7)
    posterior = gaitpref.PreferenceGP(space, kernel, noise=0.02).posterior(winners, losers)
    loop = gaitpref.CoSpar(space, kernel, 0.02, n=1, buffer=1, seed=0)   # ask() / tell()
    loop = gaitpref.CoSpar(space, kernel, 0.02, n=1, buffer=1, seed=0,
                           strategy=gaitpref.make_strategy("gated-eubo"),
                           learning=gaitpref.Learning(fit="evidence", refit_every=20))
    config = gaitpref.load_config("exo-1d-step-length")                    # or a TOML path
    session = gaitpref.Session.create("sqlite:///lab.db", config, subject="S01")  # durable
"""

from typing import TYPE_CHECKING, Any

from gaitpref.config import ConfigError, ExperimentConfig, load_config, shipped_configs
from gaitpref.errors import (
    ConvergenceError,
    FeedbackError,
    GaitLibraryError,
    GaitprefError,
    QueryError,
    ReplayError,
    SessionStateError,
    StorageError,
)
from gaitpref.feedback import Comparison, Preference, Suggestion, Tie
from gaitpref.loop import Answer, CoSpar, Learning, Query
from gaitpref.model import Posterior, PreferenceGP, SquaredExponential
from gaitpref.simulate.noisy import IndifferentUser
from gaitpref.simulate.run import SimulationResult, run_simulation
from gaitpref.simulate.users import GradientCoactive, SimulatedUser
from gaitpref.space import MOVES, Feature, Move, Space
from gaitpref.strategies import STRATEGIES, Strategy, make_strategy

if TYPE_CHECKING:
    from gaitpref.gaits import GaitLibrary
    from gaitpref.sessions import REASONS, Session, SessionQuery

__version__ = "0.1.0"

# Heavier parts (gait optimization pulls scipy.optimize, sessions pull SQLAlchemy) load on first
# use, so `import gaitpref` and the CLI start quickly.
_LAZY = {
    "GaitLibrary": "gaitpref.gaits",
    "Session": "gaitpref.sessions",
    "SessionQuery": "gaitpref.sessions",
    "REASONS": "gaitpref.sessions",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'gaitpref' has no attribute {name!r}")


__all__ = [
    "MOVES",
    "REASONS",
    "STRATEGIES",
    "Answer",
    "CoSpar",
    "Comparison",
    "ConfigError",
    "ConvergenceError",
    "ExperimentConfig",
    "Feature",
    "FeedbackError",
    "GaitLibrary",
    "GaitLibraryError",
    "GaitprefError",
    "GradientCoactive",
    "IndifferentUser",
    "Learning",
    "Move",
    "Posterior",
    "Preference",
    "PreferenceGP",
    "Query",
    "QueryError",
    "ReplayError",
    "Session",
    "SessionQuery",
    "SessionStateError",
    "SimulatedUser",
    "SimulationResult",
    "Space",
    "SquaredExponential",
    "StorageError",
    "Strategy",
    "Suggestion",
    "Tie",
    "__version__",
    "load_config",
    "make_strategy",
    "run_simulation",
    "shipped_configs",
]
