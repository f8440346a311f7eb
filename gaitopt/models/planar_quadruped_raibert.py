"""The planar quadruped's bound under Raibert's three-part controller, one virtual leg at a time.

Raibert, Chepponis & Brown 1986, "Running on four legs as though they were one" (IEEE J.
Robotics and Automation 2(2)): in a bound the two legs of a pair act as one *virtual leg*, and the
back and front virtual legs take turns; each is run by the one-legged hopper's three-part
controller (Raibert 1986, *Legged Robots That Balance*, ch. 2–3; the planar hopper is
``gaitopt.models.raibert_hopper``).  The body is the Scout II template of
``gaitopt.models.planar_quadruped`` (Poulakakis, Papadopoulos & Buehler 2006): mass ``m``, pitch
inertia ``I`` about the COM, hips at ``±L`` along the body axis, a massless spring leg of
stiffness ``k`` at each hip; same coordinates (COM ``x, z``, pitch ``phi`` nose up; the leg
angle ``θ`` from vertical, foot ahead of the hip for ``θ > 0``).

**The controller, inside the dynamics (its gains are parameters):**

* *hopping height* by thrust: a stance leg's rest length is ``l0 + δ`` (``δ`` = ``thrust``), and
  the leg has a viscous loss ``c``; the force along the leg is ``F = k (l0 + δ − r) − c ṙ``.
  Each stance gives about ``½ k δ²`` and the loss takes energy away: the hop settles where they
  balance (Raibert 1986 §2.2's fixed thrust, lumped over the stance as in ``raibert_hopper``);
* *forward speed* by foot placement: at touchdown each leg's foot is ``x_f`` ahead of its hip,

      x_f = ẋ T_s/2 + k_ẋ (ẋ − ẋ_d),   θ_td = asin(x_f / l0),

  (Raibert 1986 eq. 2.4; ``ẋ`` the COM's forward speed, constant in flight).  ``T_s`` is the
  expected stance time of one virtual leg, the half period of the effective mass at a hip on the
  spring, ``T_s = π sqrt(m_h/k)``, ``m_h = m I/(I + m L²)`` (a vertical force at a hip moves it
  with ``1/m + L²/I`` per newton: the body both translates and pitches);
* *body attitude* by the stance hip's servo, torque on the body ``τ = −k_p φ − k_v φ̇``
  (Raibert 1986 eq. 2.5, ``φ_d = 0``; Raibert et al. 1986 servo the pitch through whichever
  virtual leg is on the ground).  The massless leg balances the hip torque with a ground force
  ``−τ/r`` across itself (about the hip: ``d × G = −τ`` for the leg vector ``d`` = hip − foot).

**Stance equations** (Newton–Euler; ``n = (−d_z, d_x)/r`` the leg's normal)::

    G = F d/r − (τ/r) n,     m ẍ = G_x,     m z̈ = G_z − m g,     I φ̈ = (h − c) × G + τ.

The ground force acts at the foot and the hip torque is internal, so the angular momentum about
the foot, ``H = I φ̇ + m (c − foot) × v``, changes only by gravity's moment, ``Ḣ = −m g
(x − x_foot)``; the energy ``E = ½ m |v|² + ½ I φ̇² + m g z + ½ k (l0 + δ − r)²`` changes by the
loss and the hip's work, ``Ė = −c ṙ² + τ (φ̇ − ω_leg)``, ``ω_leg = d × ḋ / r²`` (both checked
in tests/test_planar_quadruped_raibert.py, not used in the derivation).

**The bound** (Poulakakis et al. 2006, Fig. 2): apex → descent → *back stance* → flight → *front
stance* → ascent → apex.  A leg in flight is held at the law's angle for the current ``ẋ``;
lift-off when its force falls to zero, ``F = 0`` decreasing; the massless leg then returns to
``l0``.  The front foot must stay above the ground until its touchdown (declared constraints, as
in ``planar_quadruped``).  Section: the apex, ``ż = 0`` falling, ``x`` reset to 0; coordinates
``z, phi, x_dot, phi_dot`` (four multipliers: nothing is conserved over a stride, and the servo
holds the absolute pitch, so none is trivial).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..errors import ParameterError
from ..hybrid import Phase, Section, Symbols, Transition
from .blocks import apex, ballistic_flow, fall
from .planar_quadruped import _FLIGHT, POINT_NAMES, _drawing, _hips, _QuadrupedBase
from .raibert_hopper import (
    attitude_damping_parameter,
    attitude_gain_parameter,
    desired_speed_parameter,
    leg_loss_parameter,
    speed_gain_parameter,
    thrust_parameter,
)

__all__ = ["PlanarQuadrupedRaibert", "touchdown_angle_law"]

_RCB = "Raibert, Chepponis & Brown 1986, 'Running on four legs as though they were one'"
_RAIBERT = "Raibert 1986, Legged Robots That Balance"
_SERVO = _RCB + " (pitch servoed in stance); value chosen for a stable bound"
#: Largest |x_f| / l0 the foot-placement law may ask for (the leg stays below the hip).
_MAX_REACH = 0.95


def stance_time(s) -> float | ca.SX:
    """``T_s = π sqrt(m_h/k)``, ``m_h = m I/(I + m L²)`` (s): expected stance time."""
    sqrt = ca.sqrt if isinstance(s, Symbols) else math.sqrt
    m_h = s.mass * s.inertia / (s.inertia + s.mass * s.half_length**2)
    return math.pi * sqrt(m_h / s.stiffness)


def foot_placement(s, x_dot, t_s=None):
    """Raibert's ``x_f = ẋ T_s/2 + k_ẋ (ẋ − ẋ_d)`` (m ahead of the hip); ``T_s`` the bound's
    :func:`stance_time` unless given."""
    t_s = stance_time(s) if t_s is None else t_s
    return x_dot * t_s / 2 + s.k_speed * (x_dot - s.desired_speed)


def touchdown_angle_law(s, x_dot, t_s=None):
    """``θ_td = asin(x_f / l0)`` (rad, clipped to ±asin 0.95); on CasADi symbols or floats."""
    ratio = foot_placement(s, x_dot, t_s) / s.rest_length
    if isinstance(ratio, (ca.SX, ca.MX)):
        return ca.asin(ca.fmax(-_MAX_REACH, ca.fmin(_MAX_REACH, ratio)))
    return math.asin(max(-_MAX_REACH, min(_MAX_REACH, float(ratio))))


class _Legs:
    """The symbolic pieces of the controlled bound (built inside ``build``)."""

    def __init__(self, sym: Symbols, t_s=None):
        self.sym, self.t_s = sym, t_s  # t_s: the law's stance time (None: the bound's)
        self.m, self.I, self.L, self.g = sym.mass, sym.inertia, sym.half_length, sym.gravity
        self.l0, self.k, self.c, self.delta = (
            sym.rest_length,
            sym.stiffness,
            sym.damping,
            sym.thrust,
        )

    def hips(self, x):
        return _hips((x[0], x[1], x[2], x[3], x[4], x[5], self.L))

    def leg(self, hip, foot):
        """Leg vector ``d`` (hip − foot), length ``r``, rate ``ṙ`` and force ``F`` (N)."""
        dx, dz = hip[0] - foot, hip[1]
        r = ca.sqrt(dx**2 + dz**2)
        r_dot = (dx * hip[2] + dz * hip[3]) / r
        return dx, dz, r, r_dot, self.k * (self.l0 + self.delta - r) - self.c * r_dot

    def torque(self, x):
        """The attitude servo's torque on the body ``τ = −k_p φ − k_v φ̇`` (N m)."""
        return -self.sym.k_attitude * x[2] - self.sym.d_attitude * x[5]

    def flow(self, x, stance):
        """Newton–Euler with the stance legs ``[(hip, foot), ...]``; the servo's torque is
        shared equally by them.  The feet (states after the six body states) stay put."""
        tau = self.torque(x) / len(stance)
        fx, fz, moment = 0, -self.m * self.g, 0
        for hip, foot in stance:
            dx, dz, r, _, F = self.leg(hip, foot)
            # G = F d/r − (τ/r) n with n = (−d_z, d_x)/r (module docstring)
            gx = F * dx / r + tau * dz / r**2
            gz = F * dz / r - tau * dx / r**2
            fx, fz = fx + gx, fz + gz
            moment = moment + (hip[0] - x[0]) * gz - (hip[1] - x[1]) * gx + tau
        rates = [x[3], x[4], x[5], fx / self.m, fz / self.m, moment / self.I]
        return self.sym.function("flow", x, ca.vertcat(*rates, *([0] * len(stance))))

    def ballistic(self, x):
        """Flight: ẍ = 0, z̈ = −g, φ̈ = 0."""
        return ballistic_flow(self.sym, x, self.g, vertical=1)

    def flight_energy(self, x):
        e = (
            0.5 * self.m * (x[3] ** 2 + x[4] ** 2)
            + 0.5 * self.I * x[5] ** 2
            + self.m * self.g * x[1]
        )
        return self.sym.conserved("energy", x, e)

    def clearance(self, hip, angle):
        return hip[1] - self.l0 * ca.cos(angle)

    def angle(self, x):
        return touchdown_angle_law(self.sym, x[3], self.t_s)

    def touchdown(self, name, x, hip, target, doc):
        foot = hip[0] + self.l0 * ca.sin(self.angle(x))
        return Transition(
            name=name,
            guard=self.sym.function("guard", x, self.clearance(hip, self.angle(x))),
            direction=-1,
            reset=self.sym.function("reset", x, ca.vertcat(x[:6], foot)),
            target=target,
            impact=False,
            doc=doc,
        )

    def liftoff(self, name, x, hip, foot, target, doc):
        return Transition(
            name=name,
            guard=self.sym.function("guard", x, self.leg(hip, foot)[4]),
            direction=-1,
            reset=self.sym.function("reset", x, x[:6]),
            target=target,
            impact=False,
            doc=doc,
        )

    def front_above(self, x, front, outcome):
        return self.sym.constraint(
            "front foot above the ground",
            x,
            self.clearance(front, self.angle(x)),
            outcome,
            unit="m",
            source="the gait's phase sequence (Poulakakis et al. 2006, Fig. 2)",
        )

    def apex(self, x):
        """The top of the flight, ``ż = 0`` falling; ``x`` is measured from there on."""
        return apex(
            self.sym,
            x,
            x[4],  # ż = 0, falling
            ca.vertcat(0, x[1:6]),  # x measured from the apex
            doc="top of the flight, ż = 0 falling; x is measured from here on",
        )

    def falls(self, x, hips, doc):
        return fall(
            self.sym, x, "falls (a hip reaches the ground)", ca.fmin(hips[0][1], hips[1][1]), doc
        )

    def points(self, x, back_foot=None, front_foot=None):
        hips, th = self.hips(x), self.angle(x)
        feet = [(hips[0], back_foot, th), (hips[1], front_foot, th)]
        return _drawing(self.sym, x, hips, self.l0, feet)


