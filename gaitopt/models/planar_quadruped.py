"""A planar quadruped: a rigid body in pitch on a back and a front massless spring leg.

The model of Poulakakis, Papadopoulos & Buehler 2006 ("On the stability of the passive
dynamics of quadrupedal running with a bounding gait", IJRR 25(3)), the energy-conserving
sagittal-plane template of the Scout II robot: a rigid body of mass ``m`` and pitch inertia ``I``
about its centre of mass (COM); hips at ``±L`` from the COM along the body axis; a massless
prismatic spring leg of rest length ``l0`` and stiffness ``k`` at each hip (the two legs of a
pair move together in a bound or a pronk, so each sagittal leg stands for a pair).

Conventions.  ``x`` (forward) and ``z`` (up) are the COM's position (m), ``phi`` the pitch
(rad, positive nose up), so the hips are at::

    back  (x − L cos φ, z − L sin φ),      front (x + L cos φ, z + L sin φ).

In flight a leg is held at its touchdown angle ``θ`` from vertical (foot ahead of the hip for
``θ > 0``, the SLIP's convention): its foot is ``l0 (sin θ, −cos θ)`` from the hip and touches
down when the hip height reaches ``l0 cos θ`` falling (the guard ``z_hip − l0 cos θ = 0``).  A
foot on the ground is a frictionless-free pin at ``(x_foot, 0)`` (no slip), stored as a state
that the flow keeps constant.  Leg vector from foot to hip ``d = hip − foot``, length
``r = |d|``; the spring pushes along it with force ``F = k (l0 − r)``.  Newton–Euler for the
rigid body (Poulakakis et al. 2006, §2; Goldstein, *Classical Mechanics*)::

    m ẍ = Σ F dₓ/r,     m z̈ = Σ F d_z/r − m g,     I φ̈ = Σ (hₓ − x) F d_z/r − (h_z − z) F dₓ/r,

the sums over the legs on the ground (``h`` the hip).  Lift-off when a stance leg regains its
rest length, ``r = l0`` extending (its force falls to zero).  Touchdown and lift-off change no
velocity (massless legs), and the leg force is zero at both: the vector field is continuous
across every event.  Energy ``E = ½ m (ẋ² + ż²) + ½ I φ̇² + m g z + Σ ½ k (l0 − r)²`` is
conserved.

Two gaits, two phase cycles (the shooting follows one fixed cycle of phases with positive
durations, so each gait is its own model class):

* ``planar_quadruped`` — the **bound** (the default gait): apex → descent → *back stance* →
  flight → *front stance* → ascent → apex (the bound with two flight phases of Poulakakis et al.
  2006, Fig. 2).  The front foot must stay above the ground until its touchdown (descent and back
  stance: declared constraints, so a double stance ends a simulation as "front foot touches down
  during back stance" rather than being mistaken for this gait).  A leg that has lifted off is
  swung forward and not placed again until after the next apex (the SLIP's convention:
  Poulakakis et al. reposition the legs in flight; its foot clearance then is not checked).
* ``planar_quadruped_pronk`` — the **pronk** (legs in phase): apex → descent → *double stance* →
  ascent.  Simultaneous touchdown (and lift-off) of both legs is not generic: any pitch splits
  the events, so the pronk is a cycle of this phase sequence only on the invariant pitch-free set
  ``φ = φ̇ = 0`` with equal touchdown angles.  Its section is that set's apex: one coordinate
  ``z`` and one multiplier, which is the multiplier of the pitch-free direction.  There the
  two legs' forces are equal and their pitch torques cancel (hips at ``±L``), so the COM moves
  exactly as the SLIP with stiffness ``2k`` (and the same mass, energy, angle and rest length):
  ``gaitopt.model("slip", stiffness=2k, ...)`` is the check (tests/test_planar_quadruped.py).

Poincaré section: apex of the flight, ``ż = 0`` falling, ``x`` reset to 0.  As in the SLIP, the
energy ``E`` is a parameter and the forward speed follows from it,
``ẋ = sqrt(2 (E − m g z − ½ I φ̇²)/m)``: the bound's section coordinates are ``z, phi, phi_dot``
(three multipliers, none the trivial one of energy conservation or of the time shift).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import casadi as ca
import numpy as np

from ..errors import ParameterError
from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..parameters import gravity_parameter, parameter
from .blocks import apex, ballistic_flow, fall
from .quantities import energy_parameter, length_parameter, mass_parameter, stiffness_parameter

__all__ = ["PlanarQuadruped", "PlanarQuadrupedPronk"]

_PAPER = (
    "Poulakakis, Papadopoulos & Buehler 2006, IJRR 25(3), Scout II model parameters (the value "
    "given in the issue; not confirmed against the paper's text: the search tool found only the "
    "paper's companion, Poulakakis, Smith & Buehler, 'On the dynamics of bounding and extensions "
    "towards the half-bound and the gallop gaits', without its parameter table)"
)
_FLIGHT = ("x", "z", "phi", "x_dot", "z_dot", "phi_dot")
#: Drawing points of every phase.
POINT_NAMES = ("back_hip", "front_hip", "back_foot", "front_foot")
_UNITS = {
    "x": "m",
    "z": "m",
    "phi": "rad",
    "x_dot": "m/s",
    "z_dot": "m/s",
    "phi_dot": "rad/s",
    "back_foot": "m",
    "front_foot": "m",
}


def _hips(q):
    """Back and front hip positions ``(x ∓ L cos φ, z ∓ L sin φ)`` (m) and velocities (m/s)
    of the flight coordinates ``q = (x, z, φ, ẋ, ż, φ̇)`` with half-length ``L``."""
    x, z, phi, xd, zd, phid, L = q
    out = []
    for sign in (-1, +1):
        out.append(
            (
                x + sign * L * ca.cos(phi),
                z + sign * L * ca.sin(phi),
                xd - sign * L * ca.sin(phi) * phid,
                zd + sign * L * ca.cos(phi) * phid,
            )
        )
    return out  # [back, front]


def _drawing(sym: Symbols, x: ca.SX, hips, l0: ca.SX, feet) -> ca.Function:
    """``points(x, p)`` (m): the back and front hips, then each foot of ``feet = [(hip, foot,
    angle), ...]``: on the ground at ``(foot, 0)``, or, ``foot`` None, held at ``angle`` from
    vertical at the rest length ``l0`` below its hip."""
    back, front = hips
    cols = [ca.vertcat(back[0], back[1]), ca.vertcat(front[0], front[1])]
    for hip, foot, angle in feet:
        if foot is None:
            cols.append(ca.vertcat(hip[0] + l0 * ca.sin(angle), hip[1] - l0 * ca.cos(angle)))
        else:
            cols.append(ca.vertcat(foot, 0))
    return ca.Function("points", [x, sym.p], [ca.horzcat(*cols)])


def _energy():
    """The total energy ``E`` (J) of the passive bound and pronk, a parameter."""
    return energy_parameter(
        90.0,
        "total energy E (kinetic + m g z + spring)",
        "chosen: E/(m g) = 0.44 m, above the touchdown height l0·cos θ ≈ 0.31 m; "
        "a passive gait exists there (tests/test_planar_quadruped.py)",
    )


def _touchdown_angle(leg: str):
    """The nominal touchdown angle of the ``leg`` ("back", "front") as a parameter (rad)."""
    return parameter(
        0.21, unit="rad", low=-math.pi / 2, high=math.pi / 2, low_open=True, high_open=True,
        doc=f"nominal {leg}-leg touchdown angle from vertical (foot ahead > 0)",
        source="chosen: a passive bound exists there (found by tests/test_planar_quadruped.py)",
    )  # fmt: skip


class _Legs:
    """The symbolic pieces shared by the phases (built inside ``build``)."""

    def __init__(self, sym: Symbols):
        self.sym = sym
        self.m, self.I, self.L = sym.mass, sym.inertia, sym.half_length
        self.l0, self.k, self.g, self.E = sym.rest_length, sym.stiffness, sym.gravity, sym.energy

    def hips(self, x):
        return _hips((x[0], x[1], x[2], x[3], x[4], x[5], self.L))

    def leg(self, x, hip, foot):
        """Leg vector ``d = hip − (foot, 0)``, its length ``r`` and force ``F = k (l0 − r)``."""
        dx, dz = hip[0] - foot, hip[1]
        r = ca.sqrt(dx**2 + dz**2)
        return dx, dz, r, self.k * (self.l0 - r)

    def flow(self, x, legs):
        """Newton–Euler (module docstring) with the given stance legs ``[(hip, foot), ...]``;
        the feet (extra states after the six rigid-body states) have zero rate."""
        fx, fz, tau = 0, -self.m * self.g, 0
        for hip, foot in legs:
            dx, dz, r, F = self.leg(x, hip, foot)
            Fx, Fz = F * dx / r, F * dz / r
            fx, fz = fx + Fx, fz + Fz
            tau = tau + (hip[0] - x[0]) * Fz - (hip[1] - x[1]) * Fx  # (h − c) × F
        rates = [x[3], x[4], x[5], fx / self.m, fz / self.m, tau / self.I]
        return self.sym.function("flow", x, ca.vertcat(*rates, *([0] * len(legs))))

    def energy(self, x, legs):
        e = (
            0.5 * self.m * (x[3] ** 2 + x[4] ** 2)
            + 0.5 * self.I * x[5] ** 2
            + self.m * self.g * x[1]
        )
        for hip, foot in legs:
            e = e + 0.5 * self.k * (self.l0 - self.leg(x, hip, foot)[2]) ** 2
        return self.sym.conserved("energy", x, e)

    def clearance(self, hip, angle):
        """Height (m) of a foot held at ``angle`` from vertical: ``z_hip − l0 cos θ``."""
        return hip[1] - self.l0 * ca.cos(angle)

    def touchdown(self, name, x, hip, angle, feet_before, target, doc):
        """Guard: the foot's clearance falls through zero; reset: append the foot position
        ``x_hip + l0 sin θ`` to the state (no velocity changes: massless leg)."""
        foot = hip[0] + self.l0 * ca.sin(angle)
        return Transition(
            name=name,
            guard=self.sym.function("guard", x, self.clearance(hip, angle)),
            direction=-1,
            reset=self.sym.function("reset", x, ca.vertcat(x[:6], *feet_before, foot)),
            target=target,
            impact=False,
            doc=doc,
        )

    def liftoff(self, name, x, hip, foot, keep, target, doc):
        """Guard ``r − l0`` rising; reset drops the lifted foot (``keep``: the feet kept)."""
        r = self.leg(x, hip, foot)[2]
        return Transition(
            name=name,
            guard=self.sym.function("guard", x, r - self.l0),
            direction=+1,
            reset=self.sym.function("reset", x, ca.vertcat(x[:6], *keep)),
            target=target,
            impact=False,
            doc=doc,
        )

    def compressive(self, x, hip, foot, which):
        # A massless spring leg on the ground can only push: k (l0 − r) ≥ 0, zero at touchdown
        # and at lift-off (Blickhan 1989; Poulakakis et al. 2006).
        return self.sym.constraint(
            f"{which} leg force compressive",
            x,
            self.leg(x, hip, foot)[3],
            f"{which} leg pulls",
            at_start=True,
            at_end=True,
            unit="N",
            source="a massless spring leg on the ground can only push (Blickhan 1989)",
        )

    def above(self, x, hip, angle, which, outcome, at_end=False):
        return self.sym.constraint(
            f"{which} foot above the ground",
            x,
            self.clearance(hip, angle),
            outcome,
            at_end=at_end,
            unit="m",
            source="the gait's phase sequence (Poulakakis et al. 2006, Fig. 2)",
        )

    def body_falls(self, x, hips, doc):
        return fall(
            self.sym, x, "falls (a hip reaches the ground)", ca.fmin(hips[0][1], hips[1][1]), doc
        )

    def flight(self, name, x, ending, falls, angles, constraints=()):
        """A ballistic phase, both feet in the air (drawn at ``angles`` = back, front): it ends
        with ``ending`` or with a hip reaching the ground (``falls``: in words)."""
        back, front = self.hips(x)
        return Phase(
            name,
            _FLIGHT,
            ballistic_flow(self.sym, x, self.g, vertical=1),
            (ending, self.body_falls(x, (back, front), falls)),
            {"energy": self.energy(x, [])},
            points=self.points(x, [(back, None, angles[0]), (front, None, angles[1])]),
            point_names=POINT_NAMES,
            constraints=constraints,
        )

    def single_stance(self, leg, target, angles, constraints=lambda x, back, front: ()):
        """The stance on the ``leg`` ("back" or "front") alone, ending at its liftoff (into phase
        ``target``) or with a hip reaching the ground; ``constraints(x, back, front)`` adds
        conditions after the leg's compression."""
        x = _stance_states(f"{leg}_foot")
        back, front = self.hips(x)
        hip, foot = (back if leg == "back" else front), x[6]
        feet = [(back, foot if leg == "back" else None), (front, foot if leg == "front" else None)]
        liftoff = self.liftoff(
            f"{leg} liftoff", x, hip, foot, (), target, f"{leg} leg at rest length, extending"
        )
        return Phase(
            f"{leg} stance",
            (*_FLIGHT, f"{leg}_foot"),
            self.flow(x, [(hip, foot)]),
            (
                liftoff,
                self.body_falls(x, (back, front), f"a hip reaches the ground in {leg} stance"),
            ),
            {"energy": self.energy(x, [(hip, foot)])},
            points=self.points(x, [(h, f, a) for (h, f), a in zip(feet, angles, strict=True)]),
            point_names=POINT_NAMES,
            constraints=(self.compressive(x, hip, foot, leg), *constraints(x, back, front)),
        )

    def points(self, x, feet):
        """Drawing: back hip, front hip, and each foot (on the ground or held in flight)."""
        return _drawing(self.sym, x, self.hips(x), self.l0, feet)

    def apex_section(self, x, coordinates):
        top = apex(
            self.sym,
            x,
            x[4],  # ż = 0, falling
            ca.vertcat(0, x[1:6]),  # x measured from the apex
            doc="top of the flight, ż = 0 falling; x is measured from here on",
        )
        s = ca.SX.sym("s", len(coordinates))
        z = s[0]
        phi, phid = (s[1], s[2]) if len(coordinates) == 3 else (0, 0)
        speed = ca.sqrt(
            ca.fmax(2 * (self.E - self.m * self.g * z - 0.5 * self.I * phid**2) / self.m, 0)
        )
        if len(coordinates) == 3:
            doc = (
                "apex: z_dot = 0, x = 0, "
                "x_dot = sqrt(2 (energy − mass·gravity·z − ½ inertia·phi_dot²)/mass)"
            )
        else:
            doc = (
                "pitch-free apex: z_dot = 0, x = 0, phi = phi_dot = 0, "
                "x_dot = sqrt(2 (energy/mass − gravity·z))"
            )
        section = Section(coordinates, self.sym.lift(s, ca.vertcat(0, z, phi, speed, 0, phid)), doc)
        return top, section


