"""The line juggler: a ball and a paddle on a vertical line, the paddle driven by the mirror law.

Buehler, Koditschek & Kindlmann 1990, "A family of robot control strategies for intermittent
dynamical environments" (IEEE Control Systems Magazine 10(2)) and "Planning and control of robotic
juggling and catching tasks" (IJRR 1994); the one-dimensional juggler as taught in Tedrake's
*Underactuated Robotics* notes.

The ball (height ``b`` above the mirror point, velocity ``v``) flies ballistically, ``b̈ = −g``.
The paddle mirrors it, ``r = −κ b`` with the energy-feedback gain

    κ = κ0 + κ1 (E_d − E),    E = ½ v² + g b,    E_d = ½ ḃ_d²

(energies per unit mass, so this is Buehler's ``κ1/m (E_d − E)`` with ``E`` in joules).  In flight
``E`` is constant, so ``κ`` is too and the paddle velocity is ``ṙ = −κ v``.  The ball meets the
paddle where ``b = r``, i.e. ``b (1 + κ) = 0``: at the mirror point ``b = 0`` (for ``κ > −1``).
The impact reverses the relative velocity with restitution ``e``:
``v⁺ − ṙ = −e (v⁻ − ṙ)``, so ``v⁺ = −(e + (1 + e) κ) v⁻``.

**Section: just before impact**, coordinate ``b_dot`` (m/s, negative): the ball's velocity just
before the last impact.  Since the engine's section lies just after the reset that closes the
cycle, the phase carries it as a held state: state order ``b, v, b_dot`` (``b_dot`` constant in
flight; the impact sets ``b_dot⁺ = v⁻``, ``v⁺`` as above, ``b⁺ = 0``).  The lift is
``b_dot ↦ (0, −(e + (1 + e) κ(b_dot)) b_dot, b_dot)``.

Closed forms.  Flight from ``b = 0`` returns to ``b = 0`` with the speed reversed, so the
pre-impact to pre-impact map is

    ḃ[n+1] = (e + (1 + e) κ(ḃ[n])) ḃ[n].

It is the textbook map ``ḃ[n+1] = ḃ[n] (1 + (1 + e) κ1 (E_d − ½ ḃ[n]²))`` exactly when
``κ0 = (1 − e)/(1 + e)`` (restitution losses balanced at ``E = E_d``) — the value used here.  It
holds where the paddle throws the ball up, ``e + (1 + e) κ > 0``, i.e.
``½ ḃ² < E_d + 1/((1 + e) κ1)``; beyond that the ball is knocked down (a terminal transition).
Fixed point ``ḃ* = −ḃ_d``; slope ``P'(ḃ*) = 1 − (1 + e) κ1 ḃ_d²``: stable for
``0 < κ1 < 2/((1 + e) ḃ_d²)`` (period doubling at the upper end), deadbeat at
``κ1 = 1/((1 + e) ḃ_d²)``.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any, ClassVar

import casadi as ca

from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..parameters import gravity_parameter, parameter
from .blocks import bar_and_ball_points, fall
from .quantities import restitution_parameter

__all__ = ["LineJuggler"]

_BUEHLER = "Buehler, Koditschek & Kindlmann 1990"
#: The ball counts as dropped this far (m) below the mirror point.
DROP_DEPTH = 1.0
#: Half-width (m) of the drawn paddle (drawing only: ball and paddle move on one vertical line).
PADDLE_HALF_WIDTH = 0.1


def energy_gain_parameter(source: str) -> Any:
    """The mirror law's energy-feedback gain ``κ1`` (s²/m², per unit mass), default 0.04, range
    [0, 10] (the planar juggler's too)."""
    doc = "energy-feedback gain κ1 of the mirror law (per unit mass)"
    return parameter(0.04, unit="s^2/m^2", doc=doc, source=source, low=0.0, high=10.0)


def impact_speed_parameter(source: str) -> Any:
    """The mirror law's desired impact speed ``ḃ_d`` (m/s), default 3 m/s, range (0, 100]."""
    doc = "desired impact speed ḃ_d (E_d = ½ ḃ_d²)"
    return parameter(3.0, unit="m/s", doc=doc, source=source, low=0.0, high=100.0, low_open=True)


@dataclass(frozen=True)
class LineJuggler(HybridModel):
    """Line juggler with the mirror law: state ``b`` (m), ``v`` (m/s), ``b_dot`` (m/s, the
    pre-impact velocity, held); section just before impact, coordinate ``b_dot``."""

    name = "line_juggler"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("b", "v", "b_dot")
    declared_coordinates = ("b_dot",)
    declared_section_doc = (
        "just before an impact: b_dot = pre-impact velocity; b = 0, v = the post-impact velocity"
    )
    rates = {"b": "v"}  # b_dot is the held pre-impact velocity, not the rate of b
    state_units = {"b": "m", "v": "m/s", "b_dot": "m/s"}  # for axis labels
    title = "Line juggler (mirror law)"
    reference = "Buehler, Koditschek & Kindlmann 1990; Tedrake, Underactuated Robotics"
    mesh = (4, 4)
    max_phase_time: ClassVar[float] = 10.0
    #: The drawing: the paddle (a bar at height r = −κ b) and the ball (a dot).
    drawing = (("paddle_left", "paddle_right"),)
    #: No ground under the scene (see :mod:`gaitopt.animation`).
    on_ground: ClassVar[bool] = False

    restitution: float = restitution_parameter(
        0.8,
        "coefficient of restitution e of the ball on the paddle",
        "chosen for the textbook juggling exercise (Underactuated Robotics, ch. 4)",
    )
    kappa1: float = energy_gain_parameter(
        "inside the stable range (0, 2/((1+e) ḃ_d²)) = (0, 0.1235) at the defaults"
    )
    desired_speed: float = impact_speed_parameter("chosen for the textbook juggling exercise")
    gravity: float = gravity_parameter()

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        e, k1, vd, g = sym.restitution, sym.kappa1, sym.desired_speed, sym.gravity
        kappa0 = (1 - e) / (1 + e)

        def kappa(b, v):
            return kappa0 + k1 * (0.5 * vd**2 - (0.5 * v**2 + g * b))

        x, (b, v, b_dot) = sym.states("b", "v", "b_dot")
        flow = sym.function("flow", x, ca.vertcat(v, -g, 0))
        k = kappa(b, v)
        gain = e + (1 + e) * k  # v⁺ = −gain · v⁻
        impact = Transition(
            name="impact",
            guard=sym.function("guard", x, b * (1 + k)),  # b − r = b (1 + κ), falling
            direction=-1,
            reset=sym.function("reset", x, ca.vertcat(0, -gain * v, v)),
            target=0,
            admissible=sym.function("admissible", x, -v),  # the ball falls onto the paddle
            doc="ball meets the paddle r = −κ b at b = 0; v⁺ = −(e + (1 + e) κ) v⁻, b_dot⁺ = v⁻",
        )
        dropped = fall(
            sym,
            x,
            "ball dropped (not thrown up by the paddle)",
            b + DROP_DEPTH,
            f"b < −{DROP_DEPTH:g} m: the impact knocked the ball down, e + (1 + e) κ ≤ 0",
        )
        energy = sym.conserved("energy", x, 0.5 * v**2 + g * b)  # per unit mass (J/kg)
        # The ball stays above the paddle between impacts, b − r = b (1 + κ) ≥ 0: zero at the
        # impact that starts the flight (it must rise at once: the paddle throws it up) and at the
        # impact that ends it.
        above = sym.constraint(
            "ball above the paddle",
            x,
            b * (1 + k),
            "ball below the paddle",
            at_start=True,
            at_end=True,
            unit="m",
            source="the paddle is solid (Buehler et al. 1990)",
        )
        # Drawing points (m, heights above the mirror point): the paddle at the mirror law's
        # r = −κ b and the ball at b; the drawn gap b − r is the constraint's b (1 + κ).
        paddle = -k * b
        points = bar_and_ball_points(sym, x, bar=paddle, ball=b, half_width=PADDLE_HALF_WIDTH)
        flight = Phase(
            "flight",
            ("b", "v", "b_dot"),
            flow,
            (impact, dropped),
            {"energy": energy},
            points=points,
            point_names=("paddle_left", "paddle_right", "ball"),
            constraints=(above,),
        )
        s = ca.SX.sym("s", 1)
        section = Section(
            ("b_dot",),
            sym.lift(s, ca.vertcat(0, -(e + (1 + e) * kappa(0, s[0])) * s[0], s[0])),
            "just before an impact: b_dot = pre-impact velocity; b = 0, v = the post-impact "
            "velocity",
        )
        return (flight,), section

    # -- closed forms ------------------------------------------------------------------------
    @property
    def kappa0(self) -> float:
        """``κ0 = (1 − e)/(1 + e)``: the value for which the textbook map holds."""
        return (1 - self.restitution) / (1 + self.restitution)

    def kappa(self, b: float, v: float) -> float:
        """Mirror-law gain ``κ = κ0 + κ1 (E_d − E)``."""
        energy = 0.5 * v**2 + self.gravity * b
        return self.kappa0 + self.kappa1 * (0.5 * self.desired_speed**2 - energy)

    def closed_form_map(self, b_dot: float) -> float:
        """Textbook pre-impact map ``ḃ' = ḃ (1 + (1 + e) κ1 (E_d − ½ ḃ²))`` (NaN where the ball
        is not thrown up)."""
        gain = self.restitution + (1 + self.restitution) * self.kappa(0.0, b_dot)
        return gain * b_dot if gain > 0 and b_dot < 0 else math.nan

    def closed_form_fixed_point(self) -> float:
        """``ḃ* = −ḃ_d`` (m/s)."""
        return -self.desired_speed

    def fixed_point(self) -> float:
        """Deprecated name of :meth:`closed_form_fixed_point` (``fixed_point`` is the found
        gait's, :attr:`gaitopt.LimitCycle.fixed_point`)."""
        warnings.warn(
            "LineJuggler.fixed_point() is now closed_form_fixed_point()",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.closed_form_fixed_point()

    def multiplier(self) -> float:
        """``P'(ḃ*) = 1 − (1 + e) κ1 ḃ_d²``."""
        return 1 - (1 + self.restitution) * self.kappa1 * self.desired_speed**2

    def stable_gains(self) -> tuple[float, float]:
        """``(0, 2/((1 + e) ḃ_d²))``: the κ1 with |P'(ḃ*)| < 1."""
        return 0.0, 2 / ((1 + self.restitution) * self.desired_speed**2)

    def deadbeat_gain(self) -> float:
        """``κ1 = 1/((1 + e) ḃ_d²)``: P'(ḃ*) = 0."""
        return 1 / ((1 + self.restitution) * self.desired_speed**2)

    def fastest_impact(self) -> float:
        """Largest pre-impact speed the paddle still throws back up (m/s):
        ``½ ḃ² < E_d + 1/((1 + e) κ1)``; inf for κ1 = 0."""
        if self.kappa1 == 0:
            return math.inf
        return math.sqrt(self.desired_speed**2 + 2 / ((1 + self.restitution) * self.kappa1))

    def map_domain(self) -> tuple[float, float]:
        """Pre-impact velocities where the map is defined, clipped to ``[−2.5 ḃ_d, −0.05 ḃ_d]``."""
        top = min(self.fastest_impact(), 2.5 * self.desired_speed)
        return -0.999 * top, -0.05 * self.desired_speed

    def existence_note(self) -> str | None:
        lo, hi = self.stable_gains()
        return (
            f"line juggler: fixed point b_dot = −{self.desired_speed:g} m/s for κ1 > 0, stable for "
            f"κ1 in ({lo:g}, {hi:.4g}) (closed form, Buehler et al. 1990); here κ1 = "
            f"{self.kappa1:g}"
        )

    def default_start(self) -> dict[str, float]:
        """Slightly off the fixed point (a simulation from here converges for stable κ1)."""
        return {"b_dot": -self.desired_speed}
