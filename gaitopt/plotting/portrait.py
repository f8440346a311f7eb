"""Phase portraits of a gait: each coordinate against its rate along the orbit, the resets as
jumps, and an optional simulated transient."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..errors import GaitoptInputError
from ..hybrid import HybridModel, Transition
from ..result import LimitCycle
from ..simulation import Simulation
from .labels import RATE_SUFFIX, coordinate_pairs, state_unit, time_label, unit_label

__all__ = ["plot_phase_portrait"]

# Samples per simulated arc for the transient overlay.
_TRANSIENT_SAMPLES = 150
# Marker shapes of the kinds of reset in one cycle (first kind: circles).
_RESET_MARKERS = ("o", "s", "D", "^", "v")


def _transition(model: HybridModel, phase: int, name: str) -> Transition | None:
    for tr in model.phases[phase].transitions:
        if tr.name == name:
            return tr
    return None


def plot_phase_portrait(
    cycle: LimitCycle,
    ax: Axes | None = None,
    simulation: Simulation | None = None,
) -> tuple[Figure, Axes]:
    """Phase portrait of a gait: each coordinate ``q`` against its rate ``q_dot`` along the orbit.

    Every state ``q`` with a partner ``q_dot`` in an arc's states gets one colour.  Each phase arc
    of the orbit is a solid line; each reset that moves the state (an impact, a relabelling such as
    the compass gait's leg swap) is a dashed jump from the arc's end to the next arc's start
    (cyclically: the last arc jumps to the first), with the pre-reset state marked by a hollow
    circle and the post-reset state by a filled one.  Where the state dimension changes (the
    kneed walker's knee strike locks the shank to the thigh; heel strike releases it) a coordinate
    that stops being a state gets only its hollow end marker and one that becomes a state only its
    filled start marker.  If the cycle has several kinds of reset, each kind has its own marker
    shape (circle, square, diamond, ...) and legend entry named after the transition
    (``"knee strike (impact)"``); with one kind the legend says ``"reset (impact)"``.  A simulated
    transient, if given, is drawn as thin grey lines (one per coordinate, broken at resets) under
    the orbit.

    Parameters
    ----------
    cycle : LimitCycle
        A solved gait (``cycle.success`` true, ``cycle.orbit`` not empty).
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new figure if omitted.
    simulation : Simulation, optional
        A simulated transient of the same model (e.g. from :func:`gaitopt.simulate` started off the
        orbit) to overlay.

    Returns
    -------
    fig : matplotlib.figure.Figure
    ax : matplotlib.axes.Axes
        The axes.  Its line artists are, for each coordinate: one per orbit arc, then one per
        nontrivial reset, then (with ``simulation``) one transient line.

    Notes
    -----
    Each axis is labelled with the model's declared units (:attr:`HybridModel.state_units`), one
    unit per axis: coordinates with different units (a hopper's metres and radians) are drawn in
    separate panels of one figure (``fig.axes``; the returned ``ax`` is the first).  The title
    gives the model, the period with its time unit and the largest modulus of the nontrivial
    Floquet multipliers.

    Raises
    ------
    GaitoptInputError
        If ``cycle`` has no orbit (a failed search) or no state has a ``_dot`` partner.
    """
    if not cycle.success or not cycle.orbit:
        raise GaitoptInputError(
            f"`cycle` must be a solved gait with an orbit; got success={cycle.success} "
            f"({cycle.message}). Plot only cycles with success=True"
        )
    model = cycle.model
    arcs = cycle.orbit
    names: list[str] = []
    for arc in arcs:
        declared = [q for q, r in model.rates.items() if q in arc.states and r in arc.states]
        held = set(model.rates.values())
        pairs = declared + [
            q
            for q in coordinate_pairs(arc.states)
            if q not in model.rates and q + RATE_SUFFIX not in held
        ]
        names += [q for q in pairs if q not in names and q not in held]
    if not names:
        raise GaitoptInputError(
            f"{model.name}: no state q has a rate q{RATE_SUFFIX} in the orbit's states "
            f"{arcs[0].states}; the phase portrait needs such pairs"
        )
    _RATE.clear()
    _RATE.update(model.rates)
    groups: dict[tuple[str | None, str | None], list[str]] = {}
    for q in names:
        key = (state_unit(model, q), state_unit(model, _rate(q)))
        groups.setdefault(key, []).append(q)
    if len(groups) > 1 and ax is not None:
        raise GaitoptInputError(
            f"{model.name}: the coordinates have {len(groups)} different units, drawn on one axes "
            f"each; pass ax=None to get a figure with {len(groups)} panels"
        )
    if ax is None:
        fig, panels = plt.subplots(
            1, len(groups), figsize=(7.6 + 4.2 * (len(groups) - 1), 4.8), layout="constrained"
        )
        panels = list(np.atleast_1d(panels))
    else:
        fig, panels = ax.figure, [ax]
    colours = {q: f"C{i % 10}" for i, q in enumerate(names)}
    largest = np.max(np.abs(cycle.multipliers)) if len(cycle.multipliers) else float("nan")
    stable = {True: "stable", False: "unstable"}.get(cycle.stable, "stability unknown")
    for panel, ((unit, rate_unit), group) in zip(panels, groups.items(), strict=True):
        _draw_portrait(panel, cycle, tuple(group), colours, simulation)
        which = ", ".join(group)
        panel.set_xlabel(f"coordinate {which} {unit_label(unit)}")
        panel.set_ylabel(f"rate d/dt of {which} {unit_label(rate_unit)}")
        panel.grid(True, alpha=0.3)
        panel.legend(fontsize=8, loc="best")
    panels[0].set_title(
        f"{model.title or model.name}: period {cycle.period:.6g} {time_label(model)}, "
        f"max |multiplier| {largest:.3g} ({stable})",
        fontsize=10,
    )
    return fig, panels[0]


def _pairs_in(states: tuple[str, ...], group: tuple[str, ...]) -> list[str]:
    return [q for q in group if q in states and _RATE.get(q, q + RATE_SUFFIX) in states]


# Rate partner of each coordinate for the portrait being drawn: the model's declared
# :attr:`HybridModel.rates`, else the naming convention q → q_dot (set by plot_phase_portrait).
_RATE: dict[str, str] = {}


def _rate(q: str) -> str:
    return _RATE.get(q, q + RATE_SUFFIX)


def _draw_portrait(
    ax: Axes,
    cycle: LimitCycle,
    group: tuple[str, ...],
    colours: dict[str, str],
    simulation: Simulation | None,
) -> None:
    """The orbit's arcs and resets (and a transient) for the coordinates in ``group``."""
    model = cycle.model
    arcs = cycle.orbit

    # The orbit: one solid line per coordinate and arc.
    labelled: set[str] = set()
    for arc in arcs:
        for q in _pairs_in(arc.states, group):
            i, j = arc.states.index(q), arc.states.index(_rate(q))
            label = None if q in labelled else q
            labelled.add(q)
            ax.plot(arc.x[i], arc.x[j], color=colours[q], lw=1.8, label=label, zorder=3)

    # Resets: dashed jumps from each arc's end to the next arc's start.  With several kinds of
    # reset in the cycle (the kneed walker's knee strike and heel strike) each kind has its own
    # marker shape and legend entry, named after the transition.
    kinds = list(dict.fromkeys(arc.transition for arc in arcs))
    named = len(kinds) > 1
    shapes = {kind: _RESET_MARKERS[i % len(_RESET_MARKERS)] for i, kind in enumerate(kinds)}
    for k, arc in enumerate(arcs):
        nxt = arcs[(k + 1) % len(arcs)]
        tr = _transition(model, arc.phase, arc.transition)
        marker = shapes[arc.transition] if named else "o"
        if named:
            kind = arc.transition + (" (impact)" if tr is None or tr.impact else "")
        else:
            kind = "reset (impact)" if tr is None or tr.impact else "reset"

        def legend_entry(kind: str = kind, marker: str = marker) -> None:
            # With several kinds, a neutral legend entry for the marker shape (the markers take
            # each coordinate's colour), added only once a marker of that kind is drawn.
            if named and kind not in labelled:
                labelled.add(kind)
                ax.scatter([], [], s=28, marker=marker, color="0.35", label=kind)

        before_pairs, after_pairs = _pairs_in(arc.states, group), _pairs_in(nxt.states, group)
        for q in before_pairs:
            if q not in after_pairs:
                # The coordinate stops being a state at this reset (a knee that locks: the shank
                # then moves with the thigh): mark where it ends.
                legend_entry()
                i, j = arc.states.index(q), arc.states.index(_rate(q))
                ax.scatter(
                    arc.x[i, -1],
                    arc.x[j, -1],
                    s=28,
                    marker=marker,
                    facecolors="white",
                    edgecolors=colours[q],
                    zorder=4,
                )
                continue
            i, j = arc.states.index(q), arc.states.index(_rate(q))
            i2, j2 = nxt.states.index(q), nxt.states.index(_rate(q))
            before = np.array([arc.x[i, -1], arc.x[j, -1]])
            after = np.array([nxt.x[i2, 0], nxt.x[j2, 0]])
            scale = max(np.ptp(arc.x[i]), np.ptp(arc.x[j]), 1e-300)
            if np.linalg.norm(after - before) <= 1e-6 * scale:
                # An identity reset (Van der Pol's section crossing): nothing to draw.  The dense
                # orbit closes only to the shooting accuracy, hence the relative 1e-6.
                continue
            legend_entry()
            ax.plot(*np.c_[before, after], color=colours[q], lw=1.2, ls="--", zorder=2)
            ax.scatter(
                *before, s=28, marker=marker, facecolors="white", edgecolors=colours[q], zorder=4
            )
            label = None if kind in labelled else kind
            labelled.add(kind)
            ax.scatter(*after, s=28, marker=marker, color=colours[q], zorder=4, label=label)
        for q in after_pairs:
            if q not in before_pairs:
                # The coordinate becomes a state at this reset (a knee released): mark its start.
                legend_entry()
                i2, j2 = nxt.states.index(q), nxt.states.index(_rate(q))
                ax.scatter(
                    nxt.x[i2, 0], nxt.x[j2, 0], s=28, marker=marker, color=colours[q], zorder=4
                )

    if simulation is not None:
        _plot_transient(ax, model, simulation, list(group))


def _plot_transient(ax: Axes, model: HybridModel, simulation: Simulation, names: list[str]) -> None:
    """One thin grey line per coordinate through all simulated arcs, NaN at resets."""
    label = "simulated transient"
    for q in names:
        xs: list[np.ndarray] = []
        ys: list[np.ndarray] = []
        for arc in simulation.arcs:
            states = model.phases[arc.phase].states
            if q not in states or _rate(q) not in states:
                continue
            _, X = arc.sample(_TRANSIENT_SAMPLES)
            xs += [X[states.index(q)], [np.nan]]
            ys += [X[states.index(_rate(q))], [np.nan]]
        if xs:
            ax.plot(
                np.concatenate(xs),
                np.concatenate(ys),
                color="0.55",
                lw=0.7,
                zorder=1,
                label=label,
            )
            label = None