def _flight_states():
    return Symbols.states(*_FLIGHT)[0]


def _stance_states(*feet):
    return Symbols.states(*_FLIGHT, *feet)[0]


@dataclass(frozen=True)
class _QuadrupedBase(HybridModel):
    """Shared parameters of the planar quadruped's gaits (Scout II, Poulakakis et al. 2006)."""

    state_units = _UNITS
    reference = (
        "Poulakakis, Papadopoulos & Buehler 2006 (IJRR 25(3)); Raibert 1986; "
        "Blickhan 1989 (the spring leg)"
    )
    drawing = (("back_foot", "back_hip", "front_hip", "front_foot"),)
    mesh = (6, 4)
    max_phase_time: ClassVar[float] = 5.0

    mass: float = mass_parameter(20.865, "body mass m", _PAPER)
    inertia: float = parameter(
        1.3, unit="kg*m^2", low=0.0, high=1e4, low_open=True,
        doc="pitch moment of inertia I about the COM", source=_PAPER,
    )  # fmt: skip
    half_length: float = length_parameter(0.276, "hip distance L from the COM (hips at ±L)", _PAPER)
    rest_length: float = length_parameter(0.323, "leg rest length l0", _PAPER)
    stiffness: float = stiffness_parameter(3520.0, "leg stiffness k (each sagittal leg)", _PAPER)
    gravity: float = gravity_parameter()

    def _touchdown_heights(self) -> list[float]:
        raise NotImplementedError

    def check(self) -> None:
        top = self.energy / (self.mass * self.gravity)
        low = max(self._touchdown_heights())
        if top <= low:
            raise ParameterError(
                f"{self.name}: `energy` = {self.energy:g} J puts the highest apex, E/(m g) = "
                f"{top:.4g} m, below the touchdown height l0·cos θ = {low:.4g} m: no foot can "
                f"reach "
                f"the ground from an apex; raise `energy` or the touchdown angle"
            )

    def apex_speed(self, z: float, phi_dot: float = 0.0) -> float:
        """Forward speed ``ẋ = sqrt(2 (E − m g z − ½ I φ̇²)/m)`` (m/s) at an apex."""
        return math.sqrt(
            max(
                2
                * (self.energy - self.mass * self.gravity * z - 0.5 * self.inertia * phi_dot**2)
                / self.mass,
                0.0,
            )
        )

    def section_limits(self) -> dict[str, tuple[float, float, str]]:
        """An apex cannot be higher than ``E/(m g)``, where no forward speed is left."""
        top = self.energy / (self.mass * self.gravity)
        return {
            "z": (
                -math.inf,
                top,
                f"the energy height E/(m g) = {top:.6g} m (energy "
                f"{self.energy:g} J); raise `energy` for a higher apex",
            )
        }


