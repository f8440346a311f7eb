"""The kneed walker: a passive biped whose swing knee folds, then locks; point or curved feet.

Hsu Chen 2007 ("Passive dynamic walking with knees: a point foot model", MIT thesis; the
model and parameters of Tedrake's *Underactuated Robotics*, ch. "Simple models of walking and
running", § "the kneed walker"), after McGeer 1990 ("Passive walking with knees", Proc. IEEE ICRA:
knees, and curved feet that roll).

**Geometry** (Hsu Chen's convention; distances measured along each link from its lower end).
Each leg is a shank of length ``l_s = a1 + b1`` and a thigh of length ``l_t = a2 + b2`` joined at
the knee; leg length ``L = l_s + l_t`` (1 m at the defaults).  Point masses: the hip ``m_h``; on
each leg a shank mass ``m_s`` at ``a1`` above the foot (``b1`` below the knee) and a thigh mass
``m_t`` at ``a2`` above the knee (``b2`` below the hip).  The stance leg's knee stays locked.

**State**: ``q1`` stance leg, ``q2`` swing thigh, ``q3`` swing shank, absolute angles
from vertical in the compass gait's (Drake's) sign convention: a link's angle is that of the
vector from its lower to its upper end, positive when it leans downhill (+x).  The swing knee is
flexed (foot trailing) when ``q3 > q2``.

**Curved feet** (McGeer 1990): each leg ends in a circular arc of radius ``R = foot_radius``
centred on the leg axis ``R`` above the foot end (so the leg is still ``L`` from the hip to its
lowest point).  The stance arc rolls without slipping on the slope (unit tangent
``t = (cos γ, −sin γ)`` downhill, normal ``n = (sin γ, cos γ)``): its contact point is
``R (q1 − γ) t`` from the origin ``O`` (where it touches when the leg is normal to the slope), the
arc centre ``R n`` above that.  Rolling on a line is a holonomic constraint, so every position is
a function of the angles and the Lagrangian needs no multiplier; ``R = 0`` is the point foot,
term by term.  Positions, points and energies are relative to ``O`` (the stance foot for ``R = 0``).

**Phases.** (0) *three-link swing* (6 states, after heel strike): stance leg, free swing thigh and
shank.  Ends at **knee strike**: ``q2 − q3`` increases through 0 (the trailing shank comes in line
with the thigh); a plastic impact locks the knee, ``M (q̇⁺ − q̇⁻) = Jᵀ Λ``, ``J q̇⁺ = 0`` with
``J = ∂(q̇3 − q̇2)/∂q̇`` (:func:`~gaitopt.mechanics.constrained_impact_velocity`): the angular
momentum of the whole walker about the stance contact and of the swing leg about the hip are
conserved (the two conservation laws behind Hsu Chen's knee-strike equations; at R = 0 the reset
agrees with her Q⁺ q̇⁺ = Q⁻ q̇⁻ form to rounding).
(1) *two-link swing* (4 states ``q1, q2, q1_dot, q2_dot``, knee locked: the compass gait with the
kneed mass distribution).  Ends at **heel strike**: the swing foot's height above the slope is
``h = −2 (L − R) sin((q1 + q2)/2 − γ) sin((q1 − q2)/2)`` (for both point and curved feet: the arc
centres are both ``L − R`` from the hip and the stance centre is ``R`` above the slope).  It
vanishes at touchdown ahead, ``q1 + q2 = 2γ``, and where the legs pass each other, ``q1 = q2``.
The guard is the first factor, ``2γ − q1 − q2`` decreasing through 0 (the compass gait's), and the
spurious-crossing rule admits it only with the swing foot ahead, ``q1 − q2 > 0``: the mid-swing
scuff (the second factor, a locked leg's foot passing the stance foot) and a touchdown behind the
stance foot are excluded explicitly, as in Drake's compass gait.  The impact is the
floating-base one (:func:`~gaitopt.mechanics.impact_velocity`) with the knee locked; for curved
feet the striking material point obeys the rolling condition (``contact_slip = −R q̇2 t``).  Then
the legs swap and the new swing knee is released straight, ``q3⁺ = q2⁺``, ``q̇3⁺ = q̇2⁺``.
Angular momentum is conserved about the new contact (whole walker) and about the hip (the
trailing leg).

Exits (a gait must not touch them; a simulation stops there): in the three-link phase a *trip*,
the swing foot's height above the slope falling through 0 before the knee locks (the foot starts
on the slope and counts only once lifted; for curved feet the height of the full circle's lowest
point, which is conservative for a foot that is only an arc of it); in both phases a *fall*, the
stance leg horizontal.

Not modelled: double support, a trailing foot that does not lift off, or a
released knee that does not flex (the knee would stay locked).  On the gait the trailing foot
rises at 0.28 m/s just after heel strike and the knee flexes at once (the tests check the knee
stays flexed through the three-link phase); ``problems/kneed_walker_feet.py`` counts perturbed
states that violate either as failures.

**Inputs** (zero by default: the passive walker, unchanged): ``hip_torque`` τ_h (N·m) between the
stance leg and the swing thigh, +τ_h on the thigh and −τ_h on the stance leg (the compass gait's
``B = [−1, 1]ᵀ``); ``knee_torque`` τ_k (N·m) between the swing thigh and shank, +τ_k on the shank
(flexing the knee, raising ``q3 − q2``) and −τ_k on the thigh.  Generalised forces
``Q = (−τ_h, τ_h − τ_k, τ_k)`` in the three-link phase and ``(−τ_h, τ_h)`` with the knee
locked, where the knee torque acts on a latched joint and does nothing.  The stance push uses
the actuated accelerations.  Powers: ``τ_h (q̇2 − q̇1)`` and ``τ_k (q̇3 − q̇2)`` (0 with the
knee locked).  ``push_off`` P (N·s, ≥ 0; Kuo 2002): an impulse along the trailing (stance)
leg's axis at the hip just before heel strike, on the floating walker (an impulsive input of the
heel strike, :attr:`~gaitopt.HybridModel.impulsive_inputs`; its work, the kinetic energy it
adds, is :meth:`KneedWalker.impulse_work`); an optional input
(:attr:`~gaitopt.HybridModel.optional_inputs`): an optimisation leaves it at 0 unless its
``bounds`` name it.

**Section:** just after heel strike, ``q2 = q3 = 2γ − q1`` and ``q̇3 = q̇2``; free coordinates
``q1, q1_dot, q2_dot`` (3 nontrivial multipliers).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import casadi as ca
import numpy as np

from ..errors import ParameterError
from ..hybrid import Constraint, HybridModel, Phase, Section, Symbols, Transition
from ..mechanics import (
    bodies_function,
    constrained_impact_velocity,
    contact_force,
    impact_velocity,
    impulse_work,
    kinetic_energy,
    lagrange_acceleration,
    potential_energy,
)
from ..parameters import gravity_parameter, parameter
from .blocks import fall
from .quantities import length_parameter, mass_parameter, slope_parameter, state_units

__all__ = ["KneedWalker"]

_HSU_CHEN = "Hsu Chen 2007, as in Tedrake's Underactuated Robotics (kneed walker)"

#: Names of the drawing points of both phases (columns of ``Phase.points``).
POINT_NAMES = (
    "stance_foot",
    "stance_knee",
    "hip",
    "swing_knee",
    "swing_foot",
    "stance_centre",
    "swing_centre",
    "swing_origin",
)
#: Order of the point masses in ``Phase.bodies`` (for momentum checks of subsystems).
BODY_NAMES = ("hip", "stance_shank", "stance_thigh", "swing_thigh", "swing_shank")


def _unit(angle: ca.SX) -> ca.SX:
    """Unit vector along a link leaning ``angle`` from vertical towards +x (lower → upper end)."""
    return ca.vertcat(ca.sin(angle), ca.cos(angle))


def _walker(sym: Symbols, q1: ca.SX, q2: ca.SX, q3: ca.SX) -> dict[str, ca.SX]:
    """Positions (relative to the rolling origin ``O``) of the masses and drawing points.

    ``q3 = q2`` gives the knee-locked walker.
    """
    R, gamma = sym.foot_radius, sym.slope
    ls = sym.a1 + sym.b1  # shank length
    lt = sym.a2 + sym.b2  # thigh length
    L = ls + lt
    t = ca.vertcat(ca.cos(gamma), -ca.sin(gamma))  # downhill tangent of the slope
    n = ca.vertcat(ca.sin(gamma), ca.cos(gamma))  # slope normal
    stance_contact = R * (q1 - gamma) * t  # rolling without slipping from O
    stance_centre = stance_contact + R * n
    stance_foot = stance_centre - R * _unit(q1)  # lower end of the leg axis
    hip = stance_foot + L * _unit(q1)
    swing_knee = hip - lt * _unit(q2)
    swing_foot = swing_knee - ls * _unit(q3)
    swing_centre = swing_foot + R * _unit(q3)
    swing_contact = swing_centre - R * n  # the arc's point nearest the slope
    return {
        "stance_contact": stance_contact,
        "stance_centre": stance_centre,
        "stance_foot": stance_foot,
        "stance_knee": stance_foot + ls * _unit(q1),
        "hip": hip,
        "swing_knee": swing_knee,
        "swing_foot": swing_foot,
        "swing_centre": swing_centre,
        "swing_contact": swing_contact,
        # Where the swing leg's own rolling origin lies on the slope (its contact point if it were
        # normal to the slope): the next stance phase's O, for drawing successive steps.
        "swing_origin": swing_contact - R * (q3 - gamma) * t,
        # Point masses (BODY_NAMES order).
        "m_hip": hip,
        "m_stance_shank": stance_foot + sym.a1 * _unit(q1),
        "m_stance_thigh": stance_foot + (ls + sym.a2) * _unit(q1),
        "m_swing_thigh": hip - sym.b2 * _unit(q2),
        "m_swing_shank": swing_knee - sym.b1 * _unit(q3),
        "tangent": t,
        "normal": n,
    }


def _masses(sym: Symbols, geo: dict[str, ca.SX]) -> list[tuple[ca.SX, ca.SX]]:
    mh, mt, ms = sym.mass_hip, sym.mass_thigh, sym.mass_shank
    return [
        (mh, geo["m_hip"]),
        (ms, geo["m_stance_shank"]),
        (mt, geo["m_stance_thigh"]),
        (mt, geo["m_swing_thigh"]),
        (ms, geo["m_swing_shank"]),
    ]


def _points(sym: Symbols, x: ca.SX, geo: dict[str, ca.SX]) -> ca.Function:
    return ca.Function("points", [x, sym.p], [ca.horzcat(*[geo[k] for k in POINT_NAMES])])


def _contact_constraints(
    sym, x, geo, masses, q, qd, tau=0, **where
) -> tuple[Constraint, Constraint]:
    """The unilateral conditions of a phase: the swing foot above the slope (its height above it:
    the arc's lowest point; for R = 0 the foot; for curved feet the full circle's lowest point,
    conservative for a foot that is only an arc of it), and a stance contact that pushes (the
    ground's normal force ``N = n · Σ m_i (r̈_i + g ŷ) ≥ 0``).  ``where``: ``at_start`` (the
    trailing foot starts on the slope and must lift off at once; one that does not would need a
    double-support phase, not modelled) or ``at_end`` (touchdown at heel strike); ``tau``: the
    generalised forces of the joint torques."""
    g = sym.gravity
    clearance = sym.constraint(
        "swing foot above the slope",
        x,
        ca.dot(geo["normal"], geo["swing_contact"]),
        "trip",
        unit="m",
        source="a foot cannot enter the ground (McGeer 1990; Hsu Chen 2007, foot clearance)",
        **where,
    )
    qdd = lagrange_acceleration(masses, q, qd, g, tau)
    push = sym.constraint(
        "stance foot pushes on the slope",
        x,
        ca.dot(geo["normal"], contact_force(masses, q, qd, qdd, g)),
        "stance foot lifts off",
        unit="N",
        source="a ground contact can only push (unilateral normal force)",
    )
    return clearance, push


@dataclass(frozen=True)
class KneedWalker(HybridModel):
    """Kneed walker: phase 0 states ``q1, q2, q3`` (rad), ``q1_dot, q2_dot, q3_dot`` (rad/s);
    phase 1 (knee locked) ``q1, q2, q1_dot, q2_dot``."""

    name = "kneed_walker"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("q1", "q2", "q3", "q1_dot", "q2_dot", "q3_dot")
    declared_coordinates = ("q1", "q1_dot", "q2_dot")
    declared_section_doc = "just after heel strike: q2 = q3 = 2·slope − q1, q3_dot = q2_dot"
    state_units = state_units(q1="rad", q2="rad", q3="rad")  # for axis labels
    title = "Kneed walker"
    reference = "Hsu Chen 2007; McGeer 1990; Tedrake, Underactuated Robotics"
    inputs = ("hip_torque", "knee_torque", "push_off")
    input_units = ("N*m", "N*m", "N*s")
    impulsive_inputs = ("push_off",)
    #: The push-off is off unless an optimisation bounds it (the torques' optima stay theirs).
    optional_inputs = ("push_off",)
    input_bounds: ClassVar[dict[str, tuple[float, float]]] = {"push_off": (0.0, float("inf"))}
    mesh = (4, 5)  # 20 RK8 steps per phase: discretisation error ~1e-11 at the defaults

    mass_hip: float = mass_parameter(0.5, "hip point mass m_h", _HSU_CHEN)
    mass_thigh: float = mass_parameter(0.5, "thigh point mass m_t (each leg)", _HSU_CHEN)
    mass_shank: float = mass_parameter(0.05, "shank point mass m_s (each leg)", _HSU_CHEN)
    a1: float = length_parameter(0.375, "foot to shank mass distance", _HSU_CHEN)
    b1: float = length_parameter(0.125, "shank mass to knee distance", _HSU_CHEN)
    a2: float = length_parameter(0.175, "knee to thigh mass distance", _HSU_CHEN)
    b2: float = length_parameter(0.325, "thigh mass to hip distance", _HSU_CHEN)
    gravity: float = gravity_parameter()
    slope: float = slope_parameter(0.0504, _HSU_CHEN, (0.0, 0.3))
    foot_radius: float = parameter(
        0.0, unit="m", low=0.0, high=1.0,
        doc="radius R of the circular-arc feet (0: point feet); at most the shank length a1 + b1",
        source="point foot (Hsu Chen 2007); curved feet after McGeer 1990",
    )  # fmt: skip

    def check(self) -> None:
        shank = self.a1 + self.b1
        if self.foot_radius > shank:
            raise ParameterError(
                f"{self.name}: parameter `foot_radius` = {self.foot_radius:g} m exceeds the shank "
                f"length a1 + b1 = {shank:g} m (the arc centre must lie on the shank); use "
                f"foot_radius ≤ {shank:g}"
            )

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        g, gamma, R = sym.gravity, sym.slope, sym.foot_radius

        # -- phase 0: three-link swing (free knee) ---------------------------------------------
        names0 = ("q1", "q2", "q3", "q1_dot", "q2_dot", "q3_dot")
        x0, (q1, q2, q3, q1d, q2d, q3d) = sym.states(*names0)
        q, qd = ca.vertcat(q1, q2, q3), ca.vertcat(q1d, q2d, q3d)
        geo0 = _walker(sym, q1, q2, q3)
        masses0 = _masses(sym, geo0)
        tau_h, tau_k = sym.input("hip_torque"), sym.input("knee_torque")
        tau0 = ca.vertcat(-tau_h, tau_h - tau_k, tau_k)  # generalised forces (module docstring)
        acc0 = lagrange_acceleration(masses0, q, qd, g, tau0)
        flow0 = sym.function("flow", x0, ca.vertcat(qd, acc0))
        # Knee strike: the knee locks; the stance contact (pinned or rolling) persists.
        locked = constrained_impact_velocity(masses0, q, qd, q3d - q2d)
        knee_strike = Transition(
            name="knee strike",
            guard=sym.function("guard", x0, q2 - q3),
            direction=+1,
            reset=sym.function("reset", x0, ca.vertcat(q1, q2, locked[0], locked[1])),
            target=1,
            impact=True,
            doc="q2 − q3 rises through 0 (the flexed knee straightens); plastic impact locking "
            "the knee: M Δq̇ = Jᵀ Λ, q̇3⁺ = q̇2⁺",
        )
        # The swing foot clears the slope; it starts on it (the trailing foot at heel strike), so
        # it must lift off at once (see _contact_constraints).
        constraints0 = _contact_constraints(sym, x0, geo0, masses0, q, qd, tau0, at_start=True)
        fall0 = fall(sym, x0, "fall", ca.cos(q1), "the stance leg reaches horizontal")
        energy0 = sym.conserved(
            "energy", x0, kinetic_energy(masses0, q, qd) + potential_energy(masses0, g)
        )
        # The swing knee must not hyperextend, q3 − q2 ≥ 0 (0 where the phase begins, the knee
        # released straight, and at knee strike): an optimiser's limit, on request.  It is the
        # knee strike guard's side, which the optimiser keeps anyway at the interior nodes.
        flexion = sym.constraint(
            "swing knee flexion",
            x0,
            q3 - q2,
            "swing knee hyperextends",
            at_start=True,
            at_end=True,
            unit="rad",
            source="a knee that does not hyperextend (the knee locks at q3 = q2; Hsu Chen 2007)",
        )
        phase0 = Phase(
            "three-link swing",
            names0,
            flow0,
            (knee_strike, fall0),
            {"energy": energy0},
            points=_points(sym, x0, geo0),
            point_names=POINT_NAMES,
            bodies=bodies_function(masses0, x0, q, qd, sym.p),
            constraints=constraints0,
            limits={"knee_flexion": (flexion,)},
        )

        # -- phase 1: two-link swing (knee locked) -----------------------------------------------
        names1 = ("q1", "q2", "q1_dot", "q2_dot")
        x1, (p1, p2, p1d, p2d) = sym.states(*names1)
        r, rd = ca.vertcat(p1, p2), ca.vertcat(p1d, p2d)
        geo1 = _walker(sym, p1, p2, p2)
        masses1 = _masses(sym, geo1)
        tau1 = ca.vertcat(-tau_h, tau_h)  # the knee is latched: its torque does nothing
        flow1 = sym.function(
            "flow", x1, ca.vertcat(rd, lagrange_acceleration(masses1, r, rd, g, tau1))
        )
        # Heel strike with the knee locked; the striking arc rolls (no slip) from then on.  Just
        # before it, Kuo's (2002) push-off: an impulse P ≥ 0 along the trailing (stance) leg's
        # axis, from its foot towards the hip, on the floating walker (the trailing foot leaves
        # the ground); with the heel strike's impulse the equations are linear, so together or
        # just before give the same velocities (mechanics.impact_velocity).  At P = 0 the
        # passive heel strike exactly.
        push_off = sym.input("push_off")
        axis = _unit(p1)  # the stance leg's axis, foot → hip (through the arc centre)
        post = impact_velocity(
            masses1, r, rd, geo1["swing_contact"], contact_slip=-R * p2d * geo1["tangent"],
            impulse=(geo1["hip"], push_off * axis),
        )  # fmt: skip
        heel_strike = Transition(
            name="heel strike",
            guard=sym.function("guard", x1, 2 * gamma - p1 - p2),
            direction=-1,
            # Legs swap; the new swing knee is released straight (q3 = q2, q̇3 = q̇2).
            reset=sym.function("reset", x1, ca.vertcat(p2, p1, p1, post[1], post[0], post[0])),
            target=0,
            admissible=sym.function("admissible", x1, p1 - p2),
            foothold="swing_origin",
            doc="q1 + q2 = 2·slope with the swing foot ahead (q2 < q1; the mid-swing scuff "
            "q1 = q2 and touchdowns behind are excluded); knee-locked plastic impact; legs swap; "
            "new swing knee released",
        )
        # With the knee locked the swing foot must still clear the slope until heel strike, where
        # its height returns to 0 (h = −2 (L − R) sin((q1 + q2)/2 − γ) sin((q1 − q2)/2): a leg
        # whose knee locks before it passes the stance leg scuffs).
        constraints1 = _contact_constraints(sym, x1, geo1, masses1, r, rd, tau1, at_end=True)
        fall1 = fall(sym, x1, "fall", ca.cos(p1), "the stance leg reaches horizontal")
        energy1 = sym.conserved(
            "energy", x1, kinetic_energy(masses1, r, rd) + potential_energy(masses1, g)
        )
        phase1 = Phase(
            "two-link swing",
            names1,
            flow1,
            (heel_strike, fall1),
            {"energy": energy1},
            points=_points(sym, x1, geo1),
            point_names=POINT_NAMES,
            bodies=bodies_function(masses1, x1, r, rd, sym.p),
            constraints=constraints1,
        )

        # -- section: just after heel strike ----------------------------------------------------
        s, (s_q1, s_q1d, s_q2d) = sym.states("q1", "q1_dot", "q2_dot")
        swing = 2 * gamma - s_q1
        section = Section(
            ("q1", "q1_dot", "q2_dot"),
            sym.lift(s, ca.vertcat(s_q1, swing, swing, s_q1d, s_q2d, s_q2d)),
            "just after heel strike: q2 = q3 = 2·slope − q1, q3_dot = q2_dot",
        )
        return (phase0, phase1), section

    def outline(self, phase, x, points):
        """Legs and curved feet, for drawing (:func:`kneed_outline`)."""
        return kneed_outline(self, phase, x, points)

    def max_step_length(self) -> float:
        """Two legs of shank a1 + b1 and thigh a2 + b2 (m): the feet are at most twice that
        apart."""
        return 2 * (self.a1 + self.b1 + self.a2 + self.b2)

    def default_start(self) -> dict[str, float]:
        """A post-heel-strike state near the passive gait at the defaults (rounded)."""
        return {"q1": -0.19, "q1_dot": 1.1, "q2_dot": 0.06}

    def input_rates(self, phase: int) -> ca.Function:
        """The joint rates the torques do work on (rad/s): ``(q̇2 − q̇1, q̇3 − q̇2)`` in the
        three-link phase, ``(q̇2 − q̇1, 0)`` with the knee locked; the push-off acts only in the
        heel strike (its work is :meth:`impulse_work`): rate 0."""
        n_p = len(self.parameter_specs())
        p = ca.SX.sym("p", n_p)
        if phase == 0:
            x = ca.SX.sym("x", 6)
            rates = ca.vertcat(x[4] - x[3], x[5] - x[4], ca.SX(0))
        else:
            x = ca.SX.sym("x", 4)
            rates = ca.vertcat(x[3] - x[2], ca.SX(0), ca.SX(0))
        return ca.Function("input_rates", [x, p], [rates], ["x", "p"], ["rates"])

    def impulse_work(self, phase: int) -> ca.Function | None:
        """The push-off's work (J) at heel strike (the two-link phase's cycle transition): the
        floating walker's kinetic energy gained from the impulse ``P`` along the stance leg's
        axis at the hip, ``P ê·v_hip⁻ + ½ P² êᵀ J M⁻¹ Jᵀ ê`` (:func:`~gaitopt.mechanics.
        impulse_work`; for point feet ``v_hip⁻ ⟂ ê``); None in the three-link phase."""
        if phase != 1:
            return None
        return _push_off_work(self)


def _push_off_work(model: HybridModel) -> ca.Function:
    """``impulse_work(x⁻, u, p) -> w`` of the two-link phase: the push-off's work (J)."""
    sym = Symbols(model.parameter_specs(), model.inputs)
    x, (p1, p2, p1d, p2d) = sym.states("q1", "q2", "q1_dot", "q2_dot")
    geo = _walker(sym, p1, p2, p2)
    work = impulse_work(
        _masses(sym, geo), ca.vertcat(p1, p2), ca.vertcat(p1d, p2d), geo["hip"],
        sym.input("push_off") * _unit(p1),
    )  # fmt: skip
    return ca.Function("impulse_work", [x, sym.u, sym.p], [work], ["x", "u", "p"], ["w"])


def kneed_outline(model: HybridModel, phase: Phase, x: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """The kneed walker's legs (foot, knee, hip, knee, foot) and, for curved feet, each foot's
    circular arc of radius ``foot_radius`` about its centre (±0.6 rad about the leg axis)."""
    names = phase.point_names
    legs = [pts[:, names.index(n)] for n in _KNEED_LEGS]
    segments = legs + [[np.nan, np.nan]]
    radius = float(model.foot_radius)
    if radius > 0:
        shank = "q3" if "q3" in phase.states else "q2"  # knee locked: the shank is the thigh
        angles = {"stance": x[phase.states.index("q1")], "swing": x[phase.states.index(shank)]}
        sweep = np.linspace(-0.6, 0.6, 13)
        for leg, angle in angles.items():
            centre = pts[:, names.index(f"{leg}_centre")]
            arc = centre[:, None] - radius * np.vstack(
                [np.sin(angle + sweep), np.cos(angle + sweep)]
            )
            segments += list(arc.T) + [[np.nan, np.nan]]
    return np.array(segments, dtype=float).T


_KNEED_LEGS = ("stance_foot", "stance_knee", "hip", "swing_knee", "swing_foot")
