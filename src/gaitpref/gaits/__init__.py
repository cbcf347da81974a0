"""Compass-gait model, HZD gait optimization and the gait library (issue 4).

Layers, bottom up: :mod:`params` and :mod:`dynamics` / :mod:`impact` (the hybrid model),
:mod:`bezier` and :mod:`zero_dynamics` (the virtual constraint and its periodic orbit),
:mod:`optimize` (one gait), :mod:`simulate` (full-model check), :mod:`library`,
:mod:`library_io` and :mod:`build` (a grid of gaits and its file), :mod:`generator`,
:mod:`gait_cache` and :mod:`on_demand` (gaits made when first proposed), :mod:`study` (COT over
step length), :mod:`figures` and :mod:`cli` (pictures and commands).  See ``docs/gaits.md``.
"""

from gaitpref.errors import GaitGeneratorError, GaitLibraryError, SimulationError
from gaitpref.gaits.build import build_library
from gaitpref.gaits.gait import Gait, GaitRequest, HZDSettings
from gaitpref.gaits.gait_cache import CachedGait, GaitCache, GaitCacheWarning
from gaitpref.gaits.generator import (
    CompassHZD,
    GaitGenerator,
    generator_names,
    make_generator,
    register_generator,
)
from gaitpref.gaits.library import (
    GaitLibrary,
)
from gaitpref.gaits.library_io import SCHEMA_VERSION, load_library, save_library
from gaitpref.gaits.on_demand import MadeGait, OnDemandGaits
from gaitpref.gaits.optimize import optimize_gait
from gaitpref.gaits.params import CompassGaitParams
from gaitpref.gaits.simulate import (
    SimulationResult,
    simulate_gait,
)
from gaitpref.gaits.study import CotCurve, compass_gait_cot, cot_over_step_length

__all__ = [
    "SCHEMA_VERSION",
    "CachedGait",
    "CompassGaitParams",
    "CompassHZD",
    "CotCurve",
    "Gait",
    "GaitCache",
    "GaitCacheWarning",
    "GaitGenerator",
    "GaitGeneratorError",
    "GaitLibrary",
    "GaitLibraryError",
    "GaitRequest",
    "HZDSettings",
    "MadeGait",
    "OnDemandGaits",
    "SimulationError",
    "SimulationResult",
    "build_library",
    "compass_gait_cot",
    "cot_over_step_length",
    "generator_names",
    "load_library",
    "make_generator",
    "optimize_gait",
    "register_generator",
    "save_library",
    "simulate_gait",
]