@dataclass(frozen=True)
class PlanarQuadruped(_QuadrupedBase):
    """Planar quadruped, the **bound**: flight state ``x, z`` (m), ``phi`` (rad), rates; stance
    adds the foot position ``back_foot``/``front_foot`` (m); per-step inputs the back and front
    touchdown angles (rad from vertical)."""

    name = "planar_quadruped"
    title = "Planar quadruped (Scout II template), bounding"
    declared_states = _FLIGHT
    declared_coordinates = ("z", "phi", "phi_dot")
    declared_section_doc = (
        "apex: z_dot = 0, x = 0, "
        "x_dot = sqrt(2 (energy − mass·gravity·z − ½ inertia·phi_dot²)/mass)"
    )
    inputs = ("back_touchdown_angle", "front_touchdown_angle")
    input_units = ("rad", "rad")
    input_bounds: ClassVar[dict[str, tuple[float, float]]] = {
        "back_touchdown_angle": (-math.pi / 2, math.pi / 2),
        "front_touchdown_angle": (-math.pi / 2, math.pi / 2),
    }

    back_touchdown_angle: float = _touchdown_angle("back")
    front_touchdown_angle: float = _touchdown_angle("front")
    energy: float = _energy()

    def _touchdown_heights(self):
        return [
            self.rest_length * math.cos(a)
            for a in (self.back_touchdown_angle, self.front_touchdown_angle)
        ]

    def nominal_input(self) -> np.ndarray:
        """The touchdown-angle parameters (rad)."""
        return np.array([self.back_touchdown_angle, self.front_touchdown_angle])

    def default_start(self) -> dict[str, float]:
        """Near the (unstable) bound at the defaults: z = 0.3182 m, φ = 0, φ̇ = 5.551 rad/s."""
        return {"z": 0.318, "phi": 0.0, "phi_dot": 5.55}

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        legs = _Legs(sym)
        tb, tf = sym.input("back_touchdown_angle"), sym.input("front_touchdown_angle")
        pb, pf = sym.back_touchdown_angle, sym.front_touchdown_angle  # drawing only

        # 0 descent: apex → back touchdown, front foot above the ground
        xd = _flight_states()
        back, front = legs.hips(xd)
        descent = legs.flight(
            "descent",
            xd,
            legs.touchdown(
                "back touchdown",
                xd,
                back,
                tb,
                (),
                1,
                "back foot reaches the ground: z_back − l0 cos θ_b = 0, falling",
            ),
            "a hip reaches the ground in flight",
            (pb, pf),
            (legs.above(xd, front, tf, "front", "front foot touches down first (not this bound)"),),
        )
        # 1 back stance, the front foot above the ground
        back_stance = legs.single_stance(
            "back",
            2,
            (pb, pf),
            lambda x, back, front: (
                legs.above(
                    x,
                    front,
                    tf,
                    "front",
                    "front foot touches down during back stance (double stance: not this bound)",
                ),
            ),
        )
        # 2 flight between: back liftoff → front touchdown
        xm = _flight_states()
        front = legs.hips(xm)[1]
        touchdown = legs.touchdown(
            "front touchdown",
            xm,
            front,
            tf,
            (),
            3,
            "front foot reaches the ground: z_front − l0 cos θ_f = 0, falling",
        )
        middle = legs.flight(
            "flight", xm, touchdown, "a hip reaches the ground in flight", (pb, pf)
        )
        # 3 front stance
        front_stance = legs.single_stance("front", 4, (pb, pf))
        # 4 ascent → apex
        xa = _flight_states()
        top, section = legs.apex_section(xa, ("z", "phi", "phi_dot"))
        ascent = legs.flight("ascent", xa, top, "lifted off falling: no apex", (pb, pf))
        return (descent, back_stance, middle, front_stance, ascent), section


