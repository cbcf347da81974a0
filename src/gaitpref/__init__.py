"""gaitpref: preference-based gait personalization (CoSpar, Tucker, Novoseller et al., ICRA 2020)."""

from gaitpref.model import (
    ConvergenceError,
    Posterior,
    PreferenceGP,
    SquaredExponential,
)
from gaitpref.space import MOVES, Feature, Move, Space

__version__ = "0.1.0"

__all__ = [
    "MOVES",
    "ConvergenceError",
    "Feature",
    "Move",
    "Posterior",
    "PreferenceGP",
    "Space",
    "SquaredExponential",
    "__version__",
]
