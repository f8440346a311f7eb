"""The rimless wheel rolling down a slope (McGeer 1990; Coleman et al. 1997; Tedrake,
Underactuated Robotics, ch. "Simple models of walking and running", §rimless wheel).

A point mass on ``spokes`` massless spokes of length ``l``; the stance spoke is an inverted
pendulum ``θ̈ = (g/l) sin θ`` with θ the stance spoke's angle from vertical, positive downhill.
With ``α = π/spokes`` and slope ``γ``, the downhill spoke strikes when ``θ = γ + α`` (forward
step: ``θ⁺ = θ − 2α``); rocking backward, the uphill spoke strikes when ``θ = γ − α`` (backward
step: ``θ⁺ = θ + 2α``).  Each impact is inelastic and keeps angular momentum about the new
contact: ``θ̇⁺ = cos(2α) θ̇⁻``.

The Poincaré section is the chapter's: just after *any* impact, two spokes on the ground, with
the section coordinate ``θ̇⁺``; ``θ = γ − α`` after a forward impact (``θ̇⁺ ≥ 0``) and ``θ = γ + α``
after a backward one (``θ̇⁺ < 0``).  Closed forms (Tedrake; energy through the swing, angular
momentum through each impact), with ``θ_top = max(0, γ − α)`` the highest point of the hub
between the two contacts:

* ``ω₁ = sqrt(2 g/l (cos θ_top − cos(γ − α)))`` (``= sqrt(2 g/l (1 − cos(γ − α)))`` for γ < α,
  0 for γ ≥ α) and ``ω₂ = −sqrt(2 g/l (cos θ_top − cos(γ + α)))`` (``−sqrt(2 g/l (1 − cos(γ +
  α)))`` for γ < α, ``−sqrt(4 g/l sin α sin γ)`` for γ ≥ α: the "γ > α form");
* ``θ̇⁺ₙ > ω₁``: ``θ̇⁺ₙ₊₁ = cos 2α sqrt(θ̇⁺ₙ² + 4 g/l sin α sin γ)`` (vaults forward);
  ``ω₂ < θ̇⁺ₙ < ω₁``: ``θ̇⁺ₙ₊₁ = −cos 2α θ̇⁺ₙ`` (rocks back); ``θ̇⁺ₙ < ω₂``:
  ``θ̇⁺ₙ₊₁ = −cos 2α sqrt(θ̇⁺ₙ² − 4 g/l sin α sin γ)`` (vaults backward, uphill);
* rolling fixed point ``ω* = cot(2α) sqrt(4 (g/l) sin α sin γ)``, multiplier ``cos² 2α``,
  existing where ``ω* > ω₁`` (always for γ ≥ α);
* standing ``ω = 0``, a fixed point of the rocking branch with multiplier ``−cos 2α`` per impact
  (stable), reached after infinitely many impacts in finite time (the intervals shrink
  geometrically); it exists only for γ < α (for γ ≥ α the hub is never between the contacts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..mechanics import bodies_function
from ..parameters import gravity_parameter, parameter
from .quantities import length_parameter, slope_parameter

__all__ = ["RimlessWheel"]


@dataclass(frozen=True)
class RimlessWheel(HybridModel):
    """Rimless wheel: state ``theta`` (rad, from vertical, + downhill), ``theta_dot`` (rad/s)."""

    name = "rimless_wheel"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("theta", "theta_dot")
    declared_coordinates = ("theta_dot",)
    declared_section_doc = (
        "just after any impact: theta = slope − π/spokes if theta_dot ≥ 0 (forward), slope + "
        "π/spokes if theta_dot < 0 (backward)"
    )
    title = "Rimless wheel"
    reference = "McGeer 1990; Coleman, Chatterjee & Ruina 1997; Tedrake, Underactuated Robotics"
    state_units = {"theta": "rad", "theta_dot": "rad/s"}

    spokes: float = parameter(
        8, unit="1", low=3, high=64, integer=True,
        doc="number of spokes", source="Drake RimlessWheel default",
    )  # fmt: skip
    length: float = length_parameter(
        1.0, "spoke length l", "Drake RimlessWheel default", high=100.0
    )
    gravity: float = gravity_parameter()
    slope: float = slope_parameter(
        0.08,
        "Drake RimlessWheel default: produces standing and rolling fixed points",
        (0.0, 1.0),
        high_open=True,
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        object.__setattr__(self, "spokes", int(self.spokes))

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        x, (theta, theta_dot) = sym.states("theta", "theta_dot")
        g, length, gamma = sym.gravity, sym.length, sym.slope
        alpha = ca.pi / sym.spokes
        flow = sym.function("flow", x, ca.vertcat(theta_dot, g / length * ca.sin(theta)))
        forward = Transition(
            name="forward step",
            guard=sym.function("guard", x, theta - (gamma + alpha)),  # θ = γ + α
            direction=+1,
            reset=sym.function(
                "reset", x, ca.vertcat(theta - 2 * alpha, ca.cos(2 * alpha) * theta_dot)
            ),
            target=0,
            foothold="next_foot",
            doc="downhill spoke strikes at θ = γ + α; θ⁺ = θ − 2α, θ̇⁺ = cos(2α) θ̇",
        )
        backward = Transition(
            name="backward step",
            guard=sym.function("guard", x, theta - (gamma - alpha)),  # θ = γ − α
            direction=-1,
            reset=sym.function(
                "reset", x, ca.vertcat(theta + 2 * alpha, ca.cos(2 * alpha) * theta_dot)
            ),
            target=0,
            foothold="previous_foot",
            doc="uphill spoke strikes at θ = γ − α; θ⁺ = θ + 2α, θ̇⁺ = cos(2α) θ̇",
            returns_to_section=True,  # Tedrake's map counts every impact
        )
        energy = sym.conserved(
            "energy", x, 0.5 * length**2 * theta_dot**2 + g * length * ca.cos(theta)
        )  # per unit mass (J/kg)
        # Points for drawing, world frame (x downhill-horizontal, y up), contact foot at 0.
        hub = length * ca.vertcat(ca.sin(theta), ca.cos(theta))
        spoke_angles = [theta - 2 * alpha * k for k in (0, 1, -1)]
        feet = [hub - length * ca.vertcat(ca.sin(a), ca.cos(a)) for a in spoke_angles]
        points = ca.Function("points", [x, sym.p], [ca.horzcat(hub, *feet)])
        phase = Phase(
            "stance",
            ("theta", "theta_dot"),
            flow,
            (forward, backward),
            {"energy": energy},
            points=points,
            point_names=("hub", "foot", "next_foot", "previous_foot"),
            # The wheel's mass at its hub (per unit mass, 1 kg: the map does not depend on it);
            # the impact θ̇⁺ = cos 2α θ̇⁻ is the conservation of its angular momentum about the
            # new foot (Coleman, Chatterjee & Ruina 1997).
            bodies=bodies_function([(ca.DM(1.0), hub)], x, theta, theta_dot, sym.p),
        )
        s = ca.SX.sym("s", 1)
        section = Section(
            ("theta_dot",),
            # After a forward impact (θ̇⁺ ≥ 0) the stance spoke is the downhill one, θ = γ − α;
            # after a backward impact (θ̇⁺ < 0) the uphill one, θ = γ + α.
            sym.lift(s, ca.vertcat(ca.if_else(s >= 0, gamma - alpha, gamma + alpha), s)),
            "just after any impact: theta = slope − π/spokes if theta_dot ≥ 0 (forward), "
            "slope + π/spokes if theta_dot < 0 (backward)",
        )
        return (phase,), section

    # -- closed forms (Tedrake, Underactuated Robotics, §rimless wheel) ----------------------
    @property
    def alpha(self) -> float:
        """Half the angle between spokes, ``α = π/spokes`` (rad)."""
        return math.pi / self.spokes

    def rolling_speed(self) -> float:
        """Closed-form rolling fixed point ``ω* = cot 2α · sqrt(4 g/l sin α sin γ)`` (rad/s)."""
        a, g, gamma = self.alpha, self.gravity / self.length, self.slope
        return math.sqrt(4 * g * math.sin(a) * math.sin(gamma)) / math.tan(2 * a)

    def _top(self) -> float:
        """Highest point of the hub between the two contacts: ``θ_top = max(0, γ − α)`` (rad)."""
        return max(0.0, self.slope - self.alpha)

    def vaulting_speed(self) -> float:
        """``ω₁ = sqrt(2 g/l (cos θ_top − cos(γ − α)))``: least post-impact rate that vaults the
        hub forward over the stance spoke (rad/s); ``sqrt(2 g/l (1 − cos(γ − α)))`` for γ < α, 0
        for γ ≥ α (the hub starts past the top)."""
        g = self.gravity / self.length
        return math.sqrt(
            2 * g * max(0.0, math.cos(self._top()) - math.cos(self.slope - self.alpha))
        )

    def backward_vaulting_speed(self) -> float:
        """``ω₂ = −sqrt(2 g/l (cos θ_top − cos(γ + α)))`` (rad/s, negative): a backward impact's
        rate below which the hub vaults back uphill over the stance spoke; ``−sqrt(2 g/l (1 −
        cos(γ + α)))`` for γ < α and ``−sqrt(4 g/l sin α sin γ)`` for γ ≥ α."""
        g = self.gravity / self.length
        return -math.sqrt(2 * g * (math.cos(self._top()) - math.cos(self.slope + self.alpha)))

    def closed_form_map(self, theta_dot: float) -> float:
        """Tedrake's return map: the post-impact rate at the next impact, from the post-impact
        rate ``θ̇⁺ₙ`` (rad/s), by energy through the swing and angular momentum through the impact.

        * ``θ̇⁺ₙ > ω₁``: the hub vaults forward, ``cos 2α · sqrt(θ̇⁺ₙ² + 4 g/l sin α sin γ)``;
        * ``ω₂ < θ̇⁺ₙ < ω₁``: it rocks back onto the spoke it left, ``−cos 2α · θ̇⁺ₙ``;
        * ``θ̇⁺ₙ < ω₂``: it vaults backward, ``−cos 2α · sqrt(θ̇⁺ₙ² − 4 g/l sin α sin γ)``;
        * NaN at ``θ̇⁺ₙ = ω₁`` or ``ω₂`` exactly (the hub stops on top: no next impact);
          ``0`` at ``θ̇⁺ₙ = 0`` for γ < α (standing).
        """
        a, g, gamma = self.alpha, self.gravity / self.length, self.slope
        c = 4 * g * math.sin(a) * math.sin(gamma)
        omega1, omega2 = self.vaulting_speed(), self.backward_vaulting_speed()
        w = float(theta_dot)
        if w > omega1 or (w == 0.0 and omega1 == 0.0 and gamma > a):
            return math.cos(2 * a) * math.sqrt(w**2 + c)
        if omega2 < w < omega1:
            return -math.cos(2 * a) * w
        if w < omega2:
            return -math.cos(2 * a) * math.sqrt(w**2 - c)
        return math.nan

    def standing_exists(self) -> bool:
        """Whether the wheel can stand still: the vertical through the hub falls between two
        spokes on the ground, ``γ < α`` (for γ ≥ α standing is impossible)."""
        return self.slope < self.alpha

    def standing_multiplier(self) -> float:
        """Slope of the return map at the standing fixed point ω = 0 (the rocking branch):
        ``−cos 2α`` per impact (``cos² 2α`` per rocking pair); |λ| < 1, so standing is stable.
        NaN where standing is impossible (γ ≥ α)."""
        return -math.cos(2 * self.alpha) if self.standing_exists() else math.nan

    def standing_note(self) -> str:
        """Standing still, in words: exists (with its multiplier) or is impossible, and why."""
        if not self.standing_exists():
            return (
                f"standing is impossible at slope {self.slope:g} ≥ π/spokes = {self.alpha:.4g}: "
                f"the vertical through the hub never falls between two spokes on the ground"
            )
        return (
            f"standing (ω = 0) is a stable fixed point of the rocking branch, multiplier "
            f"−cos 2α = {self.standing_multiplier():.4g} per impact; it is reached after "
            f"infinitely many impacts in finite time (their intervals shrink geometrically)"
        )

    def existence_note(self) -> str | None:
        """Rolling exists only where the closed-form ω* exceeds the vaulting rate ω₁."""
        keep = math.cos(2 * self.alpha)  # θ̇⁺ = cos 2α · θ̇⁻ at each impact
        if keep <= 1e-12:  # 3 or 4 spokes: α ≥ π/4, so cot 2α ≤ 0 and ω* is no rolling speed
            effect = "stops the wheel dead" if keep > -1e-12 else "sends the wheel backwards"
            keep = keep if abs(keep) > 1e-12 else 0.0
            return (
                f"closed form: with {self.spokes:g} spokes (α = π/{self.spokes:g} ≥ π/4) each "
                f"impact keeps cos 2α = {keep:.3g} of the rate, θ̇⁺ = cos 2α · θ̇⁻, which "
                f"{effect}: there is no forward rolling fixed point at any slope (ω* = cot 2α · "
                f"sqrt(4 g/l sin α sin γ) needs cot 2α > 0, i.e. at least 5 spokes); the wheel "
                f"comes to rest (Tedrake, Underactuated Robotics, rimless wheel)"
            )
        omega, omega1 = self.rolling_speed(), self.vaulting_speed()
        if omega > omega1:
            return None
        return (
            f"closed form: rolling needs ω* = {omega:.4g} rad/s above the vaulting rate ω₁ = "
            f"{omega1:.4g} rad/s; at slope {self.slope:g} the wheel comes to rest instead "
            f"(Tedrake, Underactuated Robotics, rimless wheel)"
        )

    def outline(self, phase, x, points):
        """Every spoke from the hub, spoke k at angle θ − 2αk (NaN-separated), for drawing."""
        hub = np.asarray(points)[:, phase.point_names.index("hub")]
        theta = float(x[phase.states.index("theta")])
        segments = []
        for k in range(int(self.spokes)):
            angle = theta - 2 * self.alpha * k
            foot = hub - self.length * np.array([math.sin(angle), math.cos(angle)])
            segments += [hub, foot, [np.nan, np.nan]]
        return np.array(segments, dtype=float).T

    def default_start(self) -> dict[str, float]:
        """Twice the vaulting rate ω₁ plus 0.1 rad/s (rolls on, and converges to rolling where it
        exists); for γ ≥ α, where ω₁ = 0, 1.5 ω* (above the rolling fixed point)."""
        if self.slope >= self.alpha:
            return {"theta_dot": 1.5 * abs(self.rolling_speed()) + 0.1}
        return {"theta_dot": 2.0 * self.vaulting_speed() + 0.1}
