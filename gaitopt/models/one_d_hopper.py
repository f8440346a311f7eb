"""The one-dimensional hopper of Tedrake's exercise: a body on a massive leg, a spring preload.

Source: Tedrake, *Underactuated Robotics*, ch. "Simple Models of Walking and Running", exercise
"One-Dimensional Hopper" and its notebook ``exercises/simple_legs/one_d_hopper.ipynb``
(github.com/RussTedrake/underactuated; the controller is a one-dimensional version of Raibert
1984, "Hopping in legged systems — modeling and simulation for the two-dimensional one-legged
case", IEEE Trans. SMC 14(3)).  Masses from the notebook's ``models/one_d_hopper.urdf`` (body
10 kg, leg 1 kg), ``k = 1000 N/m`` from its ``get_hopper_parameters``, ``h = 1 m`` and the start
``z_b(0) = 1 m`` from its simulation cells.

Conventions (the notebook's).  Two rigid links on a vertical line: the **body** (mass ``m_b``,
position ``z_b``) and the **leg** (mass ``m_l``, position ``z_l``), joined by a prismatic joint
with a spring of stiffness ``k``.  The leg coordinate is ``l = z_l − z_b`` and the state is
``(z_b, l, ż_b, l̇)``; ``z_l = z_b + l`` is the height of the foot's sole above the ground
(URDF: the sole is at ``z_b + l`` in world coordinates) and both are 0 when the hopper stands
unloaded with its foot on the ground.  The joint has a hard stop at ``l = 0`` (``l ≥ 0``: the
leg hangs from the body) and, at the other end, the stroke ``l ≤ s`` (the URDF's collision
geometry: the leg's lower plate meets the body at ``l = 0.76 m``, the commented-out joint
limit).  The spring's compression is ``l + δ``, with the **preload** ``δ ≥ 0`` the control; the
spring pushes the body up and the leg down with the force ``k (l + δ)``.  Mechanical energy
(the notebook's ``E(t)``)::

    E = ½ m_b ż_b² + ½ m_l ż_l² + m_b g z_b + m_l g z_l + ½ k (l + δ)²            (1)

One hop, apex to apex, is four phases (the notebook's hopping cycle):

* **descent** (flight, ``δ = 0``; states ``z_b, l, z_b_dot, l_dot``): the leg rests on its hard
  stop, ``l = l̇ = 0``, and falls with the body, ``z̈_b = −g``, ``l̈ = 0``.  With zero preload
  the stop carries no force (both bodies accelerate at −g); the flow is the locked one, valid on
  ``l = l̇ = 0``, where the section's lift puts the state.  **Touchdown** when the foot reaches
  the ground, ``z_b + l = 0`` falling: a plastic impact stops the leg, ``ż_l⁺ = 0``
  (``l̇⁺ = −ż_b⁻``); the spring transmits no impulse, so ``ż_b⁺ = ż_b⁻``.  The ground absorbs
  the leg's momentum ``m_l ż_b⁻`` and its kinetic energy ``½ m_l ż_b⁻²``.
* **compression** (stance, ``δ = 0``; same states): foot on the ground (``z_l = ż_l = 0``,
  so ``l = −z_b``), ``m_b z̈_b = −m_b g + k l``, ``l̈ = −z̈_b``.  **Bottom** when ``ż_b = 0``
  rising: the controller sets the preload ``δ̄`` (eq. 3), no impact.
* **thrust** (stance, states ``z_b, l, z_b_dot, l_dot, delta``): ``m_b z̈_b = −m_b g +
  k (l + δ̄)``.  **Lift-off** when the body reaches the hard stop, ``l = 0`` falling: a plastic
  impact of the body on the stop pulls the leg along at the common velocity
  ``ż_b⁺ = ż_l⁺ = m_b ż_b⁻ / (m_b + m_l)`` (momentum conserved: the ground cannot pull, so no
  external impulse acts), ``l⁺ = 0``, ``l̇⁺ = 0``.
* **ascent** (flight, states as in thrust): locked on the stop, which now carries the force
  ``k δ̄ ≥ 0`` (the preload presses the leg onto it), ``z̈_b = −g``.  **Apex** when ``ż_b = 0``
  falling: the preload is reset to 0 (the notebook: it "does not have any impact in the
  motion", the stop's internal force merely vanishes); the spring energy ``½ k δ̄²`` is
  withdrawn by the actuator, and the state (``δ`` dropped) enters the descent.

**Section: apex** (``ż_b = 0`` with the leg on its stop, ``l = l̇ = 0``), coordinate ``z_b``:
the apex height ``h``, with the body and the foot both at ``h``.  The return map is the
apex-to-apex map ``h[n+1] = P(h[n])`` with one multiplier.

The preload law (the notebook's derivation).  After an apex at ``h`` the body touches down with
speed ``sqrt(2 g h)``; stance conserves (1), so the bottom ``z = z_b(t_bt) < 0`` solves
``m_b g z + ½ k z² = m_b g h`` (the body's kinetic energy at touchdown, the spring then
unloaded)::

    z = −m_b g / k − sqrt((m_b g / k)² + 2 m_b g h / k)                             (2)

Energy through the preload, the lift-off impact and the ascent, equated to ``(m_b + m_l) g h_d``
at the next apex (``h_d`` = ``desired_apex``), is linear in ``δ̄``::

    δ̄ = z / 2 + m_b g / k − (m_b + m_l)² g h_d / (k m_b z),   δ = max(δ̄, 0)      (3)

and the next apex, for any ``δ ≥ 0``, is

    h' = m_b [m_b g z + ½ k z² − k δ z] / ((m_b + m_l)² g)                         (4)

Where ``δ̄ ≥ 0`` the next apex is ``h_d`` exactly: a **deadbeat** map, ``P(h) = h_d``,
multiplier 0.  Where ``δ̄ < 0`` (more energy than the hop needs) the preload clamps at 0 and the
hop is **passive**: by (2) and (4) with ``δ = 0``,

    P(h) = ρ h,   ρ = (m_b / (m_b + m_l))²                                           (5)

(touchdown loses ``m_l g h``, lift-off keeps ``m_b / (m_b + m_l)`` of the body's momentum, so
``(m_b/(m_b + m_l))²`` of its kinetic energy; ρ = (10/11)² = 0.826446 at the defaults).  Since
(4) increases with δ, ``δ̄ ≥ 0`` exactly where the passive hop falls short, ``ρ h ≤ h_d``: the
deadbeat region is ``0 < h ≤ h_d / ρ`` and the map is continuous at its edge.  The fixed point
``h* = h_d`` lies inside it for every ``h_d > 0`` (``ρ h_d < h_d``).  At ``h_d = 0`` the law
never preloads (``δ̄ = z/2 + m_b g / k ≤ 0`` by (2)): the passive hopper's apex shrinks by ρ
every hop towards standing, ``h = 0``, and there is **no hopping gait** — energy must enter.

The stroke.  The deepest bottom the leg allows is ``z = −s``: by (2) the apex may not exceed
``h_max = k s² / (2 m_b g) − s`` (2.18391 m at the defaults).  A desired apex above ``h_max``
is unreachable: its gait would drive the body through the foot's lower plate (the declared
stroke constraint fails, and the search says so).

Constraints declared: the foot above the ground in flight (``z_b + l ≥ 0``; zero at touchdown
and at lift-off, rising at once after it); the ground pushing on the foot in stance
(``N = m_l g + k (l + δ) ≥ 0``); the stroke in compression (``s − l ≥ 0``, deepest at the
bottom); the hard stop pushing in the ascent (``k δ ≥ 0``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import casadi as ca

from ..errors import ParameterError
from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..parameters import gravity_parameter, parameter
from .blocks import apex, fall
from .quantities import length_parameter, mass_parameter, state_units, stiffness_parameter

__all__ = ["OneDHopper"]

_NOTEBOOK = (
    "Tedrake, Underactuated Robotics, exercise One-Dimensional Hopper "
    "(exercises/simple_legs/one_d_hopper.ipynb)"
)
_URDF = "the exercise's models/one_d_hopper.urdf"
#: Drawing only: the body's centre is 0.9 m above the foot's sole when l = 0 (URDF: the body at
#: 0.9 m + z_b, the sole at z_b + l).
_BODY_ABOVE_SOLE = 0.9


@dataclass(frozen=True)
class OneDHopper(HybridModel):
    """One-dimensional hopper with a massive leg and a preloaded spring (Tedrake's exercise).

    States ``z_b`` (body height, m), ``l`` (leg coordinate ``z_l − z_b``, m), ``z_b_dot``,
    ``l_dot`` (m/s); in thrust and ascent also ``delta`` (the preload δ held since the bottom,
    m).  Section: apex, coordinate ``z_b``.
    """

    name = "one_d_hopper"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("z_b", "l", "z_b_dot", "l_dot")
    declared_coordinates = ("z_b",)
    declared_section_doc = "apex: z_b_dot = 0, leg on its hard stop (l = 0, l_dot = 0)"
    state_units = {**state_units(z_b="m", l="m"), "delta": "m"}
    title = "One-dimensional hopper (deadbeat preload)"
    reference = "Tedrake, Underactuated Robotics, One-Dimensional Hopper exercise; Raibert 1984"
    mesh = (4, 4)
    max_phase_time: ClassVar[float] = 10.0

    body_mass: float = mass_parameter(10.0, "body mass m_b", _URDF + " (link body)")
    leg_mass: float = mass_parameter(1.0, "leg mass m_l", _URDF + " (link leg)")
    stiffness: float = stiffness_parameter(
        1000.0, "spring stiffness k", _NOTEBOOK + ", get_hopper_parameters", high=1e8
    )
    desired_apex: float = parameter(
        1.0, unit="m", doc="desired apex height h_d of the preload law (0: never preload)",
        source=_NOTEBOOK + " (h = 1)", low=0.0, high=100.0,
    )  # fmt: skip
    stroke: float = length_parameter(
        0.76,
        "leg stroke s: the largest l (the leg's lower plate meets the body)",
        _URDF + " (collision boxes; the commented joint limit upper=0.76)",
        high=100.0,
    )
    gravity: float = gravity_parameter(source="standard gravity (the exercise's Drake default)")

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        mb, ml, k, hd, s, g = (
            sym.body_mass, sym.leg_mass, sym.stiffness, sym.desired_apex, sym.stroke, sym.gravity,
        )  # fmt: skip
        total = mb + ml

        def energy(zb, leg, zb_dot, leg_dot, delta):
            # eq. (1): the notebook's E(t), with z_l = z_b + l
            return (
                0.5 * mb * zb_dot**2
                + 0.5 * ml * (zb_dot + leg_dot) ** 2
                + mb * g * zb
                + ml * g * (zb + leg)
                + 0.5 * k * (leg + delta) ** 2
            )

        def points(x, zb, leg):
            return ca.Function(
                "points",
                [x, sym.p],
                [ca.horzcat(ca.vertcat(0, zb + leg), ca.vertcat(0, zb + _BODY_ABOVE_SOLE))],
            )

        # -- descent: flight on the hard stop, δ = 0 ----------------------------------------------
        xd, (zb, ld, zb_dot, ld_dot) = sym.states("z_b", "l", "z_b_dot", "l_dot")
        touchdown = Transition(
            name="touchdown",
            guard=sym.function("guard", xd, zb + ld),  # the foot's sole z_l = z_b + l, falling
            direction=-1,
            # plastic: ż_l⁺ = 0, so l̇⁺ = −ż_b⁻; the spring passes no impulse, ż_b⁺ = ż_b⁻
            reset=sym.function("reset", xd, ca.vertcat(zb, ld, zb_dot, -zb_dot)),
            target=1,
            doc="the foot reaches the ground z_b + l = 0, falling; plastic: the leg stops "
            "(ż_l⁺ = 0, l̇⁺ = −ż_b⁻), the body keeps ż_b (Tedrake's notebook, touchdown)",
        )
        foot_above = sym.constraint(
            "foot above the ground", xd, zb + ld, "foot below the ground", at_end=True, unit="m",
            source="rigid ground (the notebook's raise_if_penetration)",
        )  # fmt: skip
        descent = Phase(
            "descent",
            ("z_b", "l", "z_b_dot", "l_dot"),
            sym.function("flow", xd, ca.vertcat(zb_dot, ld_dot, -g, 0)),
            (touchdown,),
            {"energy": sym.conserved("energy", xd, energy(zb, ld, zb_dot, ld_dot, 0))},
            points=points(xd, zb, ld),
            point_names=("foot", "body"),
            constraints=(foot_above,),
        )

        # -- compression: stance, δ = 0 -----------------------------------------------------------
        xc, (zc, lc, zc_dot, lc_dot) = sym.states("z_b", "l", "z_b_dot", "l_dot")
        accel_c = -g + k * lc / mb  # m_b z̈_b = −m_b g + k (l + 0)
        # eq. (3) at the bottom z = z_b(t_bt) < 0, clamped at 0 (the notebook: δ = max(δ̄, 0))
        law = zc / 2 + mb * g / k - total**2 * g * hd / (k * mb * zc)
        bottom = Transition(
            name="bottom (preload)",
            guard=sym.function("guard", xc, zc_dot),  # ż_b = 0 rising: deepest compression
            direction=+1,
            reset=sym.function("reset", xc, ca.vertcat(zc, lc, zc_dot, lc_dot, ca.fmax(law, 0))),
            target=2,
            impact=False,
            doc="bottom ż_b = 0; preload δ = max(δ̄, 0), δ̄ = z/2 + m_b g/k − (m_b + m_l)² g h_d / "
            "(k m_b z) (Tedrake's notebook, derivation of the controller)",
        )
        ground_pushes_c = sym.constraint(
            "ground pushes on the foot", xc, ml * g + k * lc, "ground pulls on the foot", unit="N",
            source="unilateral ground contact: N = m_l g + k (l + δ) on the resting leg",
        )  # fmt: skip
        within_stroke = sym.constraint(
            "leg within its stroke", xc, s - lc, "stroke exhausted (body hits the leg's lower "
            "plate)", unit="m", source=_URDF + ": the leg's lower plate meets the body at l = s",
        )  # fmt: skip
        compression = Phase(
            "compression",
            ("z_b", "l", "z_b_dot", "l_dot"),
            sym.function("flow", xc, ca.vertcat(zc_dot, lc_dot, accel_c, -accel_c)),
            (bottom,),
            {"energy": sym.conserved("energy", xc, energy(zc, lc, zc_dot, lc_dot, 0))},
            points=points(xc, zc, lc),
            point_names=("foot", "body"),
            constraints=(ground_pushes_c, within_stroke),
        )

        # -- thrust: stance with the preload δ ----------------------------------------------------
        xt, (zt, lt, zt_dot, lt_dot, dt) = sym.states("z_b", "l", "z_b_dot", "l_dot", "delta")
        accel_t = -g + k * (lt + dt) / mb
        v_common = mb * zt_dot / total  # momentum m_b ż_b⁻ = (m_b + m_l) v⁺
        liftoff = Transition(
            name="lift-off",
            guard=sym.function("guard", xt, lt),  # the body reaches the hard stop l = 0
            direction=-1,
            reset=sym.function("reset", xt, ca.vertcat(zt, 0, v_common, 0, dt)),
            target=3,
            doc="the body hits the hard stop l = 0; plastic, momentum conserved: ż_b⁺ = ż_l⁺ = "
            "m_b ż_b⁻ / (m_b + m_l) (Tedrake's notebook, lift-off impact)",
        )
        no_liftoff = fall(
            sym, xt, "no lift-off (falls back in stance)", zt_dot,
            "ż_b falls through 0 before the body reaches the stop: too little energy to leave",
        )  # fmt: skip
        ground_pushes_t = sym.constraint(
            "ground pushes on the foot", xt, ml * g + k * (lt + dt), "ground pulls on the foot",
            unit="N", source="unilateral ground contact: N = m_l g + k (l + δ) on the resting leg",
        )  # fmt: skip
        thrust = Phase(
            "thrust",
            ("z_b", "l", "z_b_dot", "l_dot", "delta"),
            sym.function("flow", xt, ca.vertcat(zt_dot, lt_dot, accel_t, -accel_t, 0)),
            (liftoff, no_liftoff),
            {"energy": sym.conserved("energy", xt, energy(zt, lt, zt_dot, lt_dot, dt))},
            points=points(xt, zt, lt),
            point_names=("foot", "body"),
            constraints=(ground_pushes_t,),
        )

        # -- ascent: flight on the hard stop, preload held ----------------------------------------
        xa, (za, la, za_dot, la_dot, da) = sym.states("z_b", "l", "z_b_dot", "l_dot", "delta")
        top = apex(
            sym, xa, za_dot, ca.vertcat(za, la, za_dot, la_dot),
            doc="apex ż_b = 0 falling; the preload is reset to 0 (Tedrake's notebook: δ(t_ap⁺) = "
            "0), the state drops δ",
        )  # fmt: skip
        foot_rises = sym.constraint(
            "foot above the ground", xa, za + la, "foot below the ground", at_start=True, unit="m",
            source="rigid ground (the notebook's raise_if_penetration)",
        )  # fmt: skip
        stop_pushes = sym.constraint(
            "hard stop pushes the leg", xa, k * da, "hard stop pulls", unit="N",
            source="the stop at l = 0 is unilateral; its force is k δ on the locked leg",
        )  # fmt: skip
        ascent = Phase(
            "ascent",
            ("z_b", "l", "z_b_dot", "l_dot", "delta"),
            sym.function("flow", xa, ca.vertcat(za_dot, la_dot, -g, 0, 0)),
            (top,),
            {"energy": sym.conserved("energy", xa, energy(za, la, za_dot, la_dot, da))},
            points=points(xa, za, la),
            point_names=("foot", "body"),
            constraints=(foot_rises, stop_pushes),
        )

        sc = ca.SX.sym("s", 1)
        section = Section(
            ("z_b",), sym.lift(sc, ca.vertcat(sc[0], 0, 0, 0)), cls.declared_section_doc
        )
        return (descent, compression, thrust, ascent), section

    def check(self) -> None:
        if self.highest_apex() <= 0:
            sinks = 2 * self.body_mass * self.gravity / self.stiffness
            raise ParameterError(
                f"one_d_hopper: the stroke s = {self.stroke:g} m is too short: even from rest the "
                f"body sinks to 2 m_b g / k = {sinks:g} m in stance; lengthen `stroke` or stiffen "
                f"`stiffness`"
            )

    # -- closed forms --------------------------------------------------------------------------
    @property
    def apex_ratio(self) -> float:
        """``ρ = (m_b / (m_b + m_l))²`` (dimensionless): the passive apex map ``P(h) = ρ h``
        (eq. 5), also the ratio of the apex energies."""
        return (self.body_mass / (self.body_mass + self.leg_mass)) ** 2

    def bottom(self, apex: float) -> float:
        """The body's height ``z`` (m, negative) at the bottom after an apex at ``apex`` (m),
        eq. (2)."""
        a = self.body_mass * self.gravity / self.stiffness
        return -a - math.sqrt(a**2 + 2 * a * apex)

    def preload_law(self, apex: float) -> float:
        """The law's ``δ̄`` (m, eq. 3) after an apex at ``apex`` (m), before the clamp at 0."""
        z = self.bottom(apex)
        mb, k, g = self.body_mass, self.stiffness, self.gravity
        total = mb + self.leg_mass
        return z / 2 + mb * g / k - total**2 * g * self.desired_apex / (k * mb * z)

    def preload(self, apex: float) -> float:
        """The preload applied, ``max(δ̄, 0)`` (m)."""
        return max(self.preload_law(apex), 0.0)

    def next_apex(self, apex: float, preload: float) -> float:
        """The next apex (m, eq. 4) after an apex at ``apex`` with the preload ``preload`` (m)
        set at the bottom."""
        z = self.bottom(apex)
        mb, k, g = self.body_mass, self.stiffness, self.gravity
        total = mb + self.leg_mass
        return mb * (mb * g * z + 0.5 * k * z**2 - k * preload * z) / (total**2 * g)

    def highest_apex(self) -> float:
        """``h_max = k s² / (2 m_b g) − s`` (m): the highest apex whose bottom, eq. (2), stays
        within the stroke ``s``."""
        return self.stiffness * self.stroke**2 / (2 * self.body_mass * self.gravity) - self.stroke

    def deadbeat_region(self) -> tuple[float, float]:
        """Apex heights (m) from which one hop reaches ``h_d`` exactly: ``(0, h_d / ρ]``, cut at
        :meth:`highest_apex`; empty ``(0, 0)`` for ``h_d = 0``."""
        return 0.0, min(self.desired_apex / self.apex_ratio, self.highest_apex())

    def closed_form_map(self, apex: float) -> float:
        """The apex-to-apex map (m): ``h_d`` in the deadbeat region, ``ρ h`` beyond (eqs. 3–5);
        NaN for an apex at or below the ground or above :meth:`highest_apex` (the stroke)."""
        h = float(apex)
        if not 0.0 < h <= self.highest_apex():
            return math.nan
        return self.next_apex(h, self.preload(h))

    def closed_form_fixed_point(self) -> float:
        """``h* = h_d`` (m) where a hopping gait exists (``0 < h_d ≤ h_max``), else NaN."""
        h = self.desired_apex
        return h if 0.0 < h <= self.highest_apex() else math.nan

    def multiplier(self) -> float:
        """``P'(h*) = 0`` (deadbeat: ``h*`` lies inside the deadbeat region)."""
        return 0.0

    def map_domain(self) -> tuple[float, float]:
        """Apex heights for plots: from 2 % of :meth:`highest_apex` to it."""
        top = self.highest_apex()
        return 0.02 * top, top

    def section_limits(self) -> dict[str, tuple[float, float, str]]:
        """An apex is a height above the ground: ``z_b ≥ 0``."""
        return {"z_b": (0.0, math.inf, "an apex is a height of the body and foot above ground")}

    def existence_note(self) -> str | None:
        rho, top = self.apex_ratio, self.highest_apex()
        if self.desired_apex == 0.0:
            return (
                f"one_d_hopper: h_d = 0 never preloads (δ̄ = z/2 + m_b g/k ≤ 0 at every bottom): "
                f"the passive apex map is h' = ρ h, ρ = (m_b/(m_b + m_l))² = {rho:.6g}, whose "
                f"only fixed point is standing (h = 0); no hopping gait without energy input "
                f"(raise `desired_apex`)"
            )
        if self.desired_apex > top:
            return (
                f"one_d_hopper: h_d = {self.desired_apex:g} m is unreachable: its stance would "
                f"compress the leg beyond the stroke s = {self.stroke:g} m (apexes up to h_max = "
                f"k s²/(2 m_b g) − s = {top:.6g} m)"
            )
        return (
            f"one_d_hopper: deadbeat fixed point h* = h_d = {self.desired_apex:g} m, multiplier 0; "
            f"deadbeat from apexes in (0, h_d/ρ] = (0, {self.desired_apex / rho:.6g}] m, passive "
            f"h' = ρ h (ρ = {rho:.6g}) above; apexes up to h_max = {top:.6g} m (stroke)"
        )

    def default_start(self) -> dict[str, float]:
        """The desired apex (the fixed point), or the notebook's start ``z_b(0) = 1 m`` for
        ``h_d = 0``."""
        return {"z_b": self.desired_apex if self.desired_apex > 0 else 1.0}
