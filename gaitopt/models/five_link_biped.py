"""The five-link biped: a planar walker with a torso, knees and point feet, driven by four torques.

The model of Kelly's OptimTraj (``demo/fiveLinkBiped``: ``Derive_Equations.m``,
``getPhysicalParameters.m``, ``heelStrikeMap.m``, ``MAIN.m``; Kelly 2017, "An introduction to
trajectory optimization: how to do your own direct collocation", SIAM Review 59(4), appendix), with
OptimTraj's own parameter set.  OptimTraj's parameter file calls it RABBIT (after Westervelt,
Grizzle & Koditschek 2003) but its values are its own and differ from FROST's RABBIT model; they
are pinned here as OptimTraj states them.  The inertias are about each link's centre of mass and
are large for the links' lengths (the shank's radius of gyration √(0.93/3.2) = 0.54 m exceeds its
0.4 m length); they are kept as published.

**Links and angles** (OptimTraj's numbering and convention).  Links 1–5: stance shank (tibia),
stance thigh (femur), torso, swing thigh, swing shank.  Every angle ``q_k`` is *absolute*, from
the vertical, *positive counter-clockwise* (the walker walks towards +x, so a positive stance-leg
angle leans it back): a link at angle ``q`` has the upward unit vector ``e(q) = (−sin q, cos q)``
along it (from its lower to its upper end), and ``q = 0`` everywhere is the walker standing
straight with the torso upright.  OptimTraj's ``e1 = cos(q1) j − sin(q1) i`` (stance foot → stance
knee), ``e2`` (knee → hip), ``e3`` (hip → shoulders) are ``e(q)``; its ``e4``, ``e5`` (hip → swing
knee → swing foot) are ``−e(q)``.  So one angle names one orientation of the line of a link,
whichever leg it belongs to, and relabelling the legs only permutes the angles.

**Geometry** (positions relative to the stance foot ``P0``, world frame, y up)::

    stance knee P1 = l_s e(q1)            torso top P3 = P2 + l_T e(q3)
    hip         P2 = P1 + l_t e(q2)       swing knee P4 = P2 − l_t e(q4)
                                          swing foot P5 = P4 − l_s e(q5)

with shank, thigh and torso lengths ``l_s, l_t, l_T``.  Centres of mass, each ``c`` from the
link's *upper* end (as ``Derive_Equations.m`` places them: ``G1 = P1 − c1 e1``, ``G2 = P2 − c2 e2``,
``G3 = P3 − c3 e3``, ``G4 = P2 + c4 e4``, ``G5 = P4 + c5 e5``; its comment "distance between parent
joint and CoM" holds for the legs, whose parent joint is the upper one, but the torso's ``c3`` is
measured down from the top of the torso)::

    G1 = P1 − c_s e(q1),  G2 = P2 − c_t e(q2),  G3 = P3 − c_T e(q3),
    G4 = P2 − c_t e(q4),  G5 = P4 − c_s e(q5).

The legs are identical (OptimTraj's ``m1 = m5``, ``m2 = m4``, …), which the relabelling at heel
strike needs.

**Dynamics.**  Each link is a rigid body (mass ``m``, inertia ``I`` about ``G``):
``T = Σ ½ m_k |Ġ_k|² + ½ I_k q̇_k²``, ``V = Σ m_k g G_k,y``.  Lagrange's equations ``M(q) q̈ =
Q − C(q, q̇) q̇ − ∂V/∂q`` follow by AD (:mod:`gaitopt.mechanics`; each link enters as its two-point
equimomental system, :func:`~gaitopt.mechanics.rigid_link`, which has the same ``T`` and ``V``).
OptimTraj derives the same equations differently, by angular-momentum balances about ``P0``, the
stance knee, the hip (twice) and the swing knee; the tests check the two agree.

**Torques** (OptimTraj's ``u2 … u5``; its ``u1``, the stance ankle, is disabled in ``MAIN.m``,
bounds 0 ≤ u1 ≤ 0, and absent here).  ``u_k`` is the torque that link ``k − 1`` exerts on link
``k``, counter-clockwise positive (and ``−u_k`` on link ``k − 1``; link 4's parent is the torso)::

    stance_knee_torque  u2: stance shank → stance thigh     power u2 (q̇2 − q̇1)
    stance_hip_torque   u3: stance thigh → torso            power u3 (q̇3 − q̇2)
    swing_hip_torque    u4: torso → swing thigh             power u4 (q̇4 − q̇3)
    swing_knee_torque   u5: swing thigh → swing shank       power u5 (q̇5 − q̇4)

so the generalised forces are ``Q = (−u2, u2 − u3, u3 − u4, u4 − u5, u5)`` and
``dE/dt = Σ u_k (q̇_k − q̇_{k−1})`` (the tests check this power balance).

**Heel strike** (OptimTraj's ``heelStrikeMap.m`` / ``cst_heelStrike``).  The guard is the swing
foot's height above the ground line ``y = −x tan γ`` (γ = ``slope``, 0 in OptimTraj),
``h = n·P5 = l_s cos(q1 + γ) + l_t cos(q2 + γ) − l_t cos(q4 + γ) − l_s cos(q5 + γ)`` with
``n = (sin γ, cos γ)``, decreasing through 0, admissible only with the swing foot ahead of the
stance foot (``t·P5 > 0``, ``t = (cos γ, −sin γ)``): a touchdown behind and the start of a step
(where the trailing foot leaves the ground, ``h = 0`` behind) are excluded.  The impact is
plastic at the swing foot, the old stance foot leaving the ground without impulse
(:func:`~gaitopt.mechanics.impact_velocity`, the floating-base method): it conserves the angular
momentum of the whole walker about the striking foot, of links 2–5 about the stance knee and so
on out to the swing shank about the swing knee — the five balances ``heelStrikeMap.m`` solves.
Then the legs swap: ``(q1, …, q5)⁺ = (q5, q4, q3, q2, q1)`` and likewise the rates.

OptimTraj also requires (``autoGen_cst_footVel``) the swing foot to move *down* just before heel
strike and the new swing foot to move *up* just after it; here both are the guard's rate
``ḣ = ∇h · ẋ`` (it depends on ``q̇`` only): ``ḣ(x⁻) < 0`` and ``ḣ(x⁺) > 0`` at the post-impact
state (the tests check the signs at a constructed impact).  The first is the guard's direction
(heel strike fires only on a downward crossing); the second is the ``at_start`` rule of the
unilateral constraint *swing foot above the ground* (``h ≥ 0`` throughout the step, which also
forbids a mid-swing scuff; OptimTraj imposes no clearance along the step).  A second constraint
requires the stance foot to push, ``N = n · Σ m_i (r̈_i + g ŷ) ≥ 0``; friction is not modelled.
The joint limits (OptimTraj's bounds, declared below) and OptimTraj's optional knee limits
(:attr:`FiveLinkBiped.knee_flexion`, the phase's limit ``"knee_flexion"``) are not imposed by
the model: they are an optimiser's, the knee limits on request.

**Exits** (terminal): a *fall*, the hip reaching the ground line (``n·P2`` falling through 0);
a *torso fall*, the torso reaching horizontal (``cos q3`` falling through 0, the edge of
OptimTraj's ``|q| ≤ π/2``).

**Section:** just after heel strike, the new swing foot on the ground behind the stance foot:
``h = 0`` fixes ``swing_shank`` from the other angles, on the branch with the foot behind its
knee, ``q5 = −γ − arccos((l_s cos(q1 + γ) + l_t cos(q2 + γ) − l_t cos(q4 + γ)) / l_s)``; free
coordinates the four other angles and all five rates (9).

**No passive gait.**  On level ground the plastic impacts dissipate energy and nothing supplies it,
so no passive (``u = 0``) gait exists; down a slope the free stance knee and the torso on its hip
are unactuated inverted pendulums, and no passive gait of this walker is known.  The model is
actuated-only (:attr:`passive_gait` False): its gaits come from trajectory optimisation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import casadi as ca

from ..errors import ParameterError
from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..mechanics import (
    bodies_function,
    contact_force,
    impact_velocity,
    kinetic_energy,
    lagrange_acceleration,
    lagrange_terms,
    potential_energy,
    rigid_link,
)
from ..parameters import gravity_parameter, parameter
from .blocks import fall
from .quantities import length_parameter, mass_parameter, slope_parameter

__all__ = ["FiveLinkBiped"]

_OPTIMTRAJ = "OptimTraj demo/fiveLinkBiped getPhysicalParameters.m (Kelly 2017)"

#: The links, in OptimTraj's order 1–5 (names of the angles ``q1 … q5``).
LINK_NAMES = ("stance_shank", "stance_thigh", "torso", "swing_thigh", "swing_shank")
#: The state: the five absolute angles (rad), then their rates (rad/s).
STATE_NAMES = LINK_NAMES + tuple(f"{name}_dot" for name in LINK_NAMES)
#: Names of the drawing points (columns of ``Phase.points``).
POINT_NAMES = ("stance_foot", "stance_knee", "hip", "torso_top", "swing_knee", "swing_foot")
#: Order of the point masses in ``Phase.bodies``: each link (LINK_NAMES order) as two point masses
#: of its equimomental system (:func:`~gaitopt.mechanics.rigid_link`), ``+`` then ``−``.
BODY_NAMES = tuple(f"{link}{sign}" for link in LINK_NAMES for sign in ("+", "-"))
#: Generalised forces of the inputs: ``Q = B u`` with ``u = (u2, u3, u4, u5)`` (OptimTraj's
#: numbering): ``Q = (−u2, u2 − u3, u3 − u4, u4 − u5, u5)``.
INPUT_MATRIX = (
    (-1.0, 0.0, 0.0, 0.0),
    (1.0, -1.0, 0.0, 0.0),
    (0.0, 1.0, -1.0, 0.0),
    (0.0, 0.0, 1.0, -1.0),
    (0.0, 0.0, 0.0, 1.0),
)


def _mass(value: float, doc: str) -> Any:
    """A link mass (kg, in (0, 1e4]) from OptimTraj."""
    return mass_parameter(value, doc, _OPTIMTRAJ)


def _inertia(value: float, doc: str) -> Any:
    """A link's moment of inertia about its centre of mass (kg·m², in [0, 1e4]) from OptimTraj."""
    return parameter(value, unit="kg*m^2", doc=doc, source=_OPTIMTRAJ, low=0.0, high=1e4)


