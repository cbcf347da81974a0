"""Pure numerics of the preference GP: kernels, likelihoods, the Laplace fit, the posterior."""

from gaitpref.model.gp import PreferenceGP
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.laplace import ConvergenceError, LaplaceMode, PriorNotPositiveDefiniteError
from gaitpref.model.likelihood import PairLikelihood, Probit
from gaitpref.model.posterior import KroneckerPriorSampler, Posterior

__all__ = [
    "ConvergenceError",
    "KroneckerPriorSampler",
    "LaplaceMode",
    "PairLikelihood",
    "Posterior",
    "PreferenceGP",
    "PriorNotPositiveDefiniteError",
    "Probit",
    "SquaredExponential",
]
