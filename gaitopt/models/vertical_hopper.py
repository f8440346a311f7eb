"""The vertical (one-legged, one-dimensional) hopper with an energy-based thrust controller.

Raibert 1984, "Hopping in legged systems — modeling and simulation for the two-dimensional
one-legged case" (IEEE Trans. SMC 14(3)) and *Legged Robots That Balance* (1986), ch. 2 (vertical
hopping: thrust by lengthening the leg spring during stance; losses from the unsprung leg mass at
touchdown and from friction); the one-dimensional hopper exercise of Tedrake's *Underactuated
Robotics* ("Simple models of walking and running").

A body of mass ``m`` (height ``y`` above the ground, m) rides on a massless leg: a linear spring
of stiffness ``k`` and rest length ``L`` (plus an optional viscous damper ``b``).  One hop, from
apex to apex, is four phases:

* **descent** (flight, state ``y, y_dot``): ``ÿ = −g``, leg at its rest length ``l0``;
  **touchdown** when ``y = l0`` falling.  The foot's impact dissipates the fraction ``ε``
  (``touchdown_loss``) of the kinetic energy, ``ẏ⁺ = sqrt(1 − ε) ẏ⁻`` — a lumped model of
  Raibert's unsprung-leg-mass loss.  The controller stores the apex energy ``E_a = ½ m ẏ⁻² +
  m g l0`` (the flight energy, measured before the loss).
* **compression** (state ``y, y_dot, apex_energy, dissipated``): ``m ÿ = −m g + k (l0 − y) −
  b ẏ``, ``dissipated`` accumulates ``∫ b ẏ² dt``.  **Bottom** when ``ẏ = 0`` rising: here the
  controller lengthens the spring's rest length by the thrust ``δ`` (below), instantly.
* **thrust** (state ``y, y_dot, delta, dissipated``): ``m ÿ = −m g + k (l0 + δ − y) − b ẏ``;
  **lift-off** when the spring regains its (new) rest length, ``y = l0 + δ`` rising (the leg's
  mechanical stop; with damping the ground force ``k(l0 + δ − y) − b ẏ`` turns slightly negative
  just before — neglected, as for the SLIP's damped variants).  In flight the massless leg
  returns to ``l0`` at no cost.
* **ascent** (flight, ``y, y_dot``) to the **apex**, ``ẏ = 0`` falling — the Poincaré section.

**Section: apex**, coordinate ``y`` (``ẏ = 0``); the return map is the apex-to-apex map
``y[n+1] = P(y[n])`` with one multiplier.  State order on the section: ``y, y_dot``.

Thrust.  With the spring compressed by ``c = l0 − y_b`` at the bottom, lengthening the rest length
by ``δ`` raises the spring energy from ``½ k c²`` to ``½ k (c + δ)²``: the thrust injects

    W(δ, c) = k δ c + ½ k δ²                                                    (1)

in closed form, and the spring is relaxed again at lift-off (``y = l0 + δ``), so all of ``W``
(less any damper loss of the thrust phase) becomes flight energy.  Conversely the thrust that
injects ``W`` is ``δ = −c + sqrt(c² + 2 W / k)`` (``W ≥ −½ k c²``: the spring's energy is the
most that shortening can remove).

Energy controller (inside the dynamics; ``E_d = m g h_d``, ``h_d`` = ``desired_height``).  At the
bottom the controller knows the apex energy ``E_a`` and measures the energy now,
``E_b = m g y_b + ½ k c²``; it replaces what was lost since the apex and closes a fraction ``K``
(``gain``) of the apex-energy error:

    W = (E_a − E_b) + K (E_d − E_a),    δ = −c + sqrt(c² + 2 W / k) + u           (2)

(``u`` = the per-step input ``thrust_offset``, 0 nominally).  Without damping the thrust phase is
lossless, so the next apex energy is ``E_b + W = E_a + K (E_d − E_a)``: the apex map is exactly

    y[n+1] = y[n] + K (h_d − y[n]),    fixed point y* = h_d,    slope P'(y*) = 1 − K    (3)

— stable for ``0 < K < 2``, deadbeat at ``K = 1``, whatever the touchdown loss.  At the fixed point
the thrust work balances the loss, ``W* = ε m g (h_d − l0)`` (energy balance), with the bottom
compression ``c*`` from ``m g (l0 − c) + ½ k c² = m g l0 + (1 − ε) m g (h_d − l0)``:

    c* = (m g + sqrt((m g)² + 2 k (1 − ε) m g (h_d − l0))) / k,    δ* from (1).      (4)

With damping (``b > 0``) the thrust-phase loss ``L2`` is not replaced: ``E' = E_a + K (E_d − E_a)
− L2``, so the fixed point lies below ``h_d`` by about ``L2 / (K m g)``; no closed form (found
numerically; the energy balance ``W = touchdown loss + ∫ b ẏ² dt`` still holds to solver
accuracy).

The map's domain: apexes above the leg length (``y > l0``; below, the body falls to the ground —
a terminal transition) and thrusts that let the body reach ``l0 + δ`` again (else "no lift-off").
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import ClassVar

import casadi as ca
import numpy as np

from ..errors import ParameterError
from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..parameters import gravity_parameter, parameter
from .blocks import apex, ballistic_flow, fall
from .quantities import length_parameter, mass_parameter, state_units, stiffness_parameter

__all__ = ["VerticalHopper"]

_RAIBERT = "Raibert 1986, Legged Robots That Balance, ch. 2"
_CHOSEN = "chosen: a 10 kg body, 0.5 m leg, stance natural frequency 20 rad/s"


@dataclass(frozen=True)
class VerticalHopper(HybridModel):
    """Vertical hopper under the energy controller: apex state ``y`` (m), ``y_dot`` (m/s);
    compression ``y, y_dot, apex_energy`` (J), ``dissipated`` (J); thrust ``y, y_dot, delta`` (m),
    ``dissipated``; per-step input ``thrust_offset`` (m, added to the controller's thrust)."""

    name = "vertical_hopper"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("y", "y_dot")
    declared_coordinates = ("y",)
    declared_section_doc = "apex: y_dot = 0"
    state_units = {**state_units(y="m"), "apex_energy": "J", "dissipated": "J", "delta": "m"}
    title = "Vertical hopper (energy-controlled thrust)"
    reference = "Raibert 1984, 1986; Tedrake, Underactuated Robotics"
    inputs = ("thrust_offset",)
    input_units = ("m",)
    mesh = (4, 4)
    max_phase_time: ClassVar[float] = 10.0

    mass: float = mass_parameter(10.0, "body mass m", _CHOSEN)
    rest_length: float = length_parameter(0.5, "leg rest length l0", _CHOSEN)
    stiffness: float = stiffness_parameter(
        4000.0, "leg spring stiffness k", _CHOSEN + " (k = m·20²)", high=1e8
    )
    damping: float = parameter(
        0.0, unit="N·s/m", low=0.0, high=1e5,
        doc="leg damping b in stance (optional loss; the closed forms assume 0)",
        source="ideal spring; Raibert's leg friction is lumped into touchdown_loss",
    )  # fmt: skip
    touchdown_loss: float = parameter(
        0.1, unit="1", low=0.0, high=1.0, high_open=True,
        doc="fraction ε of the kinetic energy lost at touchdown (ẏ⁺ = sqrt(1 − ε) ẏ⁻)",
        source=_RAIBERT + " (unsprung leg mass ≈ 10 % of the body's)",
    )  # fmt: skip
    desired_height: float = length_parameter(
        0.7,
        "desired apex height h_d of the body (E_d = m g h_d)",
        "chosen: 0.2 m of flight above the 0.5 m leg",
        high=100.0,
    )
    gain: float = parameter(
        0.5, unit="1", low=0.0, high=4.0, low_open=True,
        doc="energy-feedback gain K: W = (E_a − E_b) + K (E_d − E_a)",
        source="inside the stable range (0, 2); P'(h_d) = 1 − K = 0.5",
    )  # fmt: skip
    gravity: float = gravity_parameter()

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        m, l0, k, b, eps = sym.mass, sym.rest_length, sym.stiffness, sym.damping, sym.touchdown_loss
        hd, K, g = sym.desired_height, sym.gain, sym.gravity

        # -- flight (descent and ascent): ballistic, leg at rest length ---------------------------
        xf, (y, y_dot) = sym.states("y", "y_dot")
        ballistic = ballistic_flow(sym, xf, g, vertical=0)  # ÿ = −g
        flight_energy = sym.conserved("energy", xf, 0.5 * m * y_dot**2 + m * g * y)
        flight_points = ca.Function(
            "points", [xf, sym.p], [ca.horzcat(ca.vertcat(0, y), ca.vertcat(0, y - l0))]
        )
        touchdown = Transition(
            name="touchdown",
            guard=sym.function("guard", xf, y - l0),  # y = l0, falling
            direction=-1,
            # ẏ⁺ = sqrt(1 − ε) ẏ⁻; the controller stores E_a = ½ m ẏ⁻² + m g y; nothing dissipated
            # by the damper yet.
            reset=sym.function(
                "reset",
                xf,
                ca.vertcat(y, ca.sqrt(1 - eps) * y_dot, 0.5 * m * y_dot**2 + m * g * y, 0),
            ),
            target=1,
            doc="foot reaches the ground: y = l0, falling; ẏ⁺ = sqrt(1 − ε)·ẏ⁻ (foot impact loss)",
        )
        grounded = fall(
            sym,
            xf,
            "apex below the leg length (body reaches the ground)",
            y,
            "fires only if touchdown never armed: the apex was at or below l0",
        )
        descent = Phase(
            "descent",
            ("y", "y_dot"),
            ballistic,
            (touchdown, grounded),
            {"energy": flight_energy},
            points=flight_points,
            point_names=("body", "foot"),
        )

        # -- compression: spring at rest length l0 ------------------------------------------------
        xc, (yc, yc_dot, e_apex, lost_c) = sym.states("y", "y_dot", "apex_energy", "dissipated")
        compression_flow = sym.function(
            "flow",
            xc,
            ca.vertcat(yc_dot, -g + (k * (l0 - yc) - b * yc_dot) / m, 0, b * yc_dot**2),
        )
        c = l0 - yc  # spring compression at the bottom
        e_bottom = 0.5 * m * yc_dot**2 + m * g * yc + 0.5 * k * c**2
        work = (e_apex - e_bottom) + K * (m * g * hd - e_apex)  # controller (2)
        delta = -c + ca.sqrt(ca.fmax(c**2 + 2 * work / k, 0)) + sym.input("thrust_offset")
        bottom = Transition(
            name="bottom (thrust)",
            guard=sym.function("guard", xc, yc_dot),  # ẏ = 0, rising: maximum compression
            direction=+1,
            reset=sym.function("reset", xc, ca.vertcat(yc, yc_dot, delta, lost_c)),
            target=2,
            impact=False,
            doc="maximum compression ẏ = 0; rest length l0 → l0 + δ with δ from the energy "
            "controller W = (E_a − E_b) + K (E_d − E_a), δ = −c + sqrt(c² + 2W/k) + u",
        )
        collapses_c = fall(
            sym,
            xc,
            "collapses (body reaches the ground in stance)",
            yc,
            "y = 0: the spring is too soft for the fall",
        )
        compression = Phase(
            "compression",
            ("y", "y_dot", "apex_energy", "dissipated"),
            compression_flow,
            (bottom, collapses_c),
            {"energy": sym.conserved("energy", xc, e_bottom + lost_c)},
            points=ca.Function(
                "points", [xc, sym.p], [ca.horzcat(ca.vertcat(0, yc), ca.DM.zeros(2, 1))]
            ),
            point_names=("body", "foot"),
        )

        # -- thrust: spring at rest length l0 + δ -------------------------------------------------
        xt, (yt, yt_dot, d, lost_t) = sym.states("y", "y_dot", "delta", "dissipated")
        thrust_flow = sym.function(
            "flow",
            xt,
            ca.vertcat(yt_dot, -g + (k * (l0 + d - yt) - b * yt_dot) / m, 0, b * yt_dot**2),
        )
        liftoff = Transition(
            name="lift-off",
            guard=sym.function("guard", xt, yt - l0 - d),  # y = l0 + δ, rising
            direction=+1,
            reset=sym.function("reset", xt, ca.vertcat(yt, yt_dot)),
            target=3,
            impact=False,
            doc="the spring regains its rest length y = l0 + δ, rising; the leg returns to l0",
        )
        no_liftoff = fall(
            sym,
            xt,
            "no lift-off (falls back in stance)",
            yt_dot,
            "ẏ falls through 0 before y = l0 + δ: too little thrust to leave the ground",
        )
        collapses_t = fall(
            sym,
            xt,
            "collapses (body reaches the ground in stance)",
            yt,
            "y = 0 in the thrust phase",
        )
        thrust_energy = 0.5 * m * yt_dot**2 + m * g * yt + 0.5 * k * (l0 + d - yt) ** 2 + lost_t
        thrust = Phase(
            "thrust",
            ("y", "y_dot", "delta", "dissipated"),
            thrust_flow,
            (liftoff, no_liftoff, collapses_t),
            {"energy": sym.conserved("energy", xt, thrust_energy)},
            points=ca.Function(
                "points", [xt, sym.p], [ca.horzcat(ca.vertcat(0, yt), ca.DM.zeros(2, 1))]
            ),
            point_names=("body", "foot"),
        )

        # -- ascent to the apex -------------------------------------------------------------------
        top = apex(sym, xf, y_dot, ca.vertcat(y, y_dot), doc="top of the flight, ẏ = 0 falling")
        ascent = Phase(
            "ascent",
            ("y", "y_dot"),
            ballistic,
            (top,),
            {"energy": flight_energy},
            points=flight_points,
            point_names=("body", "foot"),
        )

        s = ca.SX.sym("s", 1)
        section = Section(("y",), sym.lift(s, ca.vertcat(s[0], 0)), "apex: y_dot = 0")
        return (descent, compression, thrust, ascent), section

    def check(self) -> None:
        if self.desired_height <= self.rest_length:
            raise ParameterError(
                f"vertical_hopper: `desired_height` = {self.desired_height:g} m is not above the "
                f"leg's rest length {self.rest_length:g} m: no flight; raise `desired_height`"
            )

    # -- closed forms (damping 0) --------------------------------------------------------------
    @property
    def weight(self) -> float:
        """``m g`` (N)."""
        return self.mass * self.gravity

    def bottom_compression(self, apex: float) -> float:
        """Spring compression ``c`` (m) at the bottom after an apex at ``apex`` (m), undamped:
        ``m g (l0 − c) + ½ k c² = m g l0 + (1 − ε) m g (apex − l0)`` (eq. 4)."""
        mg, k = self.weight, self.stiffness
        kinetic = (1 - self.touchdown_loss) * mg * (apex - self.rest_length)
        return (mg + math.sqrt(mg**2 + 2 * k * kinetic)) / k

    def thrust_work(self, delta: float, compression: float) -> float:
        """Energy (J) injected by lengthening the rest length by ``delta`` at compression ``c``:
        ``W = k δ c + ½ k δ²`` (eq. 1)."""
        return self.stiffness * (delta * compression + 0.5 * delta**2)

    def thrust_for_work(self, work: float, compression: float) -> float:
        """The thrust ``δ = −c + sqrt(c² + 2 W / k)`` (m) that injects ``work`` (J)."""
        return -compression + math.sqrt(max(compression**2 + 2 * work / self.stiffness, 0.0))

    def controller_thrust(self, apex: float, offset: float = 0.0) -> float:
        """The thrust δ (m) of the controller (eq. 2) after an apex at ``apex`` (undamped)."""
        mg = self.weight
        c = self.bottom_compression(apex)
        e_a = mg * apex
        e_b = e_a - self.touchdown_loss * mg * (apex - self.rest_length)
        work = (e_a - e_b) + self.gain * (mg * self.desired_height - e_a)
        return self.thrust_for_work(work, c) + offset

    def closed_form_map(self, apex: float, offset: float = 0.0) -> float:
        """Apex-to-apex map (m), undamped, by energy bookkeeping (eqs. 1, 2); NaN where the hop
        is not defined.  With ``offset = 0`` it is ``apex + K (h_d − apex)`` (eq. 3)."""
        if not apex > self.rest_length:
            return math.nan
        mg, l0 = self.weight, self.rest_length
        c = self.bottom_compression(apex)
        delta = self.controller_thrust(apex, offset)
        if delta < -c:
            return math.nan
        e_b = mg * apex - self.touchdown_loss * mg * (apex - l0)
        energy = e_b + self.thrust_work(delta, c)
        if energy <= mg * (l0 + delta):
            return math.nan  # the body never gets back to l0 + δ
        return energy / mg

    def closed_form_fixed_point(self) -> float:
        """``y* = h_d`` (m; eq. 3, damping 0)."""
        return self.desired_height

    def fixed_point(self) -> float:
        """Deprecated name of :meth:`closed_form_fixed_point` (``fixed_point`` is the found
        gait's, :attr:`gaitopt.LimitCycle.fixed_point`)."""
        warnings.warn(
            "VerticalHopper.fixed_point() is now closed_form_fixed_point()",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.closed_form_fixed_point()

    def multiplier(self) -> float:
        """``P'(h_d) = 1 − K`` (eq. 3, damping 0)."""
        return 1.0 - self.gain

    def stable_gains(self) -> tuple[float, float]:
        """``(0, 2)``: the gains with ``|1 − K| < 1``."""
        return 0.0, 2.0

    def deadbeat_gain(self) -> float:
        """``K = 1``: the next apex is ``h_d`` from any apex."""
        return 1.0

    def fixed_point_thrust(self) -> tuple[float, float, float]:
        """``(c*, δ*, W*)`` at the fixed point (eq. 4): bottom compression (m), thrust (m) and
        thrust work ``W* = ε m g (h_d − l0)`` (J), equal to the touchdown loss."""
        c = self.bottom_compression(self.desired_height)
        work = self.touchdown_loss * self.weight * (self.desired_height - self.rest_length)
        return c, self.thrust_for_work(work, c), work

    def map_domain(self) -> tuple[float, float]:
        """Apex heights for plots: just above the leg length to ``l0 + 3 (h_d − l0)``."""
        span = self.desired_height - self.rest_length
        return self.rest_length + 0.02 * span, self.rest_length + 3.0 * span

    def existence_note(self) -> str | None:
        note = (
            f"vertical hopper: undamped, the apex map is y' = y + K (h_d − y) with fixed point "
            f"h_d = {self.desired_height:g} m and multiplier 1 − K = {self.multiplier():g} "
            f"(stable for 0 < K < 2); apexes must lie above l0 = {self.rest_length:g} m"
        )
        if self.damping > 0:
            note += "; with damping the fixed point lies below h_d (no closed form)"
        return note

    def nominal_input(self) -> np.ndarray:
        """No offset: the thrust is the controller's."""
        return np.zeros(1)

    def default_start(self) -> dict[str, float]:
        """The desired apex height (the fixed point without damping)."""
        return {"y": self.desired_height}
