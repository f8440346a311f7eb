"""Bifurcation diagrams of a continuation branch: section coordinates and the largest multiplier
against the parameter, stable and unstable parts, special points."""

from __future__ import annotations

from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..errors import GaitoptInputError
from .labels import state_label, unit_label

__all__ = ["plot_branch"]


def plot_branch(
    branch: Any,
    *,
    coordinate: str | None = None,
    axes: tuple[Axes, Axes] | None = None,
) -> tuple[Figure, tuple[Axes, Axes]]:
    """Bifurcation diagram of a continuation branch and its period-doubled children.

    Top: a section coordinate of every return of each orbit (a period-k gait shows k values)
    against the parameter — solid where stable, dotted where unstable.  Bottom: the largest
    |multiplier| with the stability limit 1.  Special points are marked and labelled.

    Parameters
    ----------
    branch : gaitopt.continuation.Branch
        The branch (its ``children`` are drawn too).
    coordinate : str, optional
        Section coordinate to draw (default: the first one).
    axes : pair of Axes, optional
        Where to draw.

    Returns
    -------
    (Figure, (Axes, Axes))
    """
    model = branch.model
    name = coordinate or model.section.coordinates[0]
    if name not in model.state_names:
        raise GaitoptInputError(
            f"`coordinate` {name!r} is not a state of {model.name}; states: "
            f"{', '.join(model.state_names)}"
        )
    index = model.state_names.index(name)
    if axes is None:
        fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7.5, 6.5))
    else:
        top, bottom = axes
        fig = top.figure
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    n_labels = 0
    for depth, sub in enumerate(branch.descendants()):
        colour = colours[depth % len(colours)]
        # The branch's points with its special points inserted in branch order: a special point
        # is the neutral end of both neighbouring segments (solid up to it on the stable side).
        rows = [(c, bool(c.stable)) for c in sub.cycles]
        for offset, sp in enumerate(
            sorted(
                (
                    sp
                    for sp in sub.special_points
                    if sp.cycle is not None and sp.cycle.success and sp.kind != "boundary"
                ),
                key=lambda sp: sp.index,
            )
        ):
            rows.insert(sp.index + 1 + offset, (sp.cycle, True))
        lam = np.array([getattr(c.model, branch.param) for c, _ in rows])
        stable = np.array([flag for _, flag in rows])
        returns = np.array(
            [[arc.x[index, 0] for arc in c.orbit if arc.phase == 0] for c, _ in rows]
        )
        for k in range(returns.shape[1] if returns.size else 0):
            _draw_by_stability(
                top, lam, returns[:, k], stable, colour, f"period {sub.steps}" if k == 0 else None
            )
        mods = np.array([np.max(np.abs(c.multipliers)) for c, _ in rows])
        _draw_by_stability(bottom, lam, mods, stable, colour, None)
        for sp in sub.special_points:
            if sp.cycle is None:
                continue
            value = sp.cycle.fixed_point[name]
            top.plot([sp.param], [value], "o", color="k", ms=5, zorder=5)
            # Successive labels alternate above and below (period doublings crowd together).
            shift = 10 * (1 + n_labels % 3) * (1 if n_labels % 2 == 0 else -1)
            n_labels += 1
            top.annotate(
                sp.kind,
                (sp.param, value),
                textcoords="offset points",
                xytext=(4, shift),
                fontsize=7,
                arrowprops={"arrowstyle": "-", "lw": 0.4, "color": "0.4"},
            )
            bottom.plot([sp.param], [np.max(np.abs(sp.cycle.multipliers))], "o", color="k", ms=5)
    bottom.axhline(1.0, color="0.3", lw=0.9, ls="--", label="|λ| = 1 (stability limit)")
    bottom.set_yscale("log")
    bottom.legend(fontsize=7, loc="best")
    top.set_ylabel(state_label(model, name, "on the section"))
    bottom.set_ylabel("largest multiplier |λ| (1, log scale)")
    spec = next((sp for sp in model.parameter_specs() if sp.name == branch.param), None)
    unit = spec.unit if spec is not None else None
    bottom.set_xlabel(f"parameter {branch.param} {unit_label(unit)}")
    top.set_title(
        f"{model.title or model.name}: gaits vs {branch.param} (solid stable, dotted unstable)"
    )
    top.legend(fontsize=8, loc="best")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    return fig, (top, bottom)


def _draw_by_stability(ax: Axes, x, y, stable, colour, label) -> None:
    """Solid where a segment's two ends are stable, dotted otherwise (runs merged)."""
    x, y, stable = np.asarray(x), np.asarray(y), np.asarray(stable, dtype=bool)
    if len(x) == 1:
        ax.plot(x, y, "o" if stable[0] else ".", color=colour, label=label)
        return
    solid = stable[:-1] & stable[1:]  # style of segment i → i + 1
    start = 0
    for j in range(1, len(solid) + 1):
        if j == len(solid) or solid[j] != solid[start]:
            ax.plot(
                x[start : j + 1],
                y[start : j + 1],
                color=colour,
                ls="-" if solid[start] else ":",
                lw=1.6,
                label=label,
            )
            label = None
            start = j
