"""Building blocks shared by the models: falls, ballistic flight, a leg's touchdown, the apex.

Each block returns the same CasADi expressions a model would write by hand, so a model that uses
one reads like its paper and computes exactly what it computed before.

* :func:`fall` — a terminal transition (the motion ends: a fall, a trip, no apex).
* :func:`ballistic_flow` — free flight under gravity, ``q̈ = −g ŷ`` (SLIP, hoppers).
* :func:`leg_touchdown` — a massless leg of length ``l`` placed at angle ``θ`` from vertical
  meets the ground: guard ``z − l cos θ`` falling, reset to polar coordinates of the hip about
  the foot (Blickhan 1989; Raibert 1986, ch. 2).
* :func:`hip_about_foot` — the inverse map at liftoff: the hip's Cartesian position and
  velocity from its polar coordinates about the foot.
* :func:`apex` — the top of a flight, ``ż = 0`` falling: the Poincaré section of the runners
  and hoppers (Tedrake, *Underactuated Robotics*, "Simple models of walking and running").
* :func:`bar_and_ball_points` — the drawing of a ball above a level bar (the bouncing ball's
  table, the line juggler's paddle).

Gravity itself is one parameter declaration for every model,
:func:`gaitopt.parameters.gravity_parameter`.
"""

from __future__ import annotations

import casadi as ca

from ..hybrid import Symbols, Transition

__all__ = [
    "fall",
    "ballistic_flow",
    "leg_touchdown",
    "hip_about_foot",
    "apex",
    "bar_and_ball_points",
]


def fall(
    sym: Symbols,
    x: ca.SX,
    name: str,
    guard: ca.SX,
    doc: str,
    *,
    direction: int = -1,
    admissible: ca.SX | None = None,
) -> Transition:
    """A terminal transition: the motion ends when ``guard`` crosses zero in ``direction``.

    Parameters
    ----------
    sym : Symbols
        The model's symbols.
    x : casadi.SX
        The phase's state vector.
    name : str
        What happens (the simulation's outcome, e.g. ``"falls (hip reaches the ground)"``).
    guard : casadi.SX
        Expression of ``x`` (and parameters) that crosses zero at the fall.
    doc : str
        The condition in words.
    direction : int
        ``-1`` (default): falling through zero; ``+1``: rising.
    admissible : casadi.SX, optional
        The crossing counts only where this is positive.

    Returns
    -------
    Transition
        With no reset and no target.
    """
    return Transition(
        name=name,
        guard=sym.function("guard", x, guard),
        direction=direction,
        reset=None,
        target=None,
        admissible=None if admissible is None else sym.function("admissible", x, admissible),
        doc=doc,
    )


def ballistic_flow(sym: Symbols, x: ca.SX, gravity: ca.SX, vertical: int) -> ca.Function:
    """Free flight of a rigid body: ``ẋ = (q̇, q̈)`` with ``q̈ = −g`` along the vertical
    coordinate and 0 along the others.

    Parameters
    ----------
    sym : Symbols
        The model's symbols.
    x : casadi.SX
        State ``(q, q̇)``: the ``n`` coordinates (m or rad), then their rates in the same order.
    gravity : casadi.SX
        ``g`` (m/s²).
    vertical : int
        Index in ``q`` of the height (m, up).

    Returns
    -------
    casadi.Function
        ``flow(x, u, p) -> ẋ``.
    """
    n = x.numel() // 2
    rates = [x[n + i] for i in range(n)]
    accelerations = [-gravity if i == vertical else 0 for i in range(n)]
    return sym.function("flow", x, ca.vertcat(*rates, *accelerations))