@dataclass(frozen=True)
class PlanarQuadrupedPronk(_QuadrupedBase):
    """Planar quadruped, the **pronk** on its invariant pitch-free set: apex height ``z`` (m) the
    one section coordinate; per-step input the common touchdown angle (rad from vertical)."""

    name = "planar_quadruped_pronk"
    title = "Planar quadruped (Scout II template), pronking"
    declared_states = _FLIGHT
    declared_coordinates = ("z",)
    declared_section_doc = (
        "pitch-free apex: z_dot = 0, x = 0, phi = phi_dot = 0, "
        "x_dot = sqrt(2 (energy/mass − gravity·z))"
    )
    inputs = ("touchdown_angle",)
    input_units = ("rad",)
    input_bounds: ClassVar[dict[str, tuple[float, float]]] = {"touchdown_angle": (0.0, math.pi / 2)}

    touchdown_angle: float = parameter(
        0.25, unit="rad", low=0.0, high=math.pi / 2, high_open=True,
        doc="nominal touchdown angle of both legs from vertical",
        source="chosen: a passive pronk exists there "
        "(the SLIP(2k) gait, tests/test_planar_quadruped.py)",
    )  # fmt: skip
    energy: float = _energy()

    def _touchdown_heights(self):
        return [self.rest_length * math.cos(self.touchdown_angle)]

    def nominal_input(self) -> np.ndarray:
        """The touchdown-angle parameter (rad)."""
        return np.array([self.touchdown_angle])

    def default_start(self) -> dict[str, float]:
        """Near the (unstable) pronk at the defaults: z = 0.3975 m."""
        return {"z": 0.36}

    def existence_note(self) -> str | None:
        """The pronk is the SLIP of stiffness 2k (same mass, energy, angle, rest length)."""
        return (
            f"the pitch-free pronk is the SLIP with stiffness 2k = {2 * self.stiffness:g} N/m, "
            f"mass {self.mass:g} kg, energy {self.energy:g} J, rest length {self.rest_length:g} m "
            f"and touchdown angle {self.touchdown_angle:g} rad: it exists where that SLIP runs"
        )

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        legs = _Legs(sym)
        th = sym.input("touchdown_angle")
        pd = sym.touchdown_angle
        # 0 descent: both feet reach the ground together (φ = 0: both hips at height z)
        xd = _flight_states()
        back, front = legs.hips(xd)
        foot_b = back[0] + legs.l0 * ca.sin(th)
        foot_f = front[0] + legs.l0 * ca.sin(th)
        touchdown = Transition(
            name="touchdown",
            guard=sym.function("guard", xd, legs.clearance(back, th)),
            direction=-1,
            reset=sym.function("reset", xd, ca.vertcat(xd, foot_b, foot_f)),
            target=1,
            impact=False,
            doc="both feet reach the ground (pitch-free: z − l0 cos θ = 0, falling)",
        )
        descent = legs.flight("descent", xd, touchdown, "apex below touchdown height", (pd, pd))
        # 1 double stance
        xs = _stance_states("back_foot", "front_foot")
        back, front = legs.hips(xs)
        fb, ff = xs[6], xs[7]
        stance_legs = [(back, fb), (front, ff)]
        liftoff = Transition(
            name="liftoff",
            guard=sym.function("guard", xs, legs.leg(xs, back, fb)[2] - legs.l0),
            direction=+1,
            reset=sym.function("reset", xs, xs[:6]),
            target=2,
            impact=False,
            doc="both legs at rest length, extending (pitch-free: the legs are equal)",
        )
        stance = Phase(
            "double stance",
            (*_FLIGHT, "back_foot", "front_foot"),
            legs.flow(xs, stance_legs),
            (liftoff, legs.body_falls(xs, (back, front), "a hip reaches the ground in stance")),
            {"energy": legs.energy(xs, stance_legs)},
            points=legs.points(xs, [(back, fb, pd), (front, ff, pd)]),
            point_names=POINT_NAMES,
            constraints=(
                legs.compressive(xs, back, fb, "back"),
                legs.compressive(xs, front, ff, "front"),
            ),
        )
        # 2 ascent → apex
        xa = _flight_states()
        top, section = legs.apex_section(xa, ("z",))
        ascent = legs.flight("ascent", xa, top, "lifted off falling: no apex", (pd, pd))
        return (descent, stance, ascent), section
