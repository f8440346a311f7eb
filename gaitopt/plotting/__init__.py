"""Static figures of gaits: phase portraits of the orbit and staircase plots of 1-D return maps.

Every function draws into a given :class:`matplotlib.axes.Axes` (or a new figure) and returns
``(fig, ax)``; nothing is shown, so the functions work under the Agg backend in scripts and CI.
:func:`save_figure` writes a figure whole or not at all (a temporary file, then
:func:`os.replace`).

Time is in the model's unit: seconds for the physical models, dimensionless time for Van der Pol
and Garcia's simplest walker (``τ = t·sqrt(g/l)``).

Modules, one figure family each: :mod:`~gaitopt.plotting.portrait` (phase portraits),
:mod:`~gaitopt.plotting.staircase` (staircase plots of 1-D return maps),
:mod:`~gaitopt.plotting.bifurcation` (bifurcation diagrams of a branch); shared by them:
:mod:`~gaitopt.plotting.labels` (units and axis labels) and :mod:`~gaitopt.plotting.save`
(:func:`save_figure`).
"""

from __future__ import annotations

from .bifurcation import plot_branch
from .labels import coordinate_pairs, state_label, state_unit, unit_label
from .labels import time_label as time_label  # public, not in __all__ (as before)
from .portrait import plot_phase_portrait
from .save import save_figure
from .staircase import plot_return_map

__all__ = [
    "plot_phase_portrait",
    "plot_return_map",
    "coordinate_pairs",
    "save_figure",
    "plot_branch",
    "state_unit",
    "state_label",
    "unit_label",
]

# The docstring examples of the submodules run with this package's (``doctest.testmod``).
__test__ = {"coordinate_pairs": coordinate_pairs}
