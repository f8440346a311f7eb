"""The planar Raibert hopper: a body with pitch inertia on a light springy leg, Raibert's
three-part controller in the loop.

Raibert 1986, *Legged Robots That Balance* (MIT Press), ch. 2–3; Raibert, Brown & Chepponis 1984,
"Experiments in balance with a 2D one-legged hopping machine" (ASME J. Dyn. Sys. Meas. Control
106).  The body (mass ``M``, pitch inertia ``J`` about its centre of mass, which is at the hip)
rides on a massless leg: a spring of stiffness ``k`` with viscous loss ``c``, whose rest length is
``l0`` in flight and ``l0 + δ`` in stance (``δ`` = ``thrust``).  A hip actuator between body and
leg positions the massless leg in flight (kinematically: no torque on the body) and servoes the
body's pitch in stance.

**Raibert's three-part controller**, inside the dynamics (its gains are parameters):

* *hopping height* by a fixed thrust: the rest length is ``l0 + δ`` throughout stance, so each
  stance gives the body ``½ k δ²`` and the leg's loss takes energy away; the apex height settles
  where they balance (Raibert 1986 §2.2 uses a fixed thrust, here lumped over the whole stance);
* *forward speed* by foot placement: at touchdown the foot is ``x_f`` ahead of the hip,

      x_f = ẋ T_s/2 + k_ẋ (ẋ − ẋ_d),    T_s = π sqrt(M/k)

  (Raibert 1986 eq. 2.4; ``T_s`` the expected stance time, here the half period of the body on the
  spring; ``ẋ`` is constant in flight), i.e. the touchdown angle ``θ_td = asin(x_f / l0)``;
* *body attitude* by the hip servo in stance, ``τ = −k_p (φ − φ_d) − k_v φ̇`` with ``φ_d = 0``
  (Raibert 1986 eq. 2.5).

One hop, from apex to apex, is three phases:

* **descent** (flight, state ``x, z, phi, x_dot, z_dot, phi_dot``: hip position, ``x`` from the
  last apex, ``z`` above the ground; body pitch ``phi``, counter-clockwise = nose up): ballistic,
  ``ẍ = 0, z̈ = −g, φ̈ = 0``.  **Touchdown** when the foot reaches the ground,
  ``z − l0 cos θ_td = 0`` with ``z`` falling.
* **stance** (polar coordinates of the hip about the foot, state ``r, theta, phi, r_dot,
  theta_dot, phi_dot``; ``theta`` from vertical, positive when the hip is ahead of the foot, so
  touchdown is at ``theta = −θ_td``).  The massless leg carries the spring force
  ``F = k (l0 + δ − r) − c ṙ`` along itself and, to balance the hip torque about the hip, a
  ground force ``τ / r`` across itself; the body gets both and the torque ``τ``::

      M (r̈ − r θ̇²)     = F − M g cos θ
      M (r θ̈ + 2 ṙ θ̇)  = τ / r + M g sin θ
      J φ̈              = τ

  The ground force acts at the foot and the hip torque is internal, so the angular momentum
  about the foot (counter-clockwise), ``H = J φ̇ − M r² θ̇``, changes only by gravity's moment,
  ``Ḣ = −M g r sin θ`` (checked in the tests; not used in the derivation).
  **Liftoff** when the leg force falls to zero, ``F = 0`` decreasing.
* **ascent** (flight, ``x`` from the foot): ballistic up to the **apex**, ``ż = 0`` falling, where
  ``x`` is reset to 0 — the Poincaré section.

Section: the apex (``x = 0``, ``ż = 0``), coordinates ``z, phi, x_dot, phi_dot``: four
multipliers.  Nothing is conserved over a hop (thrust, loss and hip work), and no coordinate is
cyclic (the attitude servo holds the absolute pitch), so none is trivial.

Falls are terminal transitions: the hip reaches the ground (apex below the touchdown height, in
stance, or no apex after liftoff) and the body tips over (``|φ| = π/2``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import casadi as ca
import numpy as np

from ..errors import ParameterError
from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..parameters import gravity_parameter, parameter
from .blocks import apex, ballistic_flow, fall, hip_about_foot, leg_touchdown
from .quantities import length_parameter, mass_parameter, state_units, stiffness_parameter

__all__ = ["RaibertHopper", "FLIGHT_STATES", "STANCE_STATES"]

_RAIBERT = "Raibert 1986, Legged Robots That Balance"
_SIZE = "illustrative, of the size of Raibert's planar one-legged machine (Raibert et al. 1984)"
FLIGHT_STATES = ("x", "z", "phi", "x_dot", "z_dot", "phi_dot")
STANCE_STATES = ("r", "theta", "phi", "r_dot", "theta_dot", "phi_dot")
#: Default proportional gain of the attitude servo (N m/rad).
_DEFAULT_K_ATTITUDE = 400.0
#: Largest |x_f| / l0 the foot-placement law may ask for (the leg stays below the hip).
_MAX_REACH = 0.95

# -- the controller's parameters, declared alike by the Raibert-controlled quadrupeds ------------
_PLACEMENT = "of the foot-placement law x_f = ẋ T_s/2 + k_ẋ (ẋ − ẋ_d)"


def leg_loss_parameter(default: float, doc: str, source: str) -> Any:
    """The leg's viscous loss ``c`` (N s/m), range [0, 1e5]."""
    return parameter(default, unit="N s/m", doc=doc, source=source, low=0.0, high=1e5)


