"""The simplest walking model (Garcia, Chatterjee, Ruina & Coleman 1998, J. Biomech. Eng. 120).

A compass walker with a point mass at the hip and infinitesimal point masses at the feet, in the
limit foot/hip mass ratio β → 0, with time scaled by sqrt(l/g).  θ is the stance leg's angle from
the slope normal, φ the angle between the legs.  Garcia et al. eqs. (3)–(4):

    θ̈ = sin(θ − γ)
    φ̈ = sin(θ − γ) + sin φ · (θ̇² − cos(θ − γ))

Heel strike (eq. 5) when ``φ − 2θ = 0`` with the stance leg past the slope normal (θ < 0); the
scuffing of the swing foot near φ = 0 is ignored, as in the paper.  Transition (eq. 6):
``θ⁺ = −θ⁻``, ``φ⁺ = −2θ⁻``, ``θ̇⁺ = cos(2θ⁻) θ̇⁻``, ``φ̇⁺ = cos(2θ⁻)(1 − cos 2θ⁻) θ̇⁻``.

At γ = 0.009 the paper gives a stable long-step gait (θ* = 0.20031090049483,
θ̇* = −0.19983247291764) and an unstable short-step gait (θ* = 0.19393736960624,
θ̇* = −0.20386692731962).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..parameters import parameter

__all__ = ["SimplestWalker"]


@dataclass(frozen=True)
class SimplestWalker(HybridModel):
    """Garcia's simplest walker: states ``theta``, ``phi`` (rad), ``theta_dot``, ``phi_dot``
    (rad per unit of dimensionless time τ = t·sqrt(g/l)); g = l = 1."""

    name = "simplest_walker"
    state_units = {
        "theta": "rad",
        "phi": "rad",
        "theta_dot": "rad/τ",
        "phi_dot": "rad/τ",
    }  # for axis labels
    time_unit = "τ"  # dimensionless time τ = t·sqrt(g/l)
    title = "Simplest walking model"
    reference = "Garcia, Chatterjee, Ruina & Coleman 1998"

    slope: float = parameter(
        0.009,
        unit="rad",
        doc="ground slope γ",
        source="Garcia et al. 1998, the slope of their tabulated gaits",
        low=0.0,
        high=0.05,
        low_open=True,
    )

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        x, (theta, phi, theta_dot, phi_dot) = sym.states("theta", "phi", "theta_dot", "phi_dot")
        gamma = sym.slope
        theta_dd = ca.sin(theta - gamma)  # Garcia eq. (3)
        phi_dd = theta_dd + ca.sin(phi) * (theta_dot**2 - ca.cos(theta - gamma))  # eq. (4)
        flow = sym.function("flow", x, ca.vertcat(theta_dot, phi_dot, theta_dd, phi_dd))
        c = ca.cos(2 * theta)
        heel_strike = Transition(
            name="heel strike",
            guard=sym.function("guard", x, phi - 2 * theta),  # eq. (5)
            direction=+1,
            reset=sym.function(
                "reset", x, ca.vertcat(-theta, -2 * theta, c * theta_dot, c * (1 - c) * theta_dot)
            ),  # eq. (6)
            target=0,
            admissible=sym.function("admissible", x, -theta),  # stance leg past the normal
            foothold="swing_foot",
            doc="φ − 2θ = 0 rising with θ < 0 (Garcia eq. 5); transition eq. (6)",
        )
        fall = Transition(
            name="fall",
            guard=sym.function("guard", x, ca.cos(theta - gamma)),  # hip down to the ground
            direction=-1,
            reset=None,
            target=None,
            doc="the stance leg reaches the ground",
        )
        # Along the flow the hip's energy ½θ̇² + cos(θ − γ) is conserved (β → 0: the feet carry
        # no energy); scaled by m_h g l.
        energy = sym.conserved("energy", x, 0.5 * theta_dot**2 + ca.cos(theta - gamma))
        # Drawing, world frame: slope frame (x down the slope, y along the normal) rotated by γ.
        rot = ca.vertcat(
            ca.horzcat(ca.cos(gamma), ca.sin(gamma)), ca.horzcat(-ca.sin(gamma), ca.cos(gamma))
        )
        hip = ca.vertcat(-ca.sin(theta), ca.cos(theta))
        swing_foot = hip + ca.vertcat(ca.sin(theta - phi), -ca.cos(theta - phi))
        hip_velocity = ca.jtimes(hip, x, ca.vertcat(theta_dot, phi_dot, 0, 0))
        points = ca.Function(
            "points", [x, sym.p], [rot @ ca.horzcat(ca.DM.zeros(2, 1), hip, swing_foot)]
        )
        bodies = ca.Function(
            "bodies",
            [x, sym.p],
            [ca.DM(1.0), rot @ hip, rot @ hip_velocity],
            ["x", "p"],
            ["m", "r", "v"],
        )
        # The stance leg pushes: on a massless leg the hip's weight and centripetal force give
        # the leg compression m_h (g cos(θ − γ) − l θ̇²) ≥ 0 (scaled by m_h g): the walking speed
        # limit Froude < 1 (Alexander 1976; Kuo 2007).  The swing foot's scuff near φ = 0 is
        # ignored, as in Garcia et al. 1998.
        push = sym.constraint(
            "stance leg in compression",
            x,
            ca.cos(theta - gamma) - theta_dot**2,
            "stance foot lifts off",
            unit="m_h·g",
            source="hip mass on a massless leg: leg force m_h (g cos(θ − γ) − l θ̇²) ≥ 0",
        )
        phase = Phase(
            "single support",
            ("theta", "phi", "theta_dot", "phi_dot"),
            flow,
            (heel_strike, fall),
            {"energy": energy},
            points=points,
            point_names=("stance_foot", "hip", "swing_foot"),
            bodies=bodies,
            constraints=(push,),
        )
        s, (s_theta, s_theta_dot) = sym.states("theta", "theta_dot")
        lift = ca.vertcat(
            s_theta, 2 * s_theta, s_theta_dot, (1 - ca.cos(2 * s_theta)) * s_theta_dot
        )
        section = Section(
            ("theta", "theta_dot"),
            sym.lift(s, lift),
            "just after heel strike: phi = 2·theta, phi_dot = (1 − cos 2θ)·theta_dot",
        )
        return (phase,), section

    def default_start(self) -> dict[str, float]:
        """Near the long-step gait at γ = 0.009 (Garcia et al. 1998, rounded)."""
        return {"theta": 0.2, "theta_dot": -0.2}