_NAMES = POINT_NAMES


@dataclass(frozen=True)
class PlanarQuadrupedRaibert(_QuadrupedBase):
    """Planar quadruped bounding under Raibert's controller per virtual leg: flight state
    ``x, z`` (m), ``phi`` (rad), rates; stance adds the foot position (m); section at the apex,
    coordinates ``z, phi, x_dot, phi_dot``; no per-step input (the controller is in the
    dynamics)."""

    name = "planar_quadruped_raibert"
    title = "Planar quadruped bounding, Raibert's controller per virtual leg"
    reference = (
        "Raibert, Chepponis & Brown 1986; Raibert 1986; Poulakakis, Papadopoulos & Buehler 2006"
    )
    declared_states = _FLIGHT
    declared_coordinates = ("z", "phi", "x_dot", "phi_dot")
    declared_section_doc = "apex: z_dot = 0, x = 0"

    damping: float = leg_loss_parameter(
        20.0,
        "leg viscous loss c (damping ratio c/(2 sqrt(k m_h)) = 0.055, m_h = m I/(I + m L²))",
        "a lightly damped leg, as raibert_hopper's (Raibert 1986 §2.2)",
    )
    thrust: float = thrust_parameter(
        0.06,
        "thrust δ: a stance leg's rest length is l0 + δ (height control)",
        "chosen: ½ k δ² = 6.3 J a stance; with the default loss and gains the bound "
        "settles at a 0.38 m apex (found by simulating 40 strides, then solved)",
    )
    desired_speed: float = desired_speed_parameter(
        "chosen: of the passive bounds' speeds, 0–1.12 m/s (problems/planar_quadruped.py)"
    )
    k_speed: float = speed_gain_parameter(
        0.08, _RAIBERT + ", §2.3 (gains of a few hundredths of a second)", low=0.0
    )
    k_attitude: float = attitude_gain_parameter(20.0, _SERVO, positive=True)
    d_attitude: float = attitude_damping_parameter(2.0, _SERVO)

    def check(self) -> None:
        if self.thrust == 0 and self.damping == 0:
            raise ParameterError(
                f"{self.name}: `thrust` = 0 and `damping` = 0 make the leg force zero at "
                "touchdown (liftoff at once); give the leg a thrust or a loss"
            )

    def section_limits(self) -> dict[str, tuple[float, float, str]]:
        return {}

    def existence_note(self) -> str | None:
        """What sets the gait (added to a failed search)."""
        return (
            f"controlled bound: the thrust's ½ k δ² = {0.5 * self.stiffness * self.thrust**2:.3g} "
            f"J a stance must balance the leg's loss, the foot placement must stay within "
            f"{_MAX_REACH:g}·l0 of the hip, and the back leg must land first ({_RCB})"
        )

    @staticmethod
    def _stance_time(s):
        """The law's expected stance time on symbols or values (the bound's virtual leg)."""
        return stance_time(s)

    @property
    def expected_stance_time(self) -> float:
        """``T_s`` (s), the foot-placement law's expected stance time (bound: ``π sqrt(m_h/k)``,
        ``m_h = m I/(I + m L²)``)."""
        return float(self._stance_time(self))

    def foot_placement(self, x_dot: float) -> float:
        """Raibert's ``x_f`` (m ahead of the hip at touchdown) at forward speed ``x_dot``."""
        return float(foot_placement(self, x_dot, self.expected_stance_time))

    def touchdown_angle(self, x_dot: float) -> float:
        """``θ_td = asin(x_f / l0)`` (rad from vertical, foot ahead of the hip)."""
        return touchdown_angle_law(self, x_dot, self.expected_stance_time)

    def default_start(self) -> dict[str, float]:
        """Near the (stable) controlled bound at the defaults: z = 0.38199 m, φ = 0.01420 rad,
        ẋ = 0.82376 m/s, φ̇ = 4.0746 rad/s."""
        return {"z": 0.382, "phi": 0.0142, "x_dot": 0.824, "phi_dot": 4.075}

    def nominal_input(self) -> np.ndarray:
        """No per-step input: the controller is in the dynamics."""
        return np.zeros(0)

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        legs = _Legs(sym, cls._stance_time(sym))

        def flight_phase(name, x, event, constraints=()):
            back, front = legs.hips(x)
            return Phase(
                name,
                _FLIGHT,
                legs.ballistic(x),
                (event, legs.falls(x, (back, front), f"a hip reaches the ground in {name}")),
                {"energy": legs.flight_energy(x)},
                points=legs.points(x),
                point_names=_NAMES,
                constraints=constraints,
            )

        def stance_phase(name, foot_name, which, target):
            x = Symbols.states(*_FLIGHT, foot_name)[0]
            back, front = legs.hips(x)
            hip = back if which == "back" else front
            lift = legs.liftoff(
                f"{which} liftoff",
                x,
                hip,
                x[6],
                target,
                f"{which} leg force k (l0 + δ − r) − c ṙ falls to zero",
            )
            feet = {"back_foot": x[6]} if which == "back" else {"front_foot": x[6]}
            constraints = ()
            if which == "back":
                constraints = (
                    legs.front_above(
                        x,
                        front,
                        "front foot touches down during back stance (double stance: not this "
                        "bound)",
                    ),
                )
            return Phase(
                name,
                (*_FLIGHT, foot_name),
                legs.flow(x, [(hip, x[6])]),
                (lift, legs.falls(x, (back, front), f"a hip reaches the ground in {name}")),
                {},  # thrust, loss and hip work: nothing conserved
                points=legs.points(x, **feet),
                point_names=_NAMES,
                constraints=constraints,
            )

        xd = _flight()
        back, front = legs.hips(xd)
        descent = flight_phase(
            "descent",
            xd,
            legs.touchdown(
                "back touchdown",
                xd,
                back,
                1,
                "back foot reaches the ground: z_back − l0 cos θ_td = 0, falling, θ_td from "
                "Raibert's foot placement",
            ),
            (legs.front_above(xd, front, "front foot touches down first (not this bound)"),),
        )
        xm = _flight()
        back, front = legs.hips(xm)
        middle = flight_phase(
            "flight",
            xm,
            legs.touchdown(
                "front touchdown",
                xm,
                front,
                3,
                "front foot reaches the ground: z_front − l0 cos θ_td = 0, falling",
            ),
        )
        xa = _flight()
        ascent = flight_phase("ascent", xa, legs.apex(xa))
        s = ca.SX.sym("s", 4)
        section = Section(
            ("z", "phi", "x_dot", "phi_dot"),
            sym.lift(s, ca.vertcat(0, s[0], s[1], s[2], 0, s[3])),
            "apex: z_dot = 0, x = 0",
        )
        phases = (
            descent,
            stance_phase("back stance", "back_foot", "back", 2),
            middle,
            stance_phase("front stance", "front_foot", "front", 4),
            ascent,
        )
        return phases, section


def _flight():
    return Symbols.states(*_FLIGHT)[0]