def leg_touchdown(
    sym: Symbols,
    x: ca.SX,
    *,
    height: ca.SX,
    velocity: tuple[ca.SX, ca.SX],
    length: ca.SX,
    angle: ca.SX,
    carried: tuple[tuple[ca.SX, ...], tuple[ca.SX, ...]] = ((), ()),
    impact: bool = True,
    doc: str,
) -> Transition:
    """A massless leg held at ``angle`` θ from vertical (foot ahead of the hip for θ > 0)
    touches the ground: ``height − length·cos θ`` falls through zero.

    The reset gives the stance state in polar coordinates of the hip about the foot, which is
    ``(dx, dz) = (−l sin θ, height)`` away from it: ``r = |(dx, dz)|``, ``θ_s = atan2(dx, dz)``
    (from vertical, positive with the hip ahead of the foot, so ``θ_s = −θ``), ``ṙ = (dx ẋ +
    dz ż)/r``, ``θ̇_s = (dz ẋ − dx ż)/r²`` (Blickhan 1989; Tedrake, SLIP).

    Parameters
    ----------
    sym : Symbols
        The model's symbols.
    x : casadi.SX
        The flight state vector.
    height : casadi.SX
        Hip height above the ground under the foot (m).
    velocity : (casadi.SX, casadi.SX)
        Hip velocity ``(ẋ, ż)`` (m/s).
    length : casadi.SX
        Leg length ``l`` at touchdown (m).
    angle : casadi.SX
        Leg angle ``θ`` from vertical (rad).
    carried : (tuple, tuple)
        Further coordinates and rates carried over unchanged (the Raibert hopper's pitch):
        the stance state is ``(r, θ_s, *coordinates, ṙ, θ̇_s, *rates)``.
    impact : bool
        Whether the touchdown is an impact (False for a massless leg that changes no
        velocity).
    doc : str
        The transition in words.

    Returns
    -------
    Transition
        Into phase 1 (stance), with foothold ``"foot"``.
    """
    x_dot, z_dot = velocity
    dx, dz = -length * ca.sin(angle), height  # hip relative to the foot
    polar = (ca.sqrt(dx**2 + dz**2), ca.atan2(dx, dz))
    polar_rates = (
        (dx * x_dot + dz * z_dot) / ca.sqrt(dx**2 + dz**2),
        (dz * x_dot - dx * z_dot) / (dx**2 + dz**2),
    )
    coordinates, rates = carried
    return Transition(
        name="touchdown",
        guard=sym.function("guard", x, height - length * ca.cos(angle)),
        direction=-1,
        reset=sym.function("reset", x, ca.vertcat(*polar, *coordinates, *polar_rates, *rates)),
        target=1,
        impact=impact,
        foothold="foot",
        doc=doc,
    )


def hip_about_foot(
    r: ca.SX, theta: ca.SX, r_dot: ca.SX, theta_dot: ca.SX
) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
    """The hip's position ``(r sin θ, r cos θ)`` (m) and velocity (m/s) relative to the foot,
    from its polar coordinates about the foot (``θ`` from vertical, positive with the hip
    ahead)."""
    return (
        r * ca.sin(theta),
        r * ca.cos(theta),
        r_dot * ca.sin(theta) + r * theta_dot * ca.cos(theta),
        r_dot * ca.cos(theta) - r * theta_dot * ca.sin(theta),
    )


def apex(
    sym: Symbols,
    x: ca.SX,
    vertical_rate: ca.SX,
    reset: ca.SX,
    *,
    foothold: str | None = None,
    doc: str,
) -> Transition:
    """The top of a flight: ``vertical_rate`` (m/s) falls through zero; no impact.

    Parameters
    ----------
    sym : Symbols
        The model's symbols.
    x : casadi.SX
        The flight state vector.
    vertical_rate : casadi.SX
        ``ż`` (m/s).
    reset : casadi.SX
        The state after the apex (e.g. the horizontal position measured from here on).
    foothold : str, optional
        Point name of the next contact for drawing (the point below the hip).
    doc : str
        The transition in words.

    Returns
    -------
    Transition
        Into phase 0, where the section lies.
    """
    return Transition(
        name="apex",
        guard=sym.function("guard", x, vertical_rate),
        direction=-1,
        reset=sym.function("reset", x, reset),
        target=0,
        impact=False,
        foothold=foothold,
        doc=doc,
    )


def bar_and_ball_points(
    sym: Symbols, x: ca.SX, *, bar: ca.SX, ball: ca.SX, half_width: float
) -> ca.Function:
    """Drawing points (m) of a ball above a level bar: the bar's left end ``(−w, bar)``, its right
    end ``(w, bar)`` and the ball ``(0, ball)``, so that the drawn gap is ``ball − bar``.

    Parameters
    ----------
    sym : Symbols
        The model's symbols.
    x : casadi.SX
        The phase's state vector.
    bar, ball : casadi.SX
        Heights (m) of the bar and of the ball.
    half_width : float
        Half the bar's drawn width ``w`` (m).

    Returns
    -------
    casadi.Function
        ``points(x, p) -> 2×3``.
    """
    return ca.Function(
        "points",
        [x, sym.p],
        [
            ca.horzcat(
                ca.vertcat(-half_width, bar),
                ca.vertcat(half_width, bar),
                ca.vertcat(0, ball),
            )
        ],
    )
