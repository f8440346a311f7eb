"""gaitopt: gaits of the classic simple models of legged locomotion as periodic orbits of hybrid
systems — multiple shooting with CasADi, Floquet multipliers, return maps, simulation.

>>> import gaitopt
>>> gait = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
>>> round(gait.period, 6), gait.stable
(0.734461, True)
"""

from __future__ import annotations

from importlib import metadata as _metadata

from .continuation import Branch, PseudoArclength, SpecialPoint, continuation
from .curves import Curve, ParameterPath, bifurcation_curve
from .errors import (
    FrozenModelError,
    GaitoptInputError,
    GuessError,
    ParameterError,
    StateError,
    UnknownModelError,
)
from .hybrid import HybridModel, Phase, Section, Transition
from .models import REGISTRY, model
from .optimize import OptimalGait, optimize_gait
from .orbits import orbital_distance
from .result import LimitCycle, OrbitArc
from .shooting import MultipleShooting, find_limit_cycle
from .simulation import Simulation, simulate

__all__ = [
    "model",
    "REGISTRY",
    "find_limit_cycle",
    "continuation",
    "bifurcation_curve",
    "Curve",
    "ParameterPath",
    "PseudoArclength",
    "Branch",
    "SpecialPoint",
    "MultipleShooting",
    "LimitCycle",
    "OrbitArc",
    "simulate",
    "orbital_distance",
    "optimize_gait",
    "OptimalGait",
    "Simulation",
    "HybridModel",
    "Phase",
    "Section",
    "Transition",
    "GaitoptInputError",
    "UnknownModelError",
    "ParameterError",
    "StateError",
    "GuessError",
    "FrozenModelError",
]
try:  # the one source of the version: the installed package's metadata (pyproject.toml)
    __version__ = _metadata.version("gaitopt")
except _metadata.PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"
