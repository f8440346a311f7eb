"""The rimless wheel rolling down a slope (McGeer 1990; Coleman et al. 1997; Tedrake,
Underactuated Robotics, ch. "Simple models of walking and running", §rimless wheel).

A point mass on ``spokes`` massless spokes of length ``l``; the stance spoke is an inverted
pendulum ``θ̈ = (g/l) sin θ`` with θ the stance spoke's angle from vertical, positive downhill.
With ``α = π/spokes`` and slope ``γ``, the next spoke strikes when ``θ = γ + α`` (forward step); an
inelastic impact keeps angular momentum about the new contact: ``θ̇⁺ = cos(2α) θ̇⁻`` and
``θ⁺ = θ⁻ − 2α``.  Rocking backward, the uphill spoke strikes when ``θ = γ − α``.

Closed forms (Tedrake, eqs. for the rimless wheel): rolling fixed point
``ω* = cot(2α) sqrt(4 (g/l) sin α sin γ)``; map slope ``cos²(2α)``; rolling needs
``ω* > ω₁ = sqrt(2 (g/l) (1 − cos(γ − α)))``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca

from ..errors import ParameterError
from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..parameters import parameter

__all__ = ["RimlessWheel"]


@dataclass(frozen=True)
class RimlessWheel(HybridModel):
    """Rimless wheel: state ``theta`` (rad, from vertical, + downhill), ``theta_dot`` (rad/s)."""

    name = "rimless_wheel"
    title = "Rimless wheel"
    reference = "McGeer 1990; Coleman, Chatterjee & Ruina 1997; Tedrake, Underactuated Robotics"

    spokes: float = parameter(
        8,
        unit="1",
        doc="number of spokes",
        source="Drake RimlessWheel default",
        low=3,
        high=64,
        integer=True,
    )
    length: float = parameter(
        1.0,
        unit="m",
        doc="spoke length l",
        source="Drake RimlessWheel default",
        low=0.0,
        high=100.0,
        low_open=True,
    )
    gravity: float = parameter(
        9.81,
        unit="m/s^2",
        doc="gravitational acceleration g",
        source="standard gravity",
        low=0.0,
        high=100.0,
        low_open=True,
    )
    slope: float = parameter(
        0.08,
        unit="rad",
        doc="ground slope γ (downhill positive)",
        source="Drake RimlessWheel default: produces standing and rolling fixed points",
        low=0.0,
        high=1.0,
        high_open=True,
    )

    def check(self) -> None:
        alpha = math.pi / self.spokes
        if self.slope >= alpha:
            most = int(math.pi / self.slope) if self.slope > 0 else 64
            raise ParameterError(
                f"rimless_wheel: parameter `slope` = {self.slope:g} must be below π/spokes = "
                f"{alpha:.4g} rad with spokes = {self.spokes:g} (else the wheel cannot stand); "
                f"use a smaller slope or at most {most} spokes"
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
            doc="uphill spoke strikes at θ = γ − α; θ⁺ = θ + 2α, θ̇⁺ = cos(2α) θ̇",
        )
        energy = sym.conserved(
            "energy", x, 0.5 * length**2 * theta_dot**2 + g * length * ca.cos(theta)
        )  # per unit mass (J/kg)
        # Points for drawing, world frame (x downhill-horizontal, y up), contact foot at 0.
        hub = length * ca.vertcat(ca.sin(theta), ca.cos(theta))
        spoke_angles = [theta - 2 * alpha * k for k in range(2)]
        feet = [hub - length * ca.vertcat(ca.sin(a), ca.cos(a)) for a in spoke_angles]
        points = ca.Function("points", [x, sym.p], [ca.horzcat(hub, feet[0], feet[1])])
        phase = Phase(
            "stance",
            ("theta", "theta_dot"),
            flow,
            (forward, backward),
            {"energy": energy},
            points=points,
            point_names=("hub", "foot", "next_foot"),
        )
        s = ca.SX.sym("s", 1)
        section = Section(
            ("theta_dot",),
            sym.lift(s, ca.vertcat(gamma - alpha, s)),
            "just after a forward impact: theta = slope − π/spokes",
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

    def vaulting_speed(self) -> float:
        """``ω₁ = sqrt(2 g/l (1 − cos(γ − α)))``: least post-impact rate that vaults the hub
        over the contact (rad/s)."""
        return math.sqrt(2 * self.gravity / self.length * (1 - math.cos(self.slope - self.alpha)))

    def closed_form_map(self, theta_dot: float) -> float:
        """Post-impact rate at the next return to the section, by energy through the swing and
        angular momentum about the new contact through each impact.

        * ``ω > ω₁``: the hub vaults, ``ω⁺ₙ₊₁ = cos 2α · sqrt(ω⁺ₙ² + 4 g/l sin α sin γ)``;
        * ``0 < ω < ω₁``: it rocks back, the uphill spoke strikes with ``−ω``, the wheel swings
          back onto the downhill spoke: ``ω⁺ₙ₊₁ = cos² 2α · ω`` (valid while the backward swing,
          ``cos 2α · ω``, cannot vault backwards over the uphill spoke);
        * otherwise NaN.
        """
        a, g, gamma = self.alpha, self.gravity / self.length, self.slope
        if theta_dot > self.vaulting_speed():
            return math.cos(2 * a) * math.sqrt(theta_dot**2 + 4 * g * math.sin(a) * math.sin(gamma))
        backward_vault = math.sqrt(2 * g * (1 - math.cos(gamma + a)))
        if 0 < theta_dot and math.cos(2 * a) * theta_dot < backward_vault:
            return math.cos(2 * a) ** 2 * theta_dot
        return math.nan

    def existence_note(self) -> str | None:
        """Rolling exists only where the closed-form ω* exceeds the vaulting rate ω₁."""
        omega, omega1 = self.rolling_speed(), self.vaulting_speed()
        if omega > omega1:
            return None
        return (
            f"closed form: rolling needs ω* = {omega:.4g} rad/s above the vaulting rate ω₁ = "
            f"{omega1:.4g} rad/s; at slope {self.slope:g} the wheel comes to rest instead "
            f"(Tedrake, Underactuated Robotics, rimless wheel)"
        )

    def default_start(self) -> dict[str, float]:
        """Twice the vaulting rate ω₁: rolls on, and converges to rolling where it exists."""
        return {"theta_dot": 2.0 * self.vaulting_speed() + 0.1}
