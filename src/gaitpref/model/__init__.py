"""Pure numerics of the preference GP: kernels, likelihoods, the Laplace fit, the posterior."""

from gaitpref.errors import ConvergenceError, PriorNotPositiveDefiniteError
from gaitpref.model.engines import DENSE_MAX_ACTIONS, SAMPLERS, SamplerName
from gaitpref.model.evidence import Evidence, Hyperparameters, PairData, laplace_evidence
from gaitpref.model.gp import PreferenceGP
from gaitpref.model.hyperfit import (
    HyperFit,
    HyperPrior,
    LogNormal,
    default_prior,
    fit_hyperparameters,
)
from gaitpref.model.kernels import SquaredExponential
from gaitpref.model.kronecker import SAMPLE_LIMIT_ELEMENTS, KroneckerPriorSampler
from gaitpref.model.laplace import (
    LaplaceMode,
)
from gaitpref.model.likelihood import (
    ActionLikelihood,
    OrderedProbit,
    PairLikelihood,
    Probit,
    StackedActionLikelihood,
)
from gaitpref.model.ordinal import (
    Ordinal,
    OrdinalLikelihood,
    rating_likelihood,
    rating_probabilities,
)
from gaitpref.model.population import PopulationModel, PopulationPosterior, population_evidence
from gaitpref.model.population_fit import LogitNormal, PopulationFit, fit_population
from gaitpref.model.posterior import Posterior

__all__ = [
    "DENSE_MAX_ACTIONS",
    "SAMPLERS",
    "SAMPLE_LIMIT_ELEMENTS",
    "ActionLikelihood",
    "ConvergenceError",
    "Evidence",
    "HyperFit",
    "HyperPrior",
    "Hyperparameters",
    "KroneckerPriorSampler",
    "LaplaceMode",
    "LogNormal",
    "LogitNormal",
    "OrderedProbit",
    "Ordinal",
    "OrdinalLikelihood",
    "PairData",
    "PairLikelihood",
    "PopulationFit",
    "PopulationModel",
    "PopulationPosterior",
    "Posterior",
    "PreferenceGP",
    "PriorNotPositiveDefiniteError",
    "Probit",
    "SamplerName",
    "SquaredExponential",
    "StackedActionLikelihood",
    "default_prior",
    "fit_hyperparameters",
    "fit_population",
    "laplace_evidence",
    "population_evidence",
    "rating_likelihood",
    "rating_probabilities",
]
