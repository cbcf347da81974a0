"""Pure numerics of the preference GP: kernels, likelihoods, the Laplace fit, the posterior."""

from gaitpref.model.engines import DENSE_MAX_ACTIONS, SAMPLERS, SamplerName
from gaitpref.model.gp import PreferenceGP
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.kronecker import KroneckerPriorSampler
from gaitpref.model.laplace import ConvergenceError, LaplaceMode, PriorNotPositiveDefiniteError
from gaitpref.model.likelihood import PairLikelihood, Probit
from gaitpref.model.posterior import Posterior

__all__ = [
    "DENSE_MAX_ACTIONS",
    "SAMPLERS",
    "ConvergenceError",
    "KroneckerPriorSampler",
    "LaplaceMode",
    "PairLikelihood",
    "Posterior",
    "PreferenceGP",
    "PriorNotPositiveDefiniteError",
    "Probit",
    "SamplerName",
    "SquaredExponential",
]
