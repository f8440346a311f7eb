"""The stance of a point mass on a massless leg, in polar coordinates about the foot.

The SLIP (Blickhan 1989; Tedrake, *Underactuated Robotics*, SLIP), its two-legged runner, its
actuated variant and Srinivasan & Ruina's minimal biped (2006) share one stance: the hip, a point
mass ``m``, at distance ``r`` from the foot and angle ``θ`` from vertical (positive with the hip
ahead of the foot), pushed along the leg by a force ``F`` (N)::

    r̈ = r θ̇² − g cos θ + F/m,        θ̈ = (g sin θ − 2 ṙ θ̇) / r

(a central force: no torque about the foot).  They differ only in ``F``: a spring ``k (l0 − r)``
(the SLIP), a spring and an actuator in parallel, or an actuator alone.  This module holds the
pieces each writes the same way; every piece returns the expressions the models wrote by hand.

* :func:`polar_flow` — the equations above, for any leg force.
* :func:`liftoff` — the leg regains a length, extending, moving forwards: Cartesian flight state
  with ``x`` from the foot.
* :func:`spring_stance` — the SLIP's stance phase (spring leg, its falls and its condition).
* :func:`foot_stance` — the stance of a leg that carries a force profile and may not pull, drawn
  with the next foothold (the optimisers' runners).
* :func:`leg_in_flight` — the drawing of a flight: hip, the foot of the leg held at an angle,
  and the point on the ground below the hip.
* :func:`flight_to_foothold` — a ballistic flight ending where the hip comes within a leg length
  of the next foothold ``(d, 0)`` (Srinivasan & Ruina's touchdown).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import casadi as ca

from ..hybrid import Constraint, Phase, Symbols, Transition
from .blocks import ballistic_flow, fall, hip_about_foot
from .quantities import state_units

__all__ = [
    "STANCE",
    "FLIGHT",
    "UNITS",
    "polar_flow",
    "liftoff",
    "spring_stance",
    "foot_stance",
    "flight_to_foothold",
    "next_foot",
    "leg_in_flight",
    "leg_power",
]

#: Stance state: polar coordinates of the hip about the foot.
STANCE = ("r", "theta", "r_dot", "theta_dot")
#: Flight state: the hip's Cartesian coordinates.
FLIGHT = ("x", "z", "x_dot", "z_dot")
#: Units of both (for axis labels).
UNITS = {**state_units(x="m", z="m"), **state_units(r="m", theta="rad")}
_HIP_ABOVE = "the body cannot go below the ground"


def polar_flow(sym: Symbols, xs: ca.SX, gravity: ca.SX, radial: ca.SX) -> ca.Function:
    """``flow(x, u, p)`` of the stance ``(r, θ, ṙ, θ̇)``: ``r̈ = r θ̇² − g cos θ + a``,
    ``θ̈ = (g sin θ − 2 ṙ θ̇)/r``, with ``a`` = ``radial`` (m/s²), the leg force per unit mass."""
    r, th, r_dot, th_dot = (xs[i] for i in range(4))
    return sym.function(
        "flow",
        xs,
        ca.vertcat(
            r_dot,
            th_dot,
            r * th_dot**2 - gravity * ca.cos(th) + radial,  # centripetal, gravity, leg force
            (gravity * ca.sin(th) - 2 * r_dot * th_dot) / r,  # no torque about the foot
        ),
    )


def liftoff(
    sym: Symbols,
    xs: ca.SX,
    length: ca.SX,
    *,
    name: str,
    target: int,
    doc: str,
    ground: ca.SX | None = None,
) -> Transition:
    """The leg regains ``length`` (m), ``r = length`` rising, with the hip moving forwards; the
    flight state is the hip's ``(x, z, ẋ, ż)`` with ``x`` from the foot and ``z`` above
    ``ground`` (m; the foot's level when None)."""
    hip_x, hip_z, hip_xd, hip_zd = hip_about_foot(*(xs[i] for i in range(4)))
    if ground is not None:
        hip_z = ground + hip_z
    return Transition(
        name=name,
        guard=sym.function("guard", xs, xs[0] - length),
        direction=+1,
        reset=sym.function("reset", xs, ca.vertcat(hip_x, hip_z, hip_xd, hip_zd)),
        target=target,
        admissible=sym.function("admissible", xs, hip_xd),  # moving forwards
        impact=False,
        doc=doc,
    )


def spring_stance(
    sym: Symbols,
    *,
    stiffness: ca.SX,
    rest_length: ca.SX,
    target: int,
    leg: str = "",
    ground: ca.SX | None = None,
) -> Phase:
    """The SLIP's stance on a massless spring leg ``k (l0 − r)`` (Tedrake's stance equations),
    ending at lift-off (``r = l0`` extending, into phase ``target``) or in a fall: lifting off
    moving backwards, the leg stopping (``θ̇ = 0``), the hip reaching the foot's level.

    Parameters
    ----------
    sym : Symbols
        The model's symbols (``mass``, ``gravity``).
    stiffness, rest_length : casadi.SX
        ``k`` (N/m) and ``l0`` (m).
    target : int
        The flight phase after lift-off.
    leg : str
        The leg's name in outcomes (``"A"``: "liftoff A", "leg A pulls"); "" for a one-legged
        runner.
    ground : casadi.SX, optional
        Height of the foot's ground (m) in the flight and energy's ``z``; 0 when None.
    """
    m, g, k, l0 = sym.mass, sym.gravity, stiffness, rest_length
    tag = f" {leg}" if leg else ""
    the_leg, the_foot = (f"leg {leg}", f"foot {leg}") if leg else ("the leg", "the foot")
    xs, (r, th, r_dot, th_dot) = sym.states(*STANCE)
    hip_x, hip_above_foot, hip_xd, _ = hip_about_foot(r, th, r_dot, th_dot)
    hip_z = hip_above_foot if ground is None else ground + hip_above_foot
    lift = liftoff(
        sym,
        xs,
        l0,
        name=f"liftoff{tag}",
        target=target,
        ground=ground,
        doc=f"{the_leg} regains its rest length, r = l0, extending, moving forwards; Cartesian "
        f"flight state with x from {the_foot}",
    )
    falls = (
        fall(
            sym,
            xs,
            f"falls back (lifts off{' leg' + tag if leg else ''} moving backwards)",
            r - l0,
            "liftoff with the hip moving backwards: too little forward energy",
            direction=+1,
            admissible=-hip_xd,
        ),
        fall(
            sym,
            xs,
            f"falls back ({'leg' + tag if leg else 'stance leg'} stops rotating)",
            th_dot,
            "θ̇ falls through 0 in stance: too little forward energy to vault over the foot",
        ),
        fall(
            sym,
            xs,
            "falls (hip reaches the ground in stance)",
            hip_above_foot,
            "the hip reaches the foot's level",
        ),
    )
    energy = 0.5 * m * (r_dot**2 + r**2 * th_dot**2) + m * g * hip_z + 0.5 * k * (l0 - r) ** 2
    # The massless spring leg can only push: its force k (l0 − r) ≥ 0 (zero at touchdown and
    # at liftoff, where r = l0: it must compress at once after touchdown).
    compressed = sym.constraint(
        f"leg{tag} force compressive",
        xs,
        k * (l0 - r),
        f"leg{tag} pulls",
        at_start=True,
        at_end=True,
        unit="N",
        source="a massless spring leg on the ground can only push (Blickhan 1989)",
    )
    return Phase(
        f"stance{tag}",
        STANCE,
        polar_flow(sym, xs, g, k / m * (l0 - r)),
        (lift, *falls),
        {"energy": sym.conserved("energy", xs, energy)},
        points=ca.Function(
            "points",
            [xs, sym.p],
            [ca.horzcat(ca.vertcat(hip_x, hip_above_foot), ca.DM.zeros(2, 1))],
        ),
        point_names=("hip", "foot"),
        constraints=(compressed,),
    )


def leg_in_flight(
    sym: Symbols, xf: ca.SX, length: ca.SX, angle: ca.SX, ground: ca.SX | None = None
) -> ca.Function:
    """``points(x, p)`` (m) of a flight ``(x, z, ẋ, ż)``: the hip, the foot of a leg of
    ``length`` held at ``angle`` from vertical (ahead of the hip), and the ground below the hip;
    heights above ``ground`` (above ``z = 0`` when None)."""
    x, z = xf[0], xf[1]
    if ground is None:
        hip, below = ca.vertcat(x, z), ca.vertcat(x, 0)
        foot = ca.vertcat(x + length * ca.sin(angle), z - length * ca.cos(angle))
    else:
        hip, below = ca.vertcat(x, z - ground), ca.vertcat(x, -ground)
        foot = ca.vertcat(x + length * ca.sin(angle), z - ground - length * ca.cos(angle))
    return ca.Function("points", [xf, sym.p], [ca.horzcat(hip, foot, below)])


def next_foot(sym: Symbols) -> ca.SX:
    """The next foothold, ``(d, 0)`` from the stance foot (m; ``d`` the parameter
    ``step_length``)."""
    return ca.vertcat(sym.step_length, 0)


def _hip_and_feet(sym: Symbols, x: ca.SX, hip: ca.SX, velocity: ca.SX) -> dict:
    """Drawing points (stance foot at the origin, hip, next foot) and the body ``(m, r, v)``."""
    return {
        "points": ca.Function(
            "points", [x, sym.p], [ca.horzcat(ca.DM.zeros(2, 1), hip, next_foot(sym))]
        ),
        "point_names": ("foot", "hip", "next_foot"),
        "bodies": ca.Function(
            "bodies", [x, sym.p], [sym.mass, hip, velocity], ["x", "p"], ["m", "r", "v"]
        ),
    }


def _hip_above(sym: Symbols, x: ca.SX, height: ca.SX) -> Constraint:
    return sym.constraint(
        "hip above the ground", x, height, "hip reaches the ground", unit="m", source=_HIP_ABOVE
    )


def foot_stance(
    sym: Symbols,
    closing: Transition,
    *,
    leg_force: Callable[[ca.SX], ca.SX],
    push_source: str,
    falls_back: tuple[str, str],
    spring_energy: Callable[[ca.SX], ca.SX] | None = None,
    conditions: Sequence[Callable[[ca.SX, ca.SX], Constraint]] = (),
) -> Phase:
    """The stance about the foot of a leg that carries a force (it may not pull), ending with
    ``closing`` or falling back (``θ̇`` falls through 0); drawn with the next foothold.

    Parameters
    ----------
    sym : Symbols
        The model's symbols (``mass``, ``gravity``, ``step_length``).
    closing : Transition
        The stance's end (heel strike, lift-off).
    leg_force : callable
        ``leg_force(r)`` (N) of the leg length ``r``: the force along the leg, which may not
        pull (the declared condition "leg pushes", from ``push_source``).
    falls_back : (str, str)
        Name and doc of the fall back.
    spring_energy : callable, optional
        ``spring_energy(r)`` (J) added to the energy.
    conditions : sequence of callables
        ``condition(xs, r)`` of the stance state and the leg length: further declared
        conditions, after "leg pushes".

    Returns
    -------
    Phase
        ``"stance"``, state :data:`STANCE`.
    """
    m, g = sym.mass, sym.gravity
    xs, (r, th, r_dot, th_dot) = sym.states(*STANCE)
    push = leg_force(r)
    hip_x, hip_z, hip_xd, hip_zd = hip_about_foot(r, th, r_dot, th_dot)
    energy = 0.5 * m * (r_dot**2 + r**2 * th_dot**2) + m * g * hip_z
    if spring_energy is not None:
        energy = energy + spring_energy(r)
    pushes = sym.constraint("leg pushes", xs, push, "leg pulls", unit="N", source=push_source)
    return Phase(
        "stance",
        STANCE,
        polar_flow(sym, xs, g, push / m),
        (closing, fall(sym, xs, falls_back[0], th_dot, falls_back[1])),
        {"energy": sym.conserved("energy", xs, energy)},  # constant where no work is done
        **_hip_and_feet(sym, xs, ca.vertcat(hip_x, hip_z), ca.vertcat(hip_xd, hip_zd)),
        constraints=(pushes, *(c(xs, r) for c in conditions), _hip_above(sym, xs, hip_z)),
    )


def flight_to_foothold(
    sym: Symbols,
    length: ca.SX,
    *,
    doc: str,
    conditions: Sequence[Callable[[ca.SX, ca.SX], Constraint]] = (),
) -> Phase:
    """A ballistic flight ``(x, z, ẋ, ż)``, ``x`` from the last stance foot, ending where the hip
    comes within ``length`` (m) of the next foothold ``(d, 0)``: ``(x − d)² + z² = length²``,
    approaching (Srinivasan & Ruina 2006), into the polar stance about the new foot.  The
    massless leg changes no velocity (``impact=False``); the hip stays above the ground.

    ``doc`` describes the touchdown; ``conditions`` are callables ``condition(xf, energy)`` of
    further declared conditions, given the flight state and its energy (J).
    """
    m, g, d = sym.mass, sym.gravity, sym.step_length
    xf, (x, z, x_dot, z_dot) = sym.states(*FLIGHT)
    dx = x - d
    dist2 = dx**2 + z**2
    rr = ca.sqrt(dist2)
    touchdown = Transition(
        name="touchdown",
        guard=sym.function("guard", xf, length**2 - dist2),
        direction=+1,
        reset=sym.function(
            "reset",
            xf,
            ca.vertcat(
                rr,
                ca.atan2(dx, z),
                (dx * x_dot + z * z_dot) / rr,
                (z * x_dot - dx * z_dot) / dist2,
            ),
        ),
        target=0,
        admissible=sym.function("admissible", xf, z),  # the hip above the new foot's level
        impact=False,  # a massless leg: the velocity is only re-expressed
        foothold="next_foot",
        doc=doc,
    )
    energy = 0.5 * m * (x_dot**2 + z_dot**2) + m * g * z
    return Phase(
        "flight",
        FLIGHT,
        ballistic_flow(sym, xf, g, vertical=1),
        (touchdown, fall(sym, xf, "falls (hip reaches the ground in flight)", z, "z = 0")),
        {"energy": sym.conserved("energy", xf, energy)},
        **_hip_and_feet(sym, xf, ca.vertcat(x, z), ca.vertcat(x_dot, z_dot)),
        constraints=(_hip_above(sym, xf, z), *(c(xf, energy) for c in conditions)),
    )


def leg_power(n_params: int, stance: bool) -> ca.Function:
    """``input_rates(x, p)``: the leg force's power per unit force, ``ṙ`` (m/s), in the stance
    (``x[2]``), 0 in flight; with the force, ``F ṙ`` (W)."""
    x = ca.SX.sym("x", 4)
    p = ca.SX.sym("p", n_params)
    rate = x[2] if stance else ca.SX(0)
    return ca.Function("input_rates", [x, p], [rate], ["x", "p"], ["rates"])
