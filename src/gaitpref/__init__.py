"""gaitpref: preference-based gait personalization (CoSpar, Tucker, Novoseller et al., ICRA 2020).

The public API::

    space = gaitpref.Space([gaitpref.Feature("step_length", values, unit="m")])
    kernel = gaitpref.SquaredExponential(lengthscale=0.03, variance=0.005, jitter=1e-7)
    posterior = gaitpref.PreferenceGP(space, kernel, noise=0.02).posterior(winners, losers)
    loop = gaitpref.CoSpar(space, kernel, 0.02, n=1, buffer=1, seed=0)   # ask() / tell()
    config = gaitpref.load_config("exo-1d-step-length")                    # or a TOML path
"""

from gaitpref.config import ConfigError, ExperimentConfig, load_config, shipped_configs
from gaitpref.cospar import Answer, CoSpar, Query, QueryError
from gaitpref.feedback import Comparison, FeedbackError, Preference, Suggestion, Tie
from gaitpref.gaits import GaitLibrary, GaitLibraryError
from gaitpref.model import (
    ConvergenceError,
    Posterior,
    PreferenceGP,
    SquaredExponential,
)
from gaitpref.simulate.run import SimulationResult, run_simulation
from gaitpref.simulate.users import GradientCoactive, SimulatedUser
from gaitpref.space import MOVES, Feature, Move, Space

__version__ = "0.1.0"

__all__ = [
    "MOVES",
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
    "GradientCoactive",
    "Move",
    "Posterior",
    "Preference",
    "PreferenceGP",
    "Query",
    "QueryError",
    "SimulatedUser",
    "SimulationResult",
    "Space",
    "SquaredExponential",
    "Suggestion",
    "Tie",
    "__version__",
    "load_config",
    "run_simulation",
    "shipped_configs",
]
