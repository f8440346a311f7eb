"""gaitopt: gaits of the classic simple models of legged locomotion as periodic orbits of hybrid
systems — multiple shooting with CasADi, Floquet multipliers, return maps, simulation.

>>> import gaitopt
>>> gait = gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))
>>> round(gait.period, 6), gait.stable
(0.734461, True)
"""

from __future__ import annotations

import sys as _sys
import types as _types

from .errors import (
    FrozenModelError,
    GaitoptInputError,
    GuessError,
    ParameterError,
    StateError,
    UnknownModelError,
)

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
#: The public names, each imported from its module on first use (PEP 562): ``import gaitopt``
#: costs the errors module only, and ``gaitopt.find_limit_cycle(gaitopt.model("compass_gait"))``
#: imports the shooting, the one model and the verification's simulation, not the basins,
#: continuation, curves or optimal gaits (SciPy's integrators and optimisers, matplotlib, Dask):
#: tests/test_import_cost.py checks which modules that call imports.
_LAZY = {
    "model": ".models",
    "register": ".models",
    "unregister": ".models",
    "REGISTRY": ".models",
    "find_limit_cycle": ".search",
    "continuation": ".continuation",
    "PseudoArclength": ".continuation",
    "Branch": ".continuation",
    "SpecialPoint": ".continuation",
    "bifurcation_curve": ".curves",
    "Curve": ".curves",
    "ParameterPath": ".curves",
    "MultipleShooting": ".shooting",
    "ShootingProblem": ".shooting",
    "Gait": ".result",
    "LimitCycle": ".result",
    "OrbitArc": ".result",
    "simulate": ".simulation",
    "Simulation": ".simulation",
    "basin": ".basin",
    "basin_slice": ".basin",
    "basin_fraction": ".basin",
    "Basin": ".basin",
    "orbital_distance": ".orbits",
    "optimize_gait": ".optimize",
    "OptimalGait": ".optimize",
    "gait_library": ".optimize",
    "stabilise": ".optimize",
    "HybridModel": ".hybrid",
    "Phase": ".hybrid",
    "Section": ".hybrid",
    "Transition": ".hybrid",
    "Constraint": ".hybrid",
}
#: Public functions named as the subpackage that defines them (``gaitopt.continuation`` the
#: function, ``gaitopt/continuation/`` its package; ``gaitopt.basin`` likewise): importing the
#: subpackage would set the package's attribute to the module (the import system's
#: ``setattr(parent, child, module)``), so :class:`_Package` keeps the function there instead —
#: as when the names were imported eagerly, after their modules.
_SHADOWED = frozenset({"continuation", "basin"})


class _Package(_types.ModuleType):
    """The package's module type: a submodule import does not replace a function of its name."""

    def __setattr__(self, name: str, value: object) -> None:
        if name in _SHADOWED and isinstance(value, _types.ModuleType):
            value = getattr(value, name, value)
        super().__setattr__(name, value)


_sys.modules[__name__].__class__ = _Package


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