def thrust_parameter(default: float, doc: str, source: str) -> Any:
    """The thrust ``δ`` (m) added to the leg's rest length in stance, range [0, 1]."""
    return parameter(default, unit="m", doc=doc, source=source, low=0.0, high=1.0)


def desired_speed_parameter(source: str) -> Any:
    """The desired forward speed ``ẋ_d`` (m/s) of the foot-placement law, default 1 m/s, range
    [−10, 10]."""
    doc = "desired forward speed ẋ_d of the foot-placement law"
    return parameter(1.0, unit="m/s", doc=doc, source=source, low=-10.0, high=10.0)


def speed_gain_parameter(default: float, source: str, *, low: float = -1.0) -> Any:
    """The speed gain ``k_ẋ`` (s) of the foot-placement law, range [low, 1] (open at 0)."""
    return parameter(
        default, unit="s", low=low, high=1.0, low_open=low == 0.0,
        doc="speed gain k_ẋ " + _PLACEMENT, source=source,
    )  # fmt: skip


def attitude_gain_parameter(default: float, source: str, *, positive: bool = False) -> Any:
    """The proportional gain ``k_p`` (N m/rad) of the stance attitude servo ``τ = −k_p φ −
    k_v φ̇``, range [0, 1e5] (``k_p`` > 0 when ``positive``)."""
    doc = "proportional gain k_p of the stance attitude servo τ = −k_p φ − k_v φ̇"
    return parameter(
        default, unit="N m/rad", doc=doc, source=source, low=0.0, high=1e5, low_open=positive
    )


def attitude_damping_parameter(default: float, source: str, note: str = "") -> Any:
    """The derivative gain ``k_v`` (N m s/rad) of the stance attitude servo, range [0, 1e5];
    ``note`` follows the doc."""
    doc = "derivative gain k_v of the stance attitude servo" + note
    return parameter(default, unit="N m s/rad", doc=doc, source=source, low=0.0, high=1e5)


def touchdown_angle_law(sym_or_values, x_dot):
    """``θ_td = asin(x_f / l0)``, ``x_f = ẋ T_s/2 + k_ẋ (ẋ − ẋ_d)``, ``T_s = π sqrt(M/k)``;
    works on CasADi symbols (``Symbols``) and on a :class:`RaibertHopper` (floats)."""
    s = sym_or_values
    x_f = foot_placement(s, x_dot)
    ratio = x_f / s.rest_length
    if isinstance(ratio, (ca.SX, ca.MX)):
        return ca.asin(ca.fmax(-_MAX_REACH, ca.fmin(_MAX_REACH, ratio)))
    return math.asin(max(-_MAX_REACH, min(_MAX_REACH, float(ratio))))


def foot_placement(s, x_dot):
    """Raibert's foot placement ``x_f = ẋ T_s/2 + k_ẋ (ẋ − ẋ_d)`` (m ahead of the hip)."""
    sqrt = ca.sqrt if isinstance(s, Symbols) else math.sqrt
    t_s = math.pi * sqrt(s.mass / s.stiffness)
    return x_dot * t_s / 2 + s.k_speed * (x_dot - s.desired_speed)


