"""Staircase (cobweb) plots of a 1-D step-to-step return map, with its fixed points."""

from __future__ import annotations

from collections.abc import Callable

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..errors import GaitoptInputError
from ..hybrid import HybridModel
from ..returnmap import fixed_points_1d, one_dimensional, return_map
from .labels import state_label, state_unit

__all__ = ["plot_return_map"]


def _new_axes(ax: Axes | None, figsize: tuple[float, float]) -> tuple[Figure, Axes]:
    if ax is None:
        fig, ax = plt.subplots(figsize=figsize, layout="constrained")
        return fig, ax
    return ax.figure, ax


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
    lo, hi = one_dimensional(model, interval, "a staircase plot needs")
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
        # The values go into the legend, not beside the markers: fixed points close together
        # (the SLIP's 0.877 and 0.917 m) would print their labels over each other.
        values_text = "; ".join(f"{x:.6g} (λ = {lam.real:.3g})" for x, lam in points[stable])
        ax.plot(
            xs,
            xs,
            "o",
            ms=8,
            color="k",
            mfc="k" if stable else "white",
            zorder=5,
            label=f"{kind} fixed point {values_text}" if xs else None,
            gid=f"{kind} fixed points",
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
