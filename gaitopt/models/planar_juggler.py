"""The planar juggler: a ball in a vertical plane batted by a one-link paddle under the mirror law.

Buehler, Koditschek & Kindlmann 1990, "A simple juggling robot: theory and experimentation"
(Experimental Robotics I) and "A family of robot control strategies for intermittent dynamical
environments" (IEEE Control Systems Magazine 10(2)).  This model generalises
:mod:`gaitopt.models.line_juggler` to the plane.

Geometry.  The paddle is a straight bar rotating about a fixed pivot at the origin, at angle ``θ``
(rad, counter-clockwise from the horizontal; y up).  The ball is a point at ``(x, y)`` (m) with
velocity ``(x_dot, y_dot)`` (m/s), in flight ``ẍ = 0``, ``ÿ = −g``; its angular position about
the pivot is ``ψ = atan2(y, x)`` (the ball stays on the right arm, ``x > 0``).

Mirror law.  The paddle follows, continuously in flight,

    θ = −κ ψ + κ_x (x − x̄) + κ_ẋ ẋ,    κ = κ0 + κ1 (E_d − E),
    E = ½ (ẋ² + ẏ²) + g y,    E_d = ½ ḃ_d²,    κ0 = (1 − e)/(1 + e)

(energies per unit mass).  The first term mirrors the ball's angle about the horizontal and, with
the energy gain κ, regulates the height exactly as in the line juggler; the last two tilt the
paddle to push the ball back towards the desired horizontal position ``x̄``
(``desired_position``).  Buehler et al. write the horizontal correction in the ball's position
along the paddle; here it is written in the Cartesian ``x, ẋ`` (equal to first order near the
impact point ψ ≈ 0), because then ``ẍ = 0`` in flight and the paddle's angular velocity has the
closed form

    θ̇ = −κ ψ̇ + κ_x ẋ,    ψ̇ = (x ẏ − y ẋ)/(x² + y²)

(``κ`` is constant in flight since ``E`` is), so the paddle's state at impact is a function of the
ball's state alone.

Guard.  The ball's signed distance above the paddle line, ``d = n·(x, y)`` with the paddle
normal ``n = (−sin θ, cos θ)``, crosses zero decreasing; equivalently ``(1 + κ) ψ = κ_x (x − x̄)
+ κ_ẋ ẋ``.  Admissible only while the ball approaches the paddle (relative normal velocity
``w_n < 0``).  Two terminal exits: the ball falls ``DROP_DEPTH`` below the pivot (knocked down),
or crosses over the pivot (``x = 0``, where the mirror law's angle is undefined).

Impact law.  The paddle is velocity-controlled (infinitely massive).  Its contact point, at
``s = (x, y)·t`` along the paddle (``t = (cos θ, sin θ)``), moves with ``θ̇ s n``.  The relative
normal velocity ``w_n = (v − θ̇ s n)·n`` is reversed and scaled by ``e``, the tangential velocity is
unchanged (the paddle point has none):  ``v⁺ = v⁻ − (1 + e) w_n n``.

**State order** ``x, y, x_dot, y_dot, x_dot_pre, energy_pre``: the last two are held (constant in
flight) and set by the impact to the ball's pre-impact horizontal velocity and energy.

**Section: just before an impact**; coordinates ``x`` (m, the impact position — continuous
through the impact), ``x_dot_pre`` (m/s, pre-impact horizontal velocity) and ``energy_pre``
(J/kg, pre-impact energy).  Why the energy rather than the vertical velocity: on the guard the
impact height solves ``(1 + κ(E)) atan2(y, x) = κ_x (x − x̄) + κ_ẋ ẋ``, implicit in ``y`` through
``E``'s ``g y``, but explicit given ``E``: ``y = x tan ψ``, ``ψ = (κ_x (x − x̄) + κ_ẋ ẋ)/(1 + κ)``,
``ẏ⁻ = −√(2 (E − g y) − ẋ²)``.  The lift ``(x, x_dot_pre, energy_pre) ↦ impact(pre-impact
state)`` is therefore explicit and its image is exactly the 3-D set the cycle-closing impact lands
in, so the return map's three multipliers are all nontrivial.

Closed forms.  The vertical line ``x = x̄`` through the desired impact point is invariant: with
``x = x̄, ẋ = 0`` the paddle is horizontal at impact, the impact is at ``y = 0`` and the contact
point moves with ``θ̇ x̄ = −κ ẏ``, exactly the line juggler's ``ṙ = −κ v``.  So the fixed point is
``(x̄, 0, E_d)`` and the energy map on that line is the line juggler's, multiplier
``λ_E = 1 − (1 + e) κ1 ḃ_d²``.  Because the line is invariant, the Jacobian is block triangular
(the horizontal rows do not depend on ``E``); linearising the horizontal motion about it (paddle
tilt ``φ = (1 + e)(κ_x ξ + κ_ẋ u)/2`` at impact, ``ξ = x − x̄``, ``u`` the pre-impact ``ẋ``,
relative normal speed ``2 ḃ_d/(1 + e)``, flight time ``T = 2 ḃ_d/g``):

    u' = u − a (κ_x ξ + κ_ẋ u),   ξ' = ξ + T u',   a = (1 + e) ḃ_d,

whose matrix has trace ``2 − a κ_ẋ − a T κ_x`` and determinant ``1 − a κ_ẋ``: stable (Jury) iff
``κ_x > 0``, ``0 < a κ_ẋ < 2`` and ``a T κ_x < 4 − 2 a κ_ẋ``; deadbeat at ``a κ_ẋ = 1``,
``a T κ_x = 1``.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import ClassVar

import casadi as ca
import numpy as np

from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..parameters import gravity_parameter, parameter
from .blocks import fall
from .line_juggler import energy_gain_parameter, impact_speed_parameter
from .quantities import length_parameter, restitution_parameter, state_units

__all__ = ["PlanarJuggler"]

#: The ball counts as dropped this far (m) below the pivot.
DROP_DEPTH = 1.0
STATES = ("x", "y", "x_dot", "y_dot", "x_dot_pre", "energy_pre")
#: Drawn paddle, in units of x̄ along the bar from the pivot (drawing only): a short stub behind
#: the pivot and the arm to twice the desired impact point.
PADDLE_REACH = (-0.2, 2.0)


@dataclass(frozen=True)
class PlanarJuggler(HybridModel):
    """Planar juggler, one-link paddle, mirror law: state ``x, y`` (m), ``x_dot, y_dot`` (m/s),
    ``x_dot_pre`` (m/s), ``energy_pre`` (J/kg) (held); section just before impact, coordinates
    ``x, x_dot_pre, energy_pre``."""

    name = "planar_juggler"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("x", "y", "x_dot", "y_dot", "x_dot_pre", "energy_pre")
    declared_coordinates = ("x", "x_dot_pre", "energy_pre")
    declared_section_doc = (
        "just before an impact: x = impact position, x_dot_pre, energy_pre = pre-impact horizontal"
        " velocity and energy; y on the paddle, velocities after the impact"
    )
    state_units = {**state_units(x="m", y="m"), "x_dot_pre": "m/s", "energy_pre": "J/kg"}
    title = "Planar juggler (one-link paddle, mirror law)"
    reference = "Buehler, Koditschek & Kindlmann 1990"
    mesh = (4, 4)
    max_phase_time: ClassVar[float] = 10.0
    #: The drawing: the paddle (a bar through the pivot at the mirror law's angle θ) and the
    #: ball (a dot).
    drawing = (("paddle_back", "pivot", "paddle_tip"),)
    #: No ground under the scene (see :mod:`gaitopt.animation`).
    on_ground: ClassVar[bool] = False

    restitution: float = restitution_parameter(
        0.8, "coefficient of restitution e of the ball on the paddle", "as the line juggler"
    )
    kappa1: float = energy_gain_parameter(
        "as the line juggler: stable range (0, 2/((1+e) ḃ_d²)) = (0, 0.1235)"
    )
    kappa_x: float = parameter(
        0.15, unit="rad/m", low=-10.0, high=10.0,
        doc="horizontal-position gain κ_x of the mirror law (paddle tilt per metre of x − x̄)",
        source="inside the stable range (0, (4 − 2 a κ_ẋ)/(a T)) = (0, 0.884) at the defaults",
    )  # fmt: skip
    kappa_xdot: float = parameter(
        0.1, unit="rad s/m", low=-10.0, high=10.0,
        doc="horizontal-velocity gain κ_ẋ of the mirror law",
        source="inside the stable range (0, 2/((1+e) ḃ_d)) = (0, 0.370); deadbeat at 0.185",
    )  # fmt: skip
    desired_speed: float = impact_speed_parameter("as the line juggler")
    desired_position: float = length_parameter(
        0.5,
        "desired impact point x̄ on the paddle (distance from the pivot)",
        "a bar of about a metre (Buehler et al. 1990's one-link juggler)",
        high=100.0,
    )
    gravity: float = gravity_parameter()

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        e, k1, g = sym.restitution, sym.kappa1, sym.gravity
        kx, kv, vd, xbar = sym.kappa_x, sym.kappa_xdot, sym.desired_speed, sym.desired_position
        kappa0 = (1 - e) / (1 + e)

        def energy(y, vx, vy):
            return 0.5 * (vx**2 + vy**2) + g * y

        def kappa(E):
            return kappa0 + k1 * (0.5 * vd**2 - E)

        def tilt(x, vx):  # horizontal correction of the mirror law
            return kx * (x - xbar) + kv * vx

        def paddle(x, y, vx, vy):
            """Mirror law: paddle angle θ, angular velocity θ̇, normal n, contact point s."""
            k = kappa(energy(y, vx, vy))
            theta = -k * ca.atan2(y, x) + tilt(x, vx)
            theta_dot = -k * (x * vy - y * vx) / (x**2 + y**2) + kx * vx  # κ, ẋ const in flight
            n = ca.vertcat(-ca.sin(theta), ca.cos(theta))
            s = x * ca.cos(theta) + y * ca.sin(theta)
            return theta, theta_dot, n, s

        def normal_velocity(x, y, vx, vy):
            """Relative normal velocity w_n = (v − θ̇ s n)·n of the ball and the paddle point."""
            _, theta_dot, n, s = paddle(x, y, vx, vy)
            return vx * n[0] + vy * n[1] - theta_dot * s, n

        def impact(x, y, vx, vy):
            """v⁺ = v⁻ − (1 + e) w_n n; position unchanged; hold ẋ⁻ and E⁻."""
            w_n, n = normal_velocity(x, y, vx, vy)
            v_plus = ca.vertcat(vx, vy) - (1 + e) * w_n * n
            return ca.vertcat(x, y, v_plus, vx, energy(y, vx, vy))

        xs, (x, y, vx, vy, _, _) = sym.states(*STATES)
        flow = sym.function("flow", xs, ca.vertcat(vx, vy, 0, -g, 0, 0))
        theta, _, n, _ = paddle(x, y, vx, vy)
        w_n, _ = normal_velocity(x, y, vx, vy)
        hit = Transition(
            name="impact",
            guard=sym.function("guard", xs, -x * ca.sin(theta) + y * ca.cos(theta)),
            direction=-1,
            reset=sym.function("reset", xs, impact(x, y, vx, vy)),
            target=0,
            admissible=sym.function("admissible", xs, -w_n),  # ball approaches the paddle
            doc="ball meets the mirror-law paddle, d = n·(x, y) = 0; v⁺ = v⁻ − (1 + e) w_n n",
        )
        dropped = fall(
            sym,
            xs,
            "ball dropped (not thrown up by the paddle)",
            y + DROP_DEPTH,
            f"y < −{DROP_DEPTH:g} m: the ball fell past the paddle",
        )
        over = fall(
            sym,
            xs,
            "ball crossed over the pivot",
            x,
            "x = 0: the ball left the paddle's right arm (the mirror law needs x > 0)",
        )
        # The ball stays above the paddle between impacts: its distance d = n·(x, y) from the
        # paddle line is zero at the impact that starts a flight (it must rise at once) and at the
        # one that ends it.
        above = sym.constraint(
            "ball above the paddle",
            xs,
            -x * ca.sin(theta) + y * ca.cos(theta),
            "ball below the paddle",
            at_start=True,
            at_end=True,
            unit="m",
            source="the paddle is solid (Buehler et al. 1994)",
        )
        # Drawing points (m, pivot at the origin): the paddle along t = (cos θ, sin θ) and the
        # ball; the ball's drawn distance from the paddle line is the constraint's n·(x, y).
        along = ca.vertcat(ca.cos(theta), ca.sin(theta))
        points = ca.Function(
            "points",
            [xs, sym.p],
            [
                ca.horzcat(
                    PADDLE_REACH[0] * xbar * along,
                    ca.DM.zeros(2, 1),
                    PADDLE_REACH[1] * xbar * along,
                    ca.vertcat(x, y),
                )
            ],
        )
        flight = Phase(
            "flight",
            STATES,
            flow,
            (hit, dropped, over),
            {"energy": sym.conserved("energy", xs, energy(y, vx, vy))},
            points=points,
            point_names=("paddle_back", "pivot", "paddle_tip", "ball"),
            constraints=(above,),
        )

        s = ca.SX.sym("s", 3)
        x0, vx0, E0 = s[0], s[1], s[2]
        psi = tilt(x0, vx0) / (1 + kappa(E0))  # on the guard: (1 + κ) ψ = tilt
        y0 = x0 * ca.tan(psi)
        vy0 = -ca.sqrt(2 * (E0 - g * y0) - vx0**2)  # falling onto the paddle
        section = Section(
            ("x", "x_dot_pre", "energy_pre"),
            sym.lift(s, impact(x0, y0, vx0, vy0)),
            "just before an impact: x = impact position, x_dot_pre, energy_pre = pre-impact "
            "horizontal velocity and energy; y on the paddle, velocities after the impact",
        )
        return (flight,), section

    # -- closed forms ------------------------------------------------------------------------
    @property
    def kappa0(self) -> float:
        """``κ0 = (1 − e)/(1 + e)`` (the line juggler's: restitution losses balanced at E_d)."""
        return (1 - self.restitution) / (1 + self.restitution)

    @property
    def desired_energy(self) -> float:
        """``E_d = ½ ḃ_d²`` (J/kg)."""
        return 0.5 * self.desired_speed**2

    def kappa(self, y: float, x_dot: float, y_dot: float) -> float:
        """Mirror-law gain ``κ = κ0 + κ1 (E_d − E)``."""
        energy = 0.5 * (x_dot**2 + y_dot**2) + self.gravity * y
        return self.kappa0 + self.kappa1 * (self.desired_energy - energy)

    def paddle_state(self, x: float, y: float, x_dot: float, y_dot: float) -> tuple[float, float]:
        """Paddle angle θ (rad) and angular velocity θ̇ (rad/s) the mirror law commands."""
        k = self.kappa(y, x_dot, y_dot)
        theta = -k * math.atan2(y, x) + self.kappa_x * (x - self.desired_position)
        theta += self.kappa_xdot * x_dot
        theta_dot = -k * (x * y_dot - y * x_dot) / (x**2 + y**2) + self.kappa_x * x_dot
        return theta, theta_dot

    def closed_form_fixed_point(self) -> dict[str, float]:
        """``(x̄, 0, E_d)``: the vertical bounce on the line ``x = x̄``."""
        return {"x": self.desired_position, "x_dot_pre": 0.0, "energy_pre": self.desired_energy}

    def fixed_point(self) -> dict[str, float]:
        """Deprecated name of :meth:`closed_form_fixed_point` (``fixed_point`` is the found
        gait's, :attr:`gaitopt.LimitCycle.fixed_point`)."""
        warnings.warn(
            "PlanarJuggler.fixed_point() is now closed_form_fixed_point()",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.closed_form_fixed_point()

    def horizontal_matrix(self) -> np.ndarray:
        """Linearised horizontal map in ``(ξ, u) = (x − x̄, ẋ⁻)`` (module docstring)."""
        a = (1 + self.restitution) * self.desired_speed
        T = 2 * self.desired_speed / self.gravity
        du = np.array([-a * self.kappa_x, 1 - a * self.kappa_xdot])  # u' = du · (ξ, u)
        return np.array([[1, 0], [0, 0]]) + np.outer([T, 1], du)

    def multipliers_closed_form(self) -> np.ndarray:
        """The three multipliers: ``λ_E = 1 − (1 + e) κ1 ḃ_d²`` and the horizontal pair."""
        energy = 1 - (1 + self.restitution) * self.kappa1 * self.desired_speed**2
        return np.concatenate([[energy], np.linalg.eigvals(self.horizontal_matrix())])

    def stable_horizontal_gains(self) -> dict[str, tuple[float, float]]:
        """Jury conditions: ``κ_ẋ ∈ (0, 2/a)``; ``κ_x ∈ (0, (4 − 2 a κ_ẋ)/(a T))``."""
        a = (1 + self.restitution) * self.desired_speed
        T = 2 * self.desired_speed / self.gravity
        return {
            "kappa_xdot": (0.0, 2 / a),
            "kappa_x": (0.0, (4 - 2 * a * self.kappa_xdot) / (a * T)),
        }

    def deadbeat_gains(self) -> dict[str, float]:
        """All three multipliers zero: κ1 = 1/((1 + e) ḃ_d²), κ_ẋ = 1/a, κ_x = 1/(a T)."""
        a = (1 + self.restitution) * self.desired_speed
        T = 2 * self.desired_speed / self.gravity
        return {
            "kappa1": 1 / (a * self.desired_speed),
            "kappa_xdot": 1 / a,
            "kappa_x": 1 / (a * T),
        }

    def existence_note(self) -> str | None:
        hi = 2 / ((1 + self.restitution) * self.desired_speed**2)
        gains = self.stable_horizontal_gains()
        return (
            f"planar juggler: fixed point (x, x_dot_pre, energy_pre) = ({self.desired_position:g}, "
            f"0, {self.desired_energy:g}) for κ1 > 0; stable (linearisation, module docstring) "
            f"for κ1 in (0, {hi:.4g}), κ_ẋ in (0, {gains['kappa_xdot'][1]:.4g}), κ_x in "
            f"(0, {gains['kappa_x'][1]:.4g}); here κ1 = {self.kappa1:g}, κ_ẋ = "
            f"{self.kappa_xdot:g}, κ_x = {self.kappa_x:g}"
        )

    def default_start(self) -> dict[str, float]:
        """A throw 5 cm beyond x̄, drifting outwards at 0.1 m/s, 20 % under the desired energy.

        The offsets are halved until the impact is feasible with room to spare: the paddle's tilt
        ``κ_x (x − x̄) + κ_ẋ ẋ`` puts the impact at the height ``y = x tan ψ`` (module
        docstring), which must leave at least half the energy for the vertical speed,
        ``g y ≤ ½ (E − ½ ẋ²)`` (a large ``κ_ẋ`` or ``x̄`` tilts the paddle so far that the
        nominal throw would have to hit it above its own energy height).  With no offset the
        impact is on the horizontal paddle at ``y = 0``, always feasible.
        """
        energy = 0.8 * self.desired_energy
        for k in range(40):
            dx, dv = 0.05 * 0.5**k, 0.1 * 0.5**k
            x = self.desired_position + dx
            kappa = self.kappa0 + self.kappa1 * (self.desired_energy - energy)
            psi = (self.kappa_x * dx + self.kappa_xdot * dv) / (1 + kappa)
            if abs(psi) < 1.4 and self.gravity * x * math.tan(psi) <= 0.5 * (energy - dv**2 / 2):
                return {"x": x, "x_dot_pre": dv, "energy_pre": energy}
        return {"x": self.desired_position, "x_dot_pre": 0.0, "energy_pre": energy}
