"""Static figures of gaits: phase portraits of the orbit and staircase plots of 1-D return maps.

Every function draws into a given :class:`matplotlib.axes.Axes` (or a new figure) and returns
``(fig, ax)``; nothing is shown, so the functions work under the Agg backend in scripts and CI.
:func:`save_figure` writes a figure whole or not at all (a temporary file, then
:func:`os.replace`).

Time is in the model's unit: seconds for the physical models, dimensionless time for Van der Pol
and Garcia's simplest walker (``τ = t·sqrt(g/l)``).

Modules, one figure family each: :mod:`~gaitopt.plotting.portrait` (phase portraits),
:mod:`~gaitopt.plotting.staircase` (staircase plots of 1-D return maps),
:mod:`~gaitopt.plotting.bifurcation` (bifurcation diagrams of a branch),
:mod:`~gaitopt.plotting.optimal` (an optimal gait's states and inputs); shared by them:
:mod:`~gaitopt.plotting.labels` (units and axis labels) and :mod:`~gaitopt.plotting.save`
(:func:`save_figure`).

The figure functions are imported on first use (PEP 562): :mod:`~gaitopt.plotting.labels` needs
no matplotlib, so the command line's text output reads the models' units from it without
importing matplotlib.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

from .labels import coordinate_pairs, state_label, state_unit, unit_label
from .labels import time_label as time_label  # public, not in __all__ (as before)

__all__ = [
    "plot_phase_portrait",
    "plot_return_map",
    "coordinate_pairs",
    "save_figure",
    "plot_branch",
    "state_unit",
    "state_label",
    "unit_label",
    "plot_optimal_orbit",
    "plot_optimal_inputs",
]

#: The figure functions, each imported from its module on first use.
_LAZY = {
    "plot_phase_portrait": ".portrait",
    "plot_return_map": ".staircase",
    "plot_branch": ".bifurcation",
    "save_figure": ".save",
    "plot_optimal_orbit": ".optimal",
    "plot_optimal_inputs": ".optimal",
}

# The docstring examples of the submodules run with this package's (``doctest.testmod``).
__test__ = {"coordinate_pairs": coordinate_pairs}


def __getattr__(name: str) -> Any:
    """A figure function of :data:`_LAZY`, imported from its module (with matplotlib)."""
    if name in _LAZY:
        value = getattr(import_module(_LAZY[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