@dataclass(frozen=True)
class RaibertHopper(HybridModel):
    """Planar Raibert hopper: apex state ``x, z`` (m), ``phi`` (rad), ``x_dot, z_dot`` (m/s),
    ``phi_dot`` (rad/s); stance ``r`` (m), ``theta``, ``phi`` (rad), ``r_dot``, ``theta_dot``,
    ``phi_dot``; section at the apex, coordinates ``z, phi, x_dot, phi_dot``; no per-step input
    (Raibert's controller is inside the dynamics)."""

    name = "raibert_hopper"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("x", "z", "phi", "x_dot", "z_dot", "phi_dot")
    declared_coordinates = ("z", "phi", "x_dot", "phi_dot")
    declared_section_doc = "apex: z_dot = 0, x = 0"
    drawing = (("hip", "foot"), ("tail", "nose"))  # leg and body; other points are helpers
    state_units = {**state_units(x="m", z="m", phi="rad"), **state_units(r="m", theta="rad")}
    title = "Planar Raibert hopper (three-part controller)"
    reference = "Raibert 1986; Raibert, Brown & Chepponis 1984"
    mesh = (4, 4)
    max_phase_time: ClassVar[float] = 5.0

    mass: float = mass_parameter(10.0, "body mass M", _SIZE)
    inertia: float = parameter(
        0.5, unit="kg m^2", low=0.0, high=1e4, low_open=True,
        doc="body pitch inertia J about its centre of mass (at the hip)", source=_SIZE,
    )  # fmt: skip
    rest_length: float = length_parameter(0.5, "leg rest length l0 in flight", _SIZE)
    stiffness: float = stiffness_parameter(
        4000.0,
        ("leg spring stiffness k (k l0/(M g) = 20.4; expected stance time π sqrt(M/k) = 0.157 s)"),
        _SIZE,
    )
    damping: float = leg_loss_parameter(
        20.0,
        "leg viscous loss c (damping ratio c/(2 sqrt(k M)) = 0.05)",
        "a lightly damped leg (the air spring's losses, Raibert 1986 §2.2)",
    )
    thrust: float = thrust_parameter(
        0.04,
        "thrust δ: the leg's rest length in stance is l0 + δ (height control)",
        "sets the hop: ½ k δ² = 3.2 J a hop balances the leg's loss near a 0.1 m hop",
    )
    desired_speed: float = desired_speed_parameter(
        "a brisk hop for this size (Raibert's machines ran at 0.5–2 m/s)"
    )
    k_speed: float = speed_gain_parameter(
        0.05, _RAIBERT + ", §2.3 (gains of a few hundredths of a second)"
    )
    k_attitude: float = attitude_gain_parameter(
        _DEFAULT_K_ATTITUDE,
        "sqrt(k_p/J) = 28 rad/s: the servo settles within a stance (ω T_s = 4.4)",
    )
    d_attitude: float = attitude_damping_parameter(
        20.0, "a well-damped servo", " (damping ratio k_v/(2 sqrt(k_p J)) = 0.71)"
    )
    gravity: float = gravity_parameter()

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        M, J, l0, k, c, delta, g = (
            sym.mass,
            sym.inertia,
            sym.rest_length,
            sym.stiffness,
            sym.damping,
            sym.thrust,
            sym.gravity,
        )
        kp, kv = sym.k_attitude, sym.d_attitude
        bar = ca.sqrt(3 * J / M)  # half-length of a uniform bar with this inertia (drawing only)

        # -- flight: descent from the apex, foot placed by the speed controller --------------
        xf, (x, z, phi, x_dot, z_dot, phi_dot) = sym.states(*FLIGHT_STATES)
        ballistic = ballistic_flow(sym, xf, g, vertical=1)  # ẍ = 0, z̈ = −g, φ̈ = 0
        # z − l0 cos θ_td = 0; polar coordinates of the hip about the foot x + x_f, the body's
        # pitch unchanged.
        touchdown = leg_touchdown(
            sym,
            xf,
            height=z,
            velocity=(x_dot, z_dot),
            length=l0,
            angle=touchdown_angle_law(sym, x_dot),
            carried=((phi,), (phi_dot,)),
            impact=False,  # a massless leg: no velocity changes
            doc="foot reaches the ground: z − l0·cos θ_td = 0, falling, θ_td = asin(x_f/l0) from "
            "Raibert's foot placement; the hip in polar coordinates about the foot",
        )

        def ground(name: str, what: str) -> Transition:
            return fall(sym, xf, name, z, what)

        def tips_over(x_state: ca.SX, pitch: ca.SX) -> Transition:
            return fall(
                sym,
                x_state,
                "body tips over (|phi| = pi/2)",
                ca.cos(pitch),
                "the body's pitch reaches ±90°",
            )

        flight_energy = sym.conserved(
            "energy",
            xf,
            0.5 * M * (x_dot**2 + z_dot**2) + 0.5 * J * phi_dot**2 + M * g * z,
        )

        def flight_points(x_hip: ca.SX, z_hip: ca.SX, below: ca.SX) -> ca.Function:
            # The leg drawn at the parameters' touchdown angle for the desired speed.
            th = touchdown_angle_law(sym, sym.desired_speed)
            return ca.Function(
                "points",
                [xf, sym.p],
                [
                    ca.horzcat(
                        ca.vertcat(x_hip, z_hip),
                        ca.vertcat(x_hip + l0 * ca.sin(th), z_hip - l0 * ca.cos(th)),
                        ca.vertcat(x_hip + bar * ca.cos(phi), z_hip + bar * ca.sin(phi)),
                        ca.vertcat(x_hip - bar * ca.cos(phi), z_hip - bar * ca.sin(phi)),
                        ca.vertcat(x_hip, below),
                    )
                ],
            )

        descent = Phase(
            "descent",
            FLIGHT_STATES,
            ballistic,
            (
                touchdown,
                ground(
                    "apex below touchdown height (hip reaches the ground)",
                    "fires only if touchdown never armed: the apex was below l0·cos θ_td",
                ),
                tips_over(xf, phi),
            ),
            {"energy": flight_energy},
            points=flight_points(x, z, ca.SX(0)),
            point_names=("hip", "foot", "nose", "tail", "origin"),
        )

        # -- stance: polar coordinates about the foot; thrust, loss and the attitude servo ---
        xs, (r, th, phi_s, r_dot, th_dot, phi_dot_s) = sym.states(*STANCE_STATES)
        force = k * (l0 + delta - r) - c * r_dot  # along the leg, pushing the body up
        tau = -kp * phi_s - kv * phi_dot_s  # hip torque on the body (counter-clockwise)
        stance_flow = sym.function(
            "flow",
            xs,
            ca.vertcat(
                r_dot,
                th_dot,
                phi_dot_s,
                r * th_dot**2 + force / M - g * ca.cos(th),
                (tau / (M * r) + g * ca.sin(th) - 2 * r_dot * th_dot) / r,
                tau / J,
            ),
        )
        hip_x, hip_z, hip_xd, hip_zd = hip_about_foot(r, th, r_dot, th_dot)
        liftoff = Transition(
            name="liftoff",
            guard=sym.function("guard", xs, force),  # F = k (l0 + δ − r) − c ṙ = 0, falling
            direction=-1,
            reset=sym.function(
                "reset", xs, ca.vertcat(hip_x, hip_z, phi_s, hip_xd, hip_zd, phi_dot_s)
            ),
            target=2,
            impact=False,
            doc="the leg force falls to zero, k (l0 + δ − r) − c ṙ = 0; Cartesian flight state "
            "with x from the foot (the massless leg then returns to l0)",
        )
        collapses = fall(
            sym,
            xs,
            "falls (hip reaches the ground in stance)",
            hip_z,
            "the hip reaches the foot's level",
        )
        stance_points = ca.Function(
            "points",
            [xs, sym.p],
            [
                ca.horzcat(
                    ca.vertcat(hip_x, hip_z),
                    ca.DM.zeros(2, 1),
                    ca.vertcat(hip_x + bar * ca.cos(phi_s), hip_z + bar * ca.sin(phi_s)),
                    ca.vertcat(hip_x - bar * ca.cos(phi_s), hip_z - bar * ca.sin(phi_s)),
                )
            ],
        )
        stance = Phase(
            "stance",
            STANCE_STATES,
            stance_flow,
            (liftoff, collapses, tips_over(xs, phi_s)),
            {},  # thrust, loss and hip work: nothing conserved
            points=stance_points,
            point_names=("hip", "foot", "nose", "tail"),
        )

        # -- flight: ascent to the apex --------------------------------------------------------
        top = apex(
            sym,
            xf,
            z_dot,  # ż = 0, falling
            ca.vertcat(0, z, phi, x_dot, z_dot, phi_dot),  # x from the apex
            foothold="below_hip",
            doc="top of the flight, ż = 0 falling; x is measured from here on",
        )
        ascent = Phase(
            "ascent",
            FLIGHT_STATES,
            ballistic,
            (
                top,
                ground("falls (no apex after liftoff)", "lifted off falling: no apex"),
                tips_over(xf, phi),
            ),
            {"energy": flight_energy},
            points=flight_points(x, z, ca.SX(0)),
            point_names=("hip", "foot", "nose", "tail", "below_hip"),
        )

        # -- the apex section: x = 0, ż = 0; z, φ, ẋ, φ̇ free -------------------------------
        s = ca.SX.sym("s", 4)
        section = Section(
            ("z", "phi", "x_dot", "phi_dot"),
            sym.lift(s, ca.vertcat(0, s[0], s[1], s[2], 0, s[3])),
            "apex: z_dot = 0, x = 0",
        )
        return (descent, stance, ascent), section

    def check(self) -> None:
        if self.k_attitude == 0:
            raise ParameterError(
                "raibert_hopper: `k_attitude` = 0 leaves the body pitch without a restoring "
                "torque (τ = −k_v φ̇ only, and nothing else depends on φ): every pitch φ is then "
                "a gait, a continuous family with a multiplier exactly 1 and no isolated orbit "
                f"to find; give k_attitude > 0 (default {_DEFAULT_K_ATTITUDE:g} N m/rad)"
            )
        if self.thrust == 0 and self.damping == 0:
            raise ParameterError(
                "raibert_hopper: `thrust` = 0 and `damping` = 0 make the leg force zero at "
                "touchdown (liftoff at once); give the leg a thrust or a loss"
            )

    # -- controller quantities -------------------------------------------------------------------
    @property
    def expected_stance_time(self) -> float:
        """``T_s = π sqrt(M/k)`` (s): the foot-placement law's stance time."""
        return math.pi * math.sqrt(self.mass / self.stiffness)

    def foot_placement(self, x_dot: float) -> float:
        """Raibert's ``x_f = ẋ T_s/2 + k_ẋ (ẋ − ẋ_d)`` (m ahead of the hip at touchdown)."""
        return float(foot_placement(self, x_dot))

    def neutral_point_estimate(self, x_dot: float, stance_time: float | None = None) -> float:
        """Raibert's neutral point ``ẋ T_s / 2`` (m), with ``T_s`` expected unless given."""
        t_s = self.expected_stance_time if stance_time is None else stance_time
        return x_dot * t_s / 2

    def touchdown_angle(self, x_dot: float) -> float:
        """``θ_td = asin(x_f / l0)`` (rad from vertical, foot ahead of the hip)."""
        return touchdown_angle_law(self, x_dot)

    def existence_note(self) -> str | None:
        """What sets the gait (added to a failed search)."""
        return (
            f"Raibert hopper: the thrust's ½ k δ² = {0.5 * self.stiffness * self.thrust**2:.3g} J "
            f"a hop must balance the leg's loss and the foot placement must stay within "
            f"{_MAX_REACH:g}·l0 of the hip ({_RAIBERT})"
        )

    def default_start(self) -> dict[str, float]:
        """Near the gait at the defaults: a 0.1 m hop above the touchdown height at ẋ_d."""
        return {
            "z": self.rest_length + 0.1,
            "phi": 0.0,
            "x_dot": self.desired_speed,
            "phi_dot": 0.0,
        }

    def nominal_input(self) -> np.ndarray:
        """No per-step input: the controller is in the dynamics."""
        return np.zeros(0)
