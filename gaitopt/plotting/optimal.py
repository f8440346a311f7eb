"""Figures of an optimal gait (:class:`gaitopt.optimize.OptimalGait`): its states and its input
profile over one orbit, on axes grouped by unit (``gaitopt optimize --out``'s ``orbit.png`` and
``inputs.png``)."""

from __future__ import annotations

from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..errors import GaitoptInputError
from .labels import (
    cost_unit,
    input_quantity,
    input_unit,
    is_rate,
    state_quantity,
    state_unit,
    time_axis_label,
    unit_label,
)

__all__ = ["plot_optimal_orbit", "plot_optimal_inputs", "grouped"]


def grouped(names: list[str], key: Any) -> list[tuple[Any, list[str]]]:
    """``names`` grouped by ``key(name)``, groups in order of first appearance.

    >>> grouped(["q", "v", "r", "w"], lambda n: n in "vw")
    [(False, ['q', 'r']), (True, ['v', 'w'])]
    """
    groups: dict[Any, list[str]] = {}
    for name in names:
        groups.setdefault(key(name), []).append(name)
    return list(groups.items())


def _axis_label(quantity: str, names: list[str], unit: str | None) -> str:
    """``"angle stance, swing (rad)"``: the quantity, its symbols and its unit."""
    return f"{quantity} {', '.join(names)} {unit_label(unit)}"


def plot_optimal_orbit(gait: Any) -> tuple[Figure, list[Axes]]:
    """The states of an optimal gait over one orbit, one axis per kind of state and unit.

    Coordinates (angles, positions) and rates are drawn on separate axes, and states of
    different declared units (:attr:`HybridModel.state_units`) too, each axis labelled with the
    quantity, the states' names and their unit; time on a shared axis in the model's
    :attr:`~HybridModel.time_unit`.  A reset is a jump between two phase arcs.

    Parameters
    ----------
    gait : OptimalGait
        The optimum, with its densely sampled ``orbit`` (a list of
        :class:`gaitopt.result.OrbitArc`).

    Returns
    -------
    fig : matplotlib.figure.Figure
    axes : list of matplotlib.axes.Axes
        One per group of states, top to bottom.

    Raises
    ------
    GaitoptInputError
        If the gait has no orbit to draw (a failed optimisation).
    """
    if not gait.orbit:
        raise GaitoptInputError("the gait has no orbit to draw (the optimisation failed)")
    model = gait.model
    names: list[str] = []
    for arc in gait.orbit:
        names += [n for n in arc.states if n not in names]
    groups = grouped(names, lambda n: (is_rate(model, n), state_unit(model, n)))
    fig, axes = plt.subplots(
        len(groups), 1, figsize=(7, 2.2 + 1.8 * len(groups)), sharex=True, squeeze=False
    )
    axes = list(axes[:, 0])
    colours = {n: f"C{i % 10}" for i, n in enumerate(names)}
    for ax, ((_, unit), members) in zip(axes, groups, strict=True):
        for arc in gait.orbit:
            for name in members:
                if name in arc.states:
                    row = np.asarray(arc.x)[arc.states.index(name)]
                    first = all(name not in a.states for a in gait.orbit[: gait.orbit.index(arc)])
                    ax.plot(arc.t, row, color=colours[name], label=name if first else None)
        ax.set_ylabel(_axis_label(state_quantity(model, members[0]), members, unit), fontsize=8)
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.legend(fontsize=7, ncol=min(len(members), 4))
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel(time_axis_label(model))
    axes[0].set_title(f"{model.title or model.name}: optimal orbit over one period")
    fig.tight_layout()
    return fig, axes


def plot_optimal_inputs(gait: Any) -> tuple[Figure, list[Axes]]:
    """The input profile of an optimal gait over one orbit, one axis per input unit.

    Each axis is labelled with the kind of input (torque, force, impulse, …), the inputs' names
    and their declared unit (:attr:`HybridModel.input_units`); time in the model's unit.

    Parameters
    ----------
    gait : OptimalGait
        The optimum, with its sampled ``inputs`` (``{"time": [...], input: [...]}``).

    Returns
    -------
    fig : matplotlib.figure.Figure
    axes : list of matplotlib.axes.Axes
        One per group of inputs, top to bottom.

    Raises
    ------
    GaitoptInputError
        If the gait has no input profile (a passive model, or a failed optimisation).
    """
    model = gait.model
    names = [n for n in model.inputs if n in gait.inputs]
    if not names:
        raise GaitoptInputError("the gait has no input profile to draw")
    groups = grouped(names, lambda n: (input_quantity(model, n), input_unit(model, n)))
    fig, axes = plt.subplots(
        len(groups), 1, figsize=(7, 2.2 + 1.8 * len(groups)), sharex=True, squeeze=False
    )
    axes = list(axes[:, 0])
    time = gait.inputs["time"]
    for ax, ((quantity, unit), members) in zip(axes, groups, strict=True):
        for name in members:
            ax.plot(time, gait.inputs[name], label=name)
        ax.set_ylabel(_axis_label(quantity, members, unit), fontsize=8)
        ax.ticklabel_format(axis="y", useOffset=False)  # a constant impulse reads as itself
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel(time_axis_label(model))
    cost = (
        ""
        if gait.cost is None
        else f", {gait.cost_kind} {gait.cost:.6g} {unit_label(cost_unit(model, gait.cost_kind))}"
    )
    axes[0].set_title(f"{model.title or model.name}: optimal input{cost}")
    fig.tight_layout()
    return fig, axes
