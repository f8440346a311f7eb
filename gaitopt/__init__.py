"""gaitopt: gaits of the classic simple models of legged locomotion as periodic orbits of hybrid
systems — multiple shooting with CasADi, Floquet multipliers, return maps, simulation.

>>> import gaitopt
>>> gait = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
>>> round(gait.period, 6), gait.stable
(0.734461, True)
"""

from __future__ import annotations

# The function `continuation` shares its name with its module: imported eagerly, since a lazy
# name would be shadowed by the submodule once anything imports it.
from .basin import Basin, basin, basin_fraction, basin_slice
from .continuation import Branch, PseudoArclength, SpecialPoint, continuation
from .errors import (
    FrozenModelError,
    GaitoptInputError,
    GuessError,
    ParameterError,
    StateError,
    UnknownModelError,
)
from .hybrid import Constraint, HybridModel, Phase, Section, Transition
from .models import REGISTRY, model, register, unregister
from .result import Gait, LimitCycle, OrbitArc
from .search import find_limit_cycle
from .shooting import MultipleShooting, ShootingProblem
from .simulation import Simulation, simulate

__all__ = [
    "model",
    "register",
    "unregister",
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
    "ShootingProblem",
    "Gait",
    "LimitCycle",
    "OrbitArc",
    "simulate",
    "basin",
    "basin_slice",
    "basin_fraction",
    "Basin",
    "orbital_distance",
    "optimize_gait",
    "OptimalGait",
    "gait_library",
    "stabilise",
    "Simulation",
    "HybridModel",
    "Phase",
    "Section",
    "Transition",
    "Constraint",
    "GaitoptInputError",
    "UnknownModelError",
    "ParameterError",
    "StateError",
    "GuessError",
    "FrozenModelError",
]
#: Names imported on first use (PEP 562): the two-parameter curves, the orbit
#: distance and optimal gaits pull in SciPy's integrators and optimisers, which most calls of
#: ``import gaitopt`` never need.
_LAZY = {
    "bifurcation_curve": ".curves",
    "Curve": ".curves",
    "ParameterPath": ".curves",
    "optimize_gait": ".optimize",
    "OptimalGait": ".optimize",
    "gait_library": ".optimize",
    "stabilise": ".optimize",
    "orbital_distance": ".orbits",
}


def __getattr__(name: str):
    if name == "__version__":  # the one source of the version: the installed package's metadata
        from importlib import metadata

        try:
            value = metadata.version("gaitopt")
        except metadata.PackageNotFoundError:  # a source tree that is not installed
            value = "0+unknown"
        globals()[name] = value
        return value
    if name in _LAZY:
        from importlib import import_module

        value = getattr(import_module(_LAZY[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'gaitopt' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
