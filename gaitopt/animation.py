"""Animated GIFs of walkers, runners and jugglers, from a simulation.

The drawing comes from declared model data: each phase's ``points(x, p)`` function gives named
world-frame points relative to the current contact point; the model's
:attr:`~gaitopt.hybrid.HybridModel.drawing` lists the polylines to draw through them (default:
one polyline through every point), and :meth:`~gaitopt.hybrid.HybridModel.outline` draws shapes
the points cannot say (the rimless wheel's spokes, the kneed walker's curved feet).  A dot marks
the body mass (the point named ``hip``, ``hub``, ``mass``, ``body``, ``axle`` or ``com``) or the
ball (``ball``).  At each transition with a ``foothold`` the contact point moves to that point's
world position at the event, so successive steps walk on.

A walker or hopper stands on the ground, drawn as the line ``y = −x·tan(γ)`` through the first
contact, γ the model's declared :meth:`~gaitopt.hybrid.HybridModel.ground_slope` (its ``slope``
parameter, or 0); a scene without ground (a ball on a vibrating table, a juggler's paddle) says so
with the declared class attribute :attr:`~gaitopt.hybrid.HybridModel.on_ground` ``= False``, and
is drawn without it, its view filling the frame.  Such
a scene's GIF is named ``animation.gif`` by ``make gaits`` (:func:`gif_name`), a walker's
``walking.gif``.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.animation import FuncAnimation, PillowWriter

from .errors import GaitoptInputError
from .files import replaced_atomically
from .hybrid import HybridModel, Phase
from .simulation import Simulation

__all__ = ["animate_walker", "walker_frames", "on_ground", "gif_name"]

_MASS_POINTS = ("hip", "hub", "mass", "body", "axle", "com", "ball")


def on_ground(model: HybridModel) -> bool:
    """Whether ``model``'s scene stands on the ground (the declared
    :attr:`~gaitopt.hybrid.HybridModel.on_ground`, default True): False for a ball on a table or
    a juggler's paddle, drawn without a ground."""
    return bool(model.on_ground)


def gif_name(model: HybridModel) -> str:
    """File name of ``model``'s animation: ``walking.gif`` for a scene on the ground (walkers,
    hoppers), ``animation.gif`` for one without (the bouncing ball, the jugglers)."""
    return "walking.gif" if on_ground(model) else "animation.gif"


