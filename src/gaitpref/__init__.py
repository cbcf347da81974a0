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

Every name is loaded on first use (a module ``__getattr__``, PEP 562): ``import gaitpref`` itself
loads only the error classes, so the ``gaitpref`` command starts without SciPy's optimizers,
SQLAlchemy, matplotlib or a web framework (``tests/cli/test_startup.py``).
"""

from typing import TYPE_CHECKING, Any

from gaitpref.errors import (
    ConfigError,
    ConvergenceError,
    FeedbackError,
    GaitLibraryError,
    GaitprefError,
    PriorFromError,
    QueryError,
    ReplayError,
    SessionStateError,
    StorageError,
)

if TYPE_CHECKING:
    from gaitpref.config import ExperimentConfig, load_config, shipped_configs
    from gaitpref.feedback import Comparison, Preference, Rating, Suggestion, Tie
    from gaitpref.gaits import GaitLibrary
    from gaitpref.loop import Answer, CoSpar, Learning, LineCoSpar, Query
    from gaitpref.model import Ordinal, Posterior, PreferenceGP, SquaredExponential
    from gaitpref.pointset import PointSet
    from gaitpref.sessions import REASONS, Session, SessionQuery
    from gaitpref.simulate.noisy import IndifferentUser
    from gaitpref.simulate.run import SimulationResult, run_simulation
    from gaitpref.simulate.users import GradientCoactive, SimulatedUser
    from gaitpref.space import MOVES, Feature, Move, Space
    from gaitpref.strategies import STRATEGIES, Strategy, make_strategy

__version__ = "0.1.0"

# name -> the module that defines it; imported on first access, then cached in globals().
_LAZY = {
    "ExperimentConfig": "gaitpref.config",
    "load_config": "gaitpref.config",
    "shipped_configs": "gaitpref.config",
    "Comparison": "gaitpref.feedback",
    "Preference": "gaitpref.feedback",
    "Rating": "gaitpref.feedback",
    "Suggestion": "gaitpref.feedback",
    "Tie": "gaitpref.feedback",
    "GaitLibrary": "gaitpref.gaits",
    "Answer": "gaitpref.loop",
    "CoSpar": "gaitpref.loop",
    "LineCoSpar": "gaitpref.loop",
    "PointSet": "gaitpref.pointset",
    "Learning": "gaitpref.loop",
    "Query": "gaitpref.loop",
    "Ordinal": "gaitpref.model",
    "Posterior": "gaitpref.model",
    "PreferenceGP": "gaitpref.model",
    "SquaredExponential": "gaitpref.model",
    "REASONS": "gaitpref.sessions",
    "Session": "gaitpref.sessions",
    "SessionQuery": "gaitpref.sessions",
    "IndifferentUser": "gaitpref.simulate.noisy",
    "SimulationResult": "gaitpref.simulate.run",
    "run_simulation": "gaitpref.simulate.run",
    "GradientCoactive": "gaitpref.simulate.users",
    "SimulatedUser": "gaitpref.simulate.users",
    "MOVES": "gaitpref.space",
    "Feature": "gaitpref.space",
    "Move": "gaitpref.space",
    "Space": "gaitpref.space",
    "STRATEGIES": "gaitpref.strategies",
    "Strategy": "gaitpref.strategies",
    "make_strategy": "gaitpref.strategies",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'gaitpref' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})


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
    "LineCoSpar",
    "Move",
    "Ordinal",
    "PointSet",
    "Posterior",
    "Preference",
    "PreferenceGP",
    "PriorFromError",
    "Query",
    "QueryError",
    "Rating",
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
