"""Static figures of gaits: phase portraits of the orbit and staircase plots of 1-D return maps.

Every function draws into a given :class:`matplotlib.axes.Axes` (or a new figure) and returns
``(fig, ax)``; nothing is shown, so the functions work under the Agg backend in scripts and CI.
:func:`save_figure` writes a figure whole or not at all (a temporary file, then
:func:`os.replace`).

Time is in the model's unit: seconds for the physical models, dimensionless time for Van der Pol
and Garcia's simplest walker (``τ = t·sqrt(g/l)``).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .errors import GaitoptInputError
from .files import replaced_atomically
from .hybrid import HybridModel, Transition
from .result import LimitCycle
from .returnmap import fixed_points_1d, return_map
from .simulation import Simulation

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

_RATE_SUFFIX = "_dot"
# Samples per simulated arc for the transient overlay.
_TRANSIENT_SAMPLES = 150
# Marker shapes of the kinds of reset in one cycle (first kind: circles).
_RESET_MARKERS = ("o", "s", "D", "^", "v")


def coordinate_pairs(states: tuple[str, ...] | list[str]) -> list[str]:
    """The coordinates ``q`` of ``states`` whose rate ``q_dot`` is also a state, in state order.

    >>> coordinate_pairs(("stance", "swing", "stance_dot", "swing_dot"))
    ['stance', 'swing']
    """
    return [q for q in states if not q.endswith(_RATE_SUFFIX) and q + _RATE_SUFFIX in states]


def state_unit(model: HybridModel, name: str) -> str | None:
    """Unit of state ``name`` from the model's declared :attr:`HybridModel.state_units`; a rate
    ``q_dot`` not listed gets ``unit(q)/time unit``; None if nothing is declared."""
    units = dict(model.state_units)
    if name in units:
        return units[name]
    if name.endswith(_RATE_SUFFIX) and name[: -len(_RATE_SUFFIX)] in units:
        base, time = units[name[: -len(_RATE_SUFFIX)]], model.time_unit
        return base if time == "1" and base == "1" else f"{base}/{time}"
    return None


def unit_label(unit: str | None) -> str:
    """``"(rad)"``; ``"(dimensionless)"`` for ``"1"``; ``"(unit not declared)"`` for None."""
    if unit is None:
        return "(unit not declared)"
    return "(dimensionless)" if unit == "1" else f"({unit})"


def time_label(model: HybridModel) -> str:
    """The model's time unit for labels: ``"s"``; ``"(dimensionless time)"`` for ``"1"``; a
    named dimensionless time (``"τ"``) with that note."""
    unit = model.time_unit
    if unit == "s":
        return "s"
    return "(dimensionless time)" if unit == "1" else f"{unit} (dimensionless time)"


def state_label(model: HybridModel, name: str, when: str = "") -> str:
    """Axis label of a state: ``"theta_dot just after return n (rad/s)"``."""
    text = f"{name} {when}".strip()
    return f"{text} {unit_label(state_unit(model, name))}"


def _transition(model: HybridModel, phase: int, name: str) -> Transition | None:
    for tr in model.phases[phase].transitions:
        if tr.name == name:
            return tr
    return None


def _new_axes(ax: Axes | None, figsize: tuple[float, float]) -> tuple[Figure, Axes]:
    if ax is None:
        fig, ax = plt.subplots(figsize=figsize, layout="constrained")
        return fig, ax
    return ax.figure, ax


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
            if q not in model.rates and q + _RATE_SUFFIX not in held
        ]
        names += [q for q in pairs if q not in names and q not in held]
    if not names:
        raise GaitoptInputError(
            f"{model.name}: no state q has a rate q{_RATE_SUFFIX} in the orbit's states "
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
    return [q for q in group if q in states and _RATE.get(q, q + _RATE_SUFFIX) in states]


# Rate partner of each coordinate for the portrait being drawn: the model's declared
# :attr:`HybridModel.rates`, else the naming convention q → q_dot (set by plot_phase_portrait).
_RATE: dict[str, str] = {}


def _rate(q: str) -> str:
    return _RATE.get(q, q + _RATE_SUFFIX)


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


def plot_return_map(
    model: HybridModel,
    interval: tuple[float, float],
    start: float | None = None,
    iterations: int = 8,
    ax: Axes | None = None,
    closed_form: Callable[[float], float] | None = None,
    *,
    samples: int = 80,
) -> tuple[Figure, Axes]:
    """Staircase (cobweb) plot of a 1-D step-to-step return map ``s_{n+1} = P(s_n)``.

    The map is sampled by simulation (:func:`gaitopt.returnmap.fixed_points_1d`) on ``interval``;
    where the motion does not return to the section it is NaN and the curve has a gap, and where
    it jumps (the rimless wheel's map at the vaulting speed ω₁, between rocking and rolling) the
    jump is located by bisection and the curve broken there.  Then the diagonal ``P(s) = s``, the
    staircase of ``iterations`` simulated steps from ``start``, and every fixed point found on
    the interval: filled if stable, hollow if unstable (each one solved and verified as a limit
    cycle, its multiplier written next to it).

    Parameters
    ----------
    model : HybridModel
        A model whose Poincaré section has one coordinate (rimless wheel: ``theta_dot``, rad/s;
        Van der Pol: ``q_dot``).
    interval : tuple of float
        ``(low, high)`` range of the section coordinate, in its unit.
    start : float, optional
        Start of the staircase; default: the model's :meth:`default_start` if it lies in the
        interval, else the interval's midpoint.
    iterations : int
        Steps of the staircase (it stops early where the map is undefined).
    ax : matplotlib.axes.Axes, optional
        Where to draw; a new figure if omitted.
    closed_form : callable, optional
        ``closed_form(s) -> P(s)`` (NaN where undefined), drawn dashed over the sampled map, e.g.
        ``model.closed_form_map`` of the rimless wheel.
    samples : int
        Number of map samples on the interval.

    Returns
    -------
    fig : matplotlib.figure.Figure
    ax : matplotlib.axes.Axes
        The stable fixed points are the line artist with ``gid="stable fixed points"`` (the
        unstable ones ``gid="unstable fixed points"``), its x data the fixed points.

    Raises
    ------
    GaitoptInputError
        If the section is not one-dimensional, the interval is empty, or ``iterations`` or
        ``samples`` is not a positive integer.
    """
    if len(model.section.coordinates) != 1:
        raise GaitoptInputError(
            f"{model.name}: a staircase plot needs a 1-D section; this one has coordinates "
            f"{', '.join(model.section.coordinates)}"
        )
    lo, hi = map(float, interval)
    if not lo < hi:
        raise GaitoptInputError(f"`interval` must be increasing, got {interval!r}")
    if int(iterations) != iterations or iterations < 0:
        raise GaitoptInputError(f"`iterations` must be a non-negative integer, got {iterations!r}")
    if int(samples) != samples or samples < 2:
        raise GaitoptInputError(f"`samples` must be an integer ≥ 2, got {samples!r}")
    (name,) = model.section.coordinates

    def P(s: float) -> float:
        return float(return_map(model, [s])[0])

    found = fixed_points_1d(model, (lo, hi), samples=int(samples))
    grid, values = _break_jumps(P, found.grid, found.values)

    fig, ax = _new_axes(ax, (5.6, 5.2))
    ax.plot(grid, values, color="C0", lw=1.8, label=f"return map P({name}) (simulated)")
    ax.plot([lo, hi], [lo, hi], color="k", lw=0.8, ls=":", label="diagonal P(s) = s")
    if closed_form is not None:
        fine = np.linspace(lo, hi, 600)
        ax.plot(
            fine,
            [closed_form(s) for s in fine],
            color="C3",
            lw=1.2,
            ls="--",
            label="closed form",
        )

    # The staircase: vertical to the map, horizontal to the diagonal, repeated.  A default start
    # on a fixed point would show nothing: it is moved 30 % of the interval away from it.
    if start is None:
        guess = model.default_start().get(name, np.nan)
        start = guess if lo <= guess <= hi else 0.5 * (lo + hi)
        for c in found.cycles:
            fp = float(c.section_point[0])
            if abs(start - fp) < 0.05 * (hi - lo):
                away = fp + 0.3 * (hi - lo)
                start = away if away <= hi else fp - 0.3 * (hi - lo)
    s = float(start)
    path_x, path_y = [s], [s]
    for _ in range(int(iterations)):
        s_next = P(s)
        if not np.isfinite(s_next):
            break
        path_x += [s, s_next]
        path_y += [s_next, s_next]
        s = s_next
    unit = state_unit(model, name)
    ax.plot(
        path_x,
        path_y,
        color="C1",
        lw=1.0,
        label=f"staircase from {start:.4g}" + (f" {unit}" if unit and unit != "1" else ""),
    )
    ax.plot([start], [start], "s", color="C1", ms=5)

    # Fixed points, each a verified limit cycle (duplicates from nearby brackets merged).
    points: dict[bool, list[tuple[float, complex]]] = {True: [], False: []}
    for c in found.cycles:
        x = float(c.section_point[0])
        if all(abs(x - y) > 1e-8 * max(1.0, abs(x)) for y, _ in points[True] + points[False]):
            points[bool(c.stable)].append((x, complex(c.multipliers[0])))
    for stable in (True, False):
        xs = [x for x, _ in points[stable]]
        kind = "stable" if stable else "unstable"
        ax.plot(
            xs,
            xs,
            "o",
            ms=8,
            color="k",
            mfc="k" if stable else "white",
            zorder=5,
            label=f"{kind} fixed point" if xs else None,
            gid=f"{kind} fixed points",
        )
        for x, lam in points[stable]:
            ax.annotate(
                f" {x:.6g}\n λ = {lam.real:.3g}",
                (x, x),
                xytext=(8, -22),
                textcoords="offset points",
                fontsize=8,
            )

    finite = values[np.isfinite(values)]
    top = max(hi, float(finite.max()) if finite.size else hi)
    bottom = min(lo, float(finite.min()) if finite.size else lo)
    ax.set_xlim(lo, hi)
    ax.set_ylim(bottom, top)
    ax.set_xlabel(state_label(model, name, "at return n"))
    ax.set_ylabel(state_label(model, name, "at return n + 1"))
    ax.set_title(f"{model.title or model.name}: step-to-step return map", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    return fig, ax


def _break_jumps(
    P: Callable[[float], float], grid: np.ndarray, values: np.ndarray, *, bisections: int = 30
) -> tuple[np.ndarray, np.ndarray]:
    """Insert NaN where the sampled map jumps, with samples on both sides of the jump.

    A jump is suspected where consecutive defined samples differ by far more than usual; it is
    confirmed by bisection (the difference does not shrink with the bracket).
    """
    d = np.abs(np.diff(values))
    if not np.any(np.isfinite(d)):
        return grid, values
    typical = np.nanmedian(d)
    span = np.nanmax(values) - np.nanmin(values)
    suspect = max(10 * typical, 0.05 * span)
    out_x, out_y = [grid[0]], [values[0]]
    for k in range(len(grid) - 1):
        a, b, fa, fb = grid[k], grid[k + 1], values[k], values[k + 1]
        if np.isfinite(d[k]) and d[k] > suspect:
            jump = True
            for _ in range(bisections):
                m = 0.5 * (a + b)
                fm = P(m)
                if not np.isfinite(fm):
                    break
                if abs(fm - fa) < abs(fb - fm):
                    a, fa = m, fm
                else:
                    b, fb = m, fm
                if abs(fb - fa) < 0.5 * suspect:  # the step shrinks with the bracket: steep
                    jump = False
                    break
            if jump:  # the step stays at bracket width 2⁻³⁰ (or the map is undefined inside)
                out_x += [a, np.nan, b]
                out_y += [fa, np.nan, fb]
        out_x.append(grid[k + 1])
        out_y.append(values[k + 1])
    return np.array(out_x), np.array(out_y)


def save_figure(fig: Figure, path: str | os.PathLike, *, dpi: int = 110) -> Path:
    """Write ``fig`` to ``path`` whole or not at all, then close it.

    The figure is saved to a temporary file in the same directory and moved into place with
    :func:`os.replace` (:func:`gaitopt.files.replaced_atomically`); the format comes from the
    suffix of ``path``.
    """
    path = Path(path)
    fmt = path.suffix.lstrip(".") or "png"
    try:
        with replaced_atomically(path) as tmp:
            fig.savefig(tmp, format=fmt, dpi=dpi)
    finally:
        plt.close(fig)
    return path


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