def _length(value: float, doc: str) -> Any:
    """A link length (m, in (0, 10]) from OptimTraj."""
    return length_parameter(value, doc, _OPTIMTRAJ)


def _com(value: float, doc: str) -> Any:
    """A centre-of-mass distance along a link (m, in [0, 10]) from OptimTraj."""
    return parameter(value, unit="m", doc=doc, source=_OPTIMTRAJ, low=0.0, high=10.0)


def _up(angle: ca.SX) -> ca.SX:
    """Unit vector along a link at absolute angle ``angle`` (counter-clockwise from vertical),
    from its lower to its upper end: ``(−sin q, cos q)`` (OptimTraj's ``e1``)."""
    return ca.vertcat(-ca.sin(angle), ca.cos(angle))


def _geometry(sym: Symbols, q: ca.SX) -> dict[str, ca.SX]:
    """Joints and centres of mass relative to the stance foot (OptimTraj's ``P`` and ``G``)."""
    ls, lt, lT = sym.length_shank, sym.length_thigh, sym.length_torso
    cs, ct, cT = sym.com_shank, sym.com_thigh, sym.com_torso
    e = [_up(q[k]) for k in range(5)]
    stance_knee = ls * e[0]
    hip = stance_knee + lt * e[1]
    torso_top = hip + lT * e[2]
    swing_knee = hip - lt * e[3]
    swing_foot = swing_knee - ls * e[4]
    return {
        "stance_foot": ca.SX.zeros(2, 1),
        "stance_knee": stance_knee,
        "hip": hip,
        "torso_top": torso_top,
        "swing_knee": swing_knee,
        "swing_foot": swing_foot,
        "coms": (
            stance_knee - cs * e[0],
            hip - ct * e[1],
            torso_top - cT * e[2],
            hip - ct * e[3],
            swing_knee - cs * e[4],
        ),
        "axes": tuple(e),
    }