def _outline(model: HybridModel, phase: Phase, x: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """The model's declared drawing: its :meth:`outline`, else its :attr:`drawing` polylines,
    else the polyline through every point."""
    custom = model.outline(phase, x, pts)
    if custom is not None:
        return np.asarray(custom, dtype=float)
    if model.drawing:
        segments: list[np.ndarray] = []
        for line in model.drawing:
            present = [n for n in line if n in phase.point_names]
            if len(present) < 2:
                continue
            segments += [pts[:, phase.point_names.index(n)] for n in present]
            segments.append(np.array([np.nan, np.nan]))
        return np.array(segments, dtype=float).T if segments else np.zeros((2, 0))
    return pts


def _check_drawable(model: HybridModel, simulation: Simulation) -> None:
    if not simulation.arcs:
        raise GaitoptInputError("`simulation` has no arcs; simulate at least one step")
    for arc in simulation.arcs:
        phase = model.phases[arc.phase]
        if phase.points is None:
            raise GaitoptInputError(
                f"{model.name}: phase {phase.name!r} has no drawing points (Phase.points is "
                "None); only models with a geometry can be animated"
            )


def _contact_offsets(model: HybridModel, simulation: Simulation) -> list[np.ndarray]:
    """World position of the contact point during each arc (the first contact at the origin)."""
    offsets = [np.zeros(2)]
    p = model.p
    for k in range(len(simulation.arcs) - 1):
        offset = offsets[-1]
        if k < len(simulation.events):
            event = simulation.events[k]
            phase = model.phases[event.phase]
            tr = next((t for t in phase.transitions if t.name == event.transition), None)
            if tr is not None and tr.foothold is not None:
                pts = np.asarray(phase.points(event.state_before, p), dtype=float)
                offset = offset + pts[:, phase.point_names.index(tr.foothold)]
        offsets.append(offset)
    return offsets


def walker_frames(
    model: HybridModel, simulation: Simulation, times: np.ndarray
) -> list[dict[str, np.ndarray]]:
    """World-frame drawing data of ``model`` at ``times`` along ``simulation``.

    Parameters
    ----------
    model : HybridModel
        The simulated model (its phases must have ``points``).
    simulation : Simulation
        A simulation of ``model`` (:func:`gaitopt.simulate`).
    times : numpy.ndarray
        Times (model time unit), within the simulated span.

    Returns
    -------
    list of dict
        Per time: ``"outline"`` (2×M, m, NaN-separated polyline of the body), ``"mass"`` (2×1 or
        2×0, the body mass point) and ``"contact"`` (2, the current contact point).
    """
    _check_drawable(model, simulation)
    arcs = simulation.arcs
    offsets = _contact_offsets(model, simulation)
    ends = np.array([arc.t1 for arc in arcs])
    p = model.p
    frames = []
    for t in np.asarray(times, dtype=float):
        k = min(int(np.searchsorted(ends, t, side="left")), len(arcs) - 1)
        arc = arcs[k]
        phase = model.phases[arc.phase]
        x = np.asarray(arc.solution(min(max(t, arc.t0), arc.t1)), dtype=float).ravel()
        pts = np.asarray(phase.points(x, p), dtype=float)
        outline = _outline(model, phase, x, pts)
        mass = [n for n in _MASS_POINTS if n in phase.point_names]
        mass_xy = pts[:, [phase.point_names.index(mass[0])]] if mass else np.zeros((2, 0))
        frames.append(
            {
                "outline": outline + offsets[k][:, None],
                "mass": mass_xy + offsets[k][:, None],
                "contact": offsets[k],
            }
        )
    return frames


def animate_walker(
    model: HybridModel,
    simulation: Simulation,
    path: str | os.PathLike,
    fps: int = 30,
    *,
    max_frames: int = 150,
    dpi: int = 100,
) -> Path:
    """Write a GIF of the walker moving down its slope over the simulated steps.

    Frames are taken at real-time instants ``t₀ + k·Δ`` (the model's time unit counted as
    seconds; dimensionless for Garcia's simplest walker), where ``Δ`` is the frame delay the GIF
    actually stores — ``1/fps`` rounded down to whole centiseconds, as Pillow writes it (30 fps:
    30 ms) — so the GIF plays in real time.  If that needs more than ``max_frames`` frames the
    frames are spread evenly over the motion instead and the title says how much faster than real
    time it plays.  The view is fixed and wide enough for
    the whole motion; the ground is the line ``y = −x·tan(slope)`` through the first contact.

    Parameters
    ----------
    model : HybridModel
        The simulated model; every phase it passes through must have drawing ``points``.
    simulation : Simulation
        From :func:`gaitopt.simulate` (a few steps: 3–4 keep the GIF small).
    path : str or os.PathLike
        Output GIF; written whole or not at all (temporary file, then :func:`os.replace`).
    fps : int
        Frames per second of playback, 1 to 50 (GIF viewers slow down shorter delays).
    max_frames : int
        Upper bound on the number of frames (~150 frames at 100 dpi is about 1 MB).
    dpi : int
        Resolution (the figure is 6 × 3.2 inches: 600 × 320 pixels at 100 dpi).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    GaitoptInputError
        If a phase has no drawing points (Van der Pol), the simulation is empty, ``fps`` is not
        an integer in 1..50, or ``max_frames`` is not an integer ≥ 2.
    """
    if int(fps) != fps or not 1 <= fps <= 50:
        raise GaitoptInputError(f"`fps` must be an integer from 1 to 50, got {fps!r}")
    if int(max_frames) != max_frames or max_frames < 2:
        raise GaitoptInputError(f"`max_frames` must be an integer ≥ 2, got {max_frames!r}")
    _check_drawable(model, simulation)
    path = Path(path)
    t0, t1 = simulation.arcs[0].t0, simulation.arcs[-1].t1
    delay = int(1000 / fps) // 10 / 100  # s: PillowWriter's ms, stored by GIF in centiseconds
    real_time = t0 + delay * np.arange(int(math.floor((t1 - t0) / delay)) + 1)
    if len(real_time) <= max_frames:
        times, speed = real_time, 1.0
    else:
        times = np.linspace(t0, t1, int(max_frames))
        speed = (times[1] - times[0]) / delay
    frames = walker_frames(model, simulation, times)

    # A fixed view around everything drawn.
    allxy = np.hstack([f["outline"] for f in frames] + [f["mass"] for f in frames])
    xmin, xmax = np.nanmin(allxy[0]), np.nanmax(allxy[0])
    ymin, ymax = np.nanmin(allxy[1]), np.nanmax(allxy[1])
    pad = 0.12 * max(xmax - xmin, ymax - ymin)
    xmin, xmax, ymin, ymax = xmin - pad, xmax + pad, ymin - pad, ymax + pad
    slope = model.ground_slope()  # rad; 0 (level) for a model without a slope
    ground = on_ground(model)
    if not ground:
        # A scene without ground is tall and narrow (a ball above its paddle): widen the view to
        # about the axes' shape in the 6 × 3.2 in frame (height/width ≈ 0.45) rather than leave
        # the axes a thin strip.
        width = max(xmax - xmin, (ymax - ymin) / 0.45)
        xmid = 0.5 * (xmin + xmax)
        xmin, xmax = xmid - 0.5 * width, xmid + 0.5 * width

    fig, ax = plt.subplots(figsize=(6.0, 3.2), layout="constrained")
    if ground:
        ax.set_xlabel("distance along the ground x (m)", fontsize=8)
        ground_x = np.array([xmin - 1.0, xmax + 1.0])
        ground_y = -ground_x * math.tan(slope)
        ax.fill_between(ground_x, ground_y, ymin - 10.0, color="0.85", zorder=0)
        ax.plot(ground_x, ground_y, color="0.3", lw=1.2, zorder=1)
    else:
        ax.set_xlabel("horizontal position x (m)", fontsize=8)
    ax.set_ylabel("height y (m)", fontsize=8)
    (body,) = ax.plot([], [], color="C0", lw=3, solid_capstyle="round", zorder=3)
    (mass,) = ax.plot([], [], "o", color="C3", ms=9 if ground else 7, zorder=4)
    (steps,) = ax.plot([], [], "^", color="k", ms=4, zorder=2)
    clock = ax.text(0.02, 0.95, "", transform=ax.transAxes, va="top", fontsize=9)
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=7)
    pace = "real time" if speed == 1.0 else f"{speed:.2g}× real time"
    if ground:
        where = f"slope {slope:.3g} rad" if slope else "level ground"
        ax.set_title(f"{model.title or model.name}, {where}; {pace}", fontsize=10)
    else:
        ax.set_title(f"{model.title or model.name}; {pace}", fontsize=10)

    def draw(k: int):
        frame = frames[k]
        body.set_data(frame["outline"][0], frame["outline"][1])
        mass.set_data(frame["mass"][0], frame["mass"][1])
        if ground:  # footholds; a scene without ground has none to mark
            contacts = np.unique(np.array([f["contact"] for f in frames[: k + 1]]), axis=0)
            steps.set_data(contacts[:, 0], contacts[:, 1])
        clock.set_text(f"t = {times[k]:.2f} {'s' if model.time_unit == 's' else '(dimensionless)'}")
        return body, mass, steps, clock

    # Lay the figure out once (every frame has the same labels and ticks), then freeze it: a
    # constrained layout redone for each frame measures all its text again (most of the time).
    draw(0)
    fig.canvas.draw()
    fig.set_layout_engine("none")
    animation = FuncAnimation(fig, draw, frames=len(frames), blit=False)
    try:
        with replaced_atomically(path, ".gif") as tmp:  # Pillow picks the format from the suffix
            animation.save(tmp, writer=PillowWriter(fps=int(fps)), dpi=dpi)
    finally:
        plt.close(fig)
    return path