def _masses(sym: Symbols, geo: dict[str, ca.SX]) -> list[tuple[ca.SX, ca.SX]]:
    """Each link's equimomental pair of point masses, in BODY_NAMES order."""
    masses = (sym.mass_shank, sym.mass_thigh, sym.mass_torso, sym.mass_thigh, sym.mass_shank)
    inertias = (
        sym.inertia_shank,
        sym.inertia_thigh,
        sym.inertia_torso,
        sym.inertia_thigh,
        sym.inertia_shank,
    )
    out: list[tuple[ca.SX, ca.SX]] = []
    for m, inertia, com, axis in zip(masses, inertias, geo["coms"], geo["axes"], strict=True):
        out.extend(rigid_link(m, com, axis, inertia))
    return out


@dataclass(frozen=True)
class FiveLinkBiped(HybridModel):
    """Five-link biped: states ``stance_shank, stance_thigh, torso, swing_thigh, swing_shank``
    (absolute angles, rad, counter-clockwise from vertical) and their ``*_dot`` rates (rad/s);
    inputs ``stance_knee_torque, stance_hip_torque, swing_hip_torque, swing_knee_torque`` (N·m).

    Declared limits (OptimTraj's ``MAIN.m`` bounds), for an optimiser to read:
    :attr:`torque_limit` ``|u_i| ≤ 100 N·m``, :attr:`angle_limit` ``|q_k| ≤ π/2 rad``,
    :attr:`rate_limit` ``|q̇_k| ≤ 10 rad/s``, and the same as ``(low, high)`` per name in
    :attr:`input_bounds` and :attr:`state_bounds`.  The step length is the ``swing_foot`` point's
    distance along the ground at heel strike (the ``stance_foot`` point is the origin).
    """

    name = "five_link_biped"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = STATE_NAMES
    declared_coordinates = tuple(n for n in STATE_NAMES if n != "swing_shank")
    declared_section_doc = (
        "just after heel strike: the swing foot on the ground behind the stance foot, swing_shank "
        "= −slope − arccos((l_s cos(stance_shank + slope) + l_t cos(stance_thigh + slope) − l_t "
        "cos(swing_thigh + slope)) / l_s)"
    )
    title = "Five-link biped"
    reference = "Kelly 2017 (SIAM Review 59(4)); OptimTraj demo/fiveLinkBiped"
    inputs = ("stance_knee_torque", "stance_hip_torque", "swing_hip_torque", "swing_knee_torque")
    input_units = ("N*m", "N*m", "N*m", "N*m")
    #: Absolute link angles (rad); their ``*_dot`` rates are rad/s (for labels).
    state_units = {q: "rad" for q in LINK_NAMES}
    mesh = (4, 5)
    passive_gait = False

    #: Bound on every joint torque, ``|u_i| ≤ torque_limit`` (N·m; OptimTraj ``MAIN.m`` uMax).
    torque_limit: ClassVar[float] = 100.0
    #: Bound on every absolute link angle, ``|q_k| ≤ angle_limit`` (rad; OptimTraj ``MAIN.m``).
    angle_limit: ClassVar[float] = math.pi / 2
    #: Bound on every absolute link rate, ``|q̇_k| ≤ rate_limit`` (rad/s; OptimTraj ``MAIN.m``).
    rate_limit: ClassVar[float] = 10.0
    #: ``{input name: (low, high)}`` (N·m): the declared input bounds.
    input_bounds: ClassVar[dict[str, tuple[float, float]]] = {
        name: (-100.0, 100.0) for name in inputs
    }
    #: ``{state name: (low, high)}`` (rad, rad/s): the declared state bounds.
    state_bounds: ClassVar[dict[str, tuple[float, float]]] = {
        **{name: (-math.pi / 2, math.pi / 2) for name in LINK_NAMES},
        **{f"{name}_dot": (-10.0, 10.0) for name in LINK_NAMES},
    }
    #: Names of the drawing points whose distance along the ground at heel strike is the step
    #: length (m): from ``stance_foot`` (the origin) to ``swing_foot``.
    step_points: ClassVar[tuple[str, str]] = ("stance_foot", "swing_foot")
    #: OptimTraj's optional knee joint limits (``pathConstraint.m``, ``c = (q1 − q2, q5 − q4) ≤ 0``;
    #: off in the 8c43235 logs, on in the later ``MAIN.m`` of a 0.5 m step in 0.7 s):
    #: ``{knee: (a, b)}`` meaning the flexion ``x[a] − x[b] ≥ 0`` (rad): the stance knee
    #: ``stance_thigh − stance_shank ≥ 0``, the swing knee ``swing_thigh − swing_shank ≥ 0``
    #: (a knee that does not hyper-extend).  Not physics, so not imposed by the model: the phase
    #: declares them as the limit ``"knee_flexion"`` (``Phase.limits``), which an optimiser
    #: imposes on request (``path_constraints=("knee_flexion",)``, ``--constrain knee_flexion``).
    knee_flexion: ClassVar[dict[str, tuple[str, str]]] = {
        "stance_knee": ("stance_thigh", "stance_shank"),
        "swing_knee": ("swing_thigh", "swing_shank"),
    }

    #: The plant for a virtual-constraint controller (:mod:`gaitopt.hzd`): :meth:`manipulator`
    #: is its open loop in the four torques; outputs on the four links other than the stance
    #: shank, phase variable the stance leg's mean angle (q1 + q2)/2 (decreasing over a step).
    actuated_coordinates: ClassVar[tuple[str, ...]] = (
        "stance_thigh",
        "torso",
        "swing_thigh",
        "swing_shank",
    )
    phase_variable: ClassVar[dict[str, float]] = {"stance_shank": 0.5, "stance_thigh": 0.5}
    plant_parameters: ClassVar[tuple[str, ...]] = (
        "mass_shank",
        "mass_thigh",
        "mass_torso",
        "inertia_shank",
        "inertia_thigh",
        "inertia_torso",
        "length_shank",
        "length_thigh",
        "length_torso",
        "com_shank",
        "com_thigh",
        "com_torso",
        "gravity",
        "slope",
    )

    mass_shank: float = _mass(3.2, "shank (tibia) mass m1 = m5")
    mass_thigh: float = _mass(6.8, "thigh (femur) mass m2 = m4")
    mass_torso: float = _mass(20.0, "torso mass m3")
    inertia_shank: float = _inertia(
        0.93, "shank moment of inertia about its centre of mass I1 = I5"
    )
    inertia_thigh: float = _inertia(
        1.08, "thigh moment of inertia about its centre of mass I2 = I4"
    )
    inertia_torso: float = _inertia(2.22, "torso moment of inertia about its centre of mass I3")
    length_shank: float = _length(0.4, "shank length l1 = l5 (foot to knee)")
    length_thigh: float = _length(0.4, "thigh length l2 = l4 (knee to hip)")
    length_torso: float = _length(0.625, "torso length l3 (hip to top)")
    com_shank: float = _com(
        0.128, "shank centre of mass below the knee c1 = c5 (at most the shank length)"
    )
    com_thigh: float = _com(
        0.163, "thigh centre of mass below the hip c2 = c4 (at most the thigh length)"
    )
    com_torso: float = _com(
        0.2, "torso centre of mass below the top of the torso c3 (at most the torso length)"
    )
    gravity: float = gravity_parameter(_OPTIMTRAJ)
    slope: float = slope_parameter(
        0.0,
        "level ground, as in OptimTraj",
        (-0.5, 0.5),
        doc="ground slope γ (downhill positive, walking towards +x)",
    )

    def check(self) -> None:
        for com, length, link in (
            ("com_shank", "length_shank", "shank"),
            ("com_thigh", "length_thigh", "thigh"),
            ("com_torso", "length_torso", "torso"),
        ):
            c, ell = getattr(self, com), getattr(self, length)
            if c > ell:
                raise ParameterError(
                    f"{self.name}: parameter `{com}` = {c:g} m exceeds `{length}` = {ell:g} m "
                    f"(the centre of mass must lie on the {link}); use {com} ≤ {ell:g}"
                )

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        g, gamma = sym.gravity, sym.slope
        x, states = sym.states(*STATE_NAMES)
        q, qd = ca.vertcat(*states[:5]), ca.vertcat(*states[5:])
        geo = _geometry(sym, q)
        masses = _masses(sym, geo)
        tau = ca.DM(INPUT_MATRIX) @ sym.u  # Q = B u (generalised forces of the joint torques)
        qdd = lagrange_acceleration(masses, q, qd, g, tau)
        flow = sym.function("flow", x, ca.vertcat(qd, qdd))

        normal = ca.vertcat(ca.sin(gamma), ca.cos(gamma))  # unit normal of the ground line
        tangent = ca.vertcat(ca.cos(gamma), -ca.sin(gamma))  # downhill (walking) direction
        swing_foot = geo["swing_foot"]
        post = impact_velocity(masses, q, qd, swing_foot)
        swap = [4, 3, 2, 1, 0]  # legs swap roles: links 1 ↔ 5, 2 ↔ 4
        heel_strike = Transition(
            name="heel strike",
            guard=sym.function("guard", x, ca.dot(normal, swing_foot)),
            direction=-1,
            reset=sym.function(
                "reset", x, ca.vertcat(*[q[k] for k in swap], *[post[k] for k in swap])
            ),
            target=0,
            admissible=sym.function("admissible", x, ca.dot(tangent, swing_foot)),
            foothold="swing_foot",
            doc="the swing foot's height above the ground falls through 0 ahead of the stance "
            "foot; plastic impact at the swing foot (the old stance foot lifts off without "
            "impulse); legs swap (q1…q5 → q5…q1, and the rates)",
        )
        falls = fall(sym, x, "fall", ca.dot(normal, geo["hip"]), "the hip reaches the ground")
        torso_fall = fall(sym, x, "torso fall", ca.cos(q[2]), "the torso reaches horizontal")
        # Unilateral constraints.  The swing foot must stay above the ground: its height is the
        # guard h, 0 where the step begins (the trailing foot must then lift off, ḣ > 0, or the
        # gait would need a double-support phase, not modelled) and 0 at heel strike.  The stance
        # foot must push: N = n · Σ m_i (r̈_i + g ŷ) ≥ 0.  OptimTraj imposes neither along the
        # step (only the foot's vertical velocity at its two ends, autoGen_cst_footVel).
        clearance = sym.constraint(
            "swing foot above the ground",
            x,
            ca.dot(normal, swing_foot),
            "trip",
            at_start=True,
            at_end=True,
            unit="m",
            source="a foot cannot enter the ground; the trailing foot lifts off after heel "
            "strike (OptimTraj autoGen_cst_footVel)",
        )
        push = sym.constraint(
            "stance foot pushes on the ground",
            x,
            ca.dot(normal, contact_force(masses, q, qd, qdd, g)),
            "stance foot lifts off",
            unit="N",
            source="a ground contact can only push (unilateral normal force)",
        )
        # OptimTraj's optional knee limits (pathConstraint.m), for an optimiser to select.
        flexion = tuple(
            sym.constraint(
                f"{knee.replace('_', ' ')} flexion",
                x,
                states[STATE_NAMES.index(a)] - states[STATE_NAMES.index(b)],
                f"{knee.replace('_', ' ')} hyperextends",
                unit="rad",
                source="a knee that does not hyperextend (OptimTraj demo/fiveLinkBiped "
                "pathConstraint.m)",
            )
            for knee, (a, b) in cls.knee_flexion.items()
        )
        energy = sym.conserved(
            "energy", x, kinetic_energy(masses, q, qd) + potential_energy(masses, g)
        )
        points = ca.Function("points", [x, sym.p], [ca.horzcat(*[geo[k] for k in POINT_NAMES])])
        phase = Phase(
            "single support",
            STATE_NAMES,
            flow,
            (heel_strike, falls, torso_fall),
            {"energy": energy},
            points=points,
            point_names=POINT_NAMES,
            bodies=bodies_function(masses, x, q, qd, sym.p),
            constraints=(clearance, push),
            limits={"knee_flexion": flexion},
        )

        # -- section: just after heel strike, the trailing foot on the ground behind ------------
        free = (*LINK_NAMES[:4], *STATE_NAMES[5:])
        s, sv = sym.states(*free)
        ls, lt = sym.length_shank, sym.length_thigh
        reach = (
            ls * ca.cos(sv[0] + gamma) + lt * ca.cos(sv[1] + gamma) - lt * ca.cos(sv[3] + gamma)
        ) / ls
        swing_shank = -gamma - ca.acos(reach)  # h = 0 with the foot behind its knee
        section = Section(
            free,
            sym.lift(s, ca.vertcat(*sv[:4], swing_shank, *sv[4:])),
            "just after heel strike: the swing foot on the ground behind the stance foot, "
            "swing_shank = −slope − arccos((l_s cos(stance_shank + slope) + l_t cos(stance_thigh "
            "+ slope) − l_t cos(swing_thigh + slope)) / l_s)",
        )
        return (phase,), section

    @classmethod
    def manipulator(cls) -> ca.Function:
        """``manipulator(q, qd, u, p) -> (M, rhs)``: the equations of motion in implicit form
        ``M(q) q̈ = rhs(q, q̇, u)`` (M in kg·m², rhs in N·m), for collocation and checks."""
        if cls not in _MANIPULATOR:
            sym = Symbols(cls.parameter_specs(), cls.inputs)
            q, qd = ca.SX.sym("q", 5), ca.SX.sym("qd", 5)
            masses = _masses(sym, _geometry(sym, q))
            tau = ca.DM(INPUT_MATRIX) @ sym.u
            M, rhs = lagrange_terms(masses, q, qd, sym.gravity, tau)
            _MANIPULATOR[cls] = ca.Function(
                "manipulator", [q, qd, sym.u, sym.p], [M, rhs], ["q", "qd", "u", "p"], ["M", "rhs"]
            )
        return _MANIPULATOR[cls]

    def input_rates(self, phase: int) -> ca.Function:
        """Each torque acts between adjacent links: input ``i`` delivers ``u_i ω_i`` with
        ``ω = (q̇2 − q̇1, q̇3 − q̇2, q̇4 − q̇3, q̇5 − q̇4)`` (rad/s), the stance knee, stance hip,
        swing hip and swing knee rates (``Bᵀ q̇``)."""
        del phase
        x = ca.SX.sym("x", 10)
        p = ca.SX.sym("p", len(self.parameter_specs()))
        rates = ca.DM(INPUT_MATRIX).T @ x[5:]
        return ca.Function("input_rates", [x, p], [rates], ["x", "p"], ["rates"])

    def max_step_length(self) -> float:
        """Two legs of shank and thigh (m): the feet are at most 2 (l1 + l2) apart."""
        return 2 * (self.length_shank + self.length_thigh)

    def default_start(self) -> dict[str, float]:
        """A plausible post-heel-strike state (rad, rad/s): trailing leg behind with a slightly
        bent knee, torso upright, walking forward (clockwise rotation of the stance leg).  Not
        on a gait: the model has none without torques."""
        return {
            "stance_shank": 0.25,
            "stance_thigh": 0.25,
            "torso": 0.0,
            "swing_thigh": -0.2,
            "stance_shank_dot": -1.2,
            "stance_thigh_dot": -1.0,
            "torso_dot": 0.0,
            "swing_thigh_dot": 0.5,
            "swing_shank_dot": 1.0,
        }

    def existence_note(self) -> str | None:
        return (
            "the five-link biped has no passive gait (on level ground the heel-strike impacts "
            "dissipate energy that nothing supplies; its free knees and torso buckle without "
            "torque): its gaits come from trajectory optimisation with its four joint torques"
        )


_MANIPULATOR: dict[type, ca.Function] = {}
