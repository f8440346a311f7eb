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

Actuation (Kuo 2002, "Energetics of actively powered locomotion using the simplest walking
model", J. Biomech. Eng. 124:113–120), both zero by default (the passive model, unchanged):

* ``push_off`` P, an impulse (units of M·sqrt(g·l)) along the trailing (stance) leg, from its
  foot to the hip, applied just before the heel-strike impulse: an *impulsive input*
  (:attr:`~gaitopt.HybridModel.impulsive_inputs`) of the heel-strike reset.  The hip's velocity
  becomes v⁻ + P ê_trailing, and the heel strike then removes its component along the new stance
  leg, so that (Kuo 2002; θ = θ⁻ the pre-impact angle)

      θ̇⁺ = cos(2θ) θ̇⁻ + sin(2θ) P,   φ̇⁺ = (1 − cos 2θ) θ̇⁺,

  the second because the infinitesimal trailing foot keeps zero velocity across the leg.  As
  ê_trailing ⟂ v⁻ the push-off does the work P²/2 (M·g·l) on the hip.  The leg pushes: P ≥ 0.
  The heel-strike impulse must still press the new leg into the ground,
  θ̇⁻ sin 2θ − P cos 2θ ≥ 0 (a larger push-off would launch the hip off the new leg; at Kuo's
  steady gait P = |θ̇| tan|θ| it is far from binding).
* ``hip_torque`` τ (units of M·g·l) on the stance leg, reacted by the upper body (as Kuo 2002's
  hip-torque powering; a finite torque cannot react against the infinitesimal swing leg), positive
  forward: θ̈ = sin(θ − γ) − τ; the swing foot, hanging from the accelerated hip, then has
  φ̈ = θ̈ (1 − cos φ) + θ̇² sin φ + sin(θ − φ − γ), i.e. Garcia's eq. (4) minus τ (1 − cos φ).
  Its power is τ·(−θ̇).
* ``hip_stiffness`` k, a parameter (default 0): Kuo's (2002) hip spring between the legs, its
  torque scaled by the foot mass (m_f·g·l per rad) so that it swings the infinitesimal foot,
  φ̈ − k φ, and does no work on the body: it sets the step frequency apart from the speed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import casadi as ca
import numpy as np

from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..parameters import parameter
from .quantities import slope_parameter

__all__ = ["SimplestWalker"]


@dataclass(frozen=True)
class SimplestWalker(HybridModel):
    """Garcia's simplest walker: states ``theta``, ``phi`` (rad), ``theta_dot``, ``phi_dot``
    (rad per unit of dimensionless time τ = t·sqrt(g/l)); g = l = 1."""

    name = "simplest_walker"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("theta", "phi", "theta_dot", "phi_dot")
    declared_coordinates = ("theta", "theta_dot")
    declared_section_doc = "just after heel strike: phi = 2·theta, phi_dot = (1 − cos 2θ)·theta_dot"
    state_units = {
        "theta": "rad",
        "phi": "rad",
        "theta_dot": "rad/τ",
        "phi_dot": "rad/τ",
    }  # for axis labels
    time_unit = "τ"  # dimensionless time τ = t·sqrt(g/l)
    length_unit = "l"  # lengths in leg lengths (l = 1)
    energy_unit = "M*g*l"  # energies and work in units of M·g·l (Kuo 2002)
    title = "Simplest walking model"
    reference = "Garcia, Chatterjee, Ruina & Coleman 1998; Kuo 2002 (actuation)"
    inputs = ("hip_torque", "push_off")
    input_units = ("M*g*l", "M*sqrt(g*l)")
    impulsive_inputs = ("push_off",)
    #: The trailing leg can only push (Kuo 2002's push-off impulse is P ≥ 0).
    input_bounds: ClassVar[dict[str, tuple[float, float]]] = {"push_off": (0.0, float("inf"))}

    slope: float = slope_parameter(
        0.009,
        "Garcia et al. 1998, the slope of their tabulated gaits",
        (0.0, 0.05),
        doc="ground slope γ",
    )

    # Range: the long-step gait exists at the default slope over all of it (solved and verified
    # at k = 0, 0.1, 0.5, 1, 2, 5, 10: step period 3.88 → 0.99 τ); its first period doubling
    # moves to steeper slopes with k (problems/simplest_walker_pd_curve.py) and leaves the
    # slope range (0.05 rad) near k ≈ 0.685.
    hip_stiffness: float = parameter(
        0.0, unit="m_f*g*l/rad", low=0.0, high=10.0,
        doc="hip spring stiffness k (Kuo 2002), scaled by the foot mass",
        source="Garcia et al. 1998: none (0); Kuo 2002 adds it to tune the step frequency",
    )  # fmt: skip

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        x, (theta, phi, theta_dot, phi_dot) = sym.states("theta", "phi", "theta_dot", "phi_dot")
        gamma = sym.slope
        tau, push = sym.input("hip_torque"), sym.input("push_off")
        passive_dd = ca.sin(theta - gamma)  # Garcia eq. (3)
        # Garcia eq. (4); with the hip torque τ on the stance leg (module docstring): θ̈ − τ and
        # φ̈ − τ (1 − cos φ).  At τ = 0 both are Garcia's expressions exactly (x − 0 = x).
        theta_dd = passive_dd - tau
        phi_dd = passive_dd + ca.sin(phi) * (theta_dot**2 - ca.cos(theta - gamma))
        phi_dd = phi_dd - tau * (1 - ca.cos(phi)) - sym.hip_stiffness * phi  # Kuo's hip spring
        flow = sym.function("flow", x, ca.vertcat(theta_dot, phi_dot, theta_dd, phi_dd))
        c = ca.cos(2 * theta)
        # Garcia eq. (6) with Kuo's (2002) push-off impulse P along the trailing leg just before
        # the heel strike: θ̇⁺ = cos 2θ θ̇⁻ + sin 2θ P; φ̇⁺ = (1 − cos 2θ) θ̇⁺.  At P = 0 the
        # expressions are eq. (6)'s exactly.
        theta_dot_plus = c * theta_dot + ca.sin(2 * theta) * push
        phi_dot_plus = c * (1 - c) * theta_dot + (1 - c) * ca.sin(2 * theta) * push
        heel_strike = Transition(
            name="heel strike",
            guard=sym.function("guard", x, phi - 2 * theta),  # eq. (5)
            direction=+1,
            reset=sym.function(
                "reset", x, ca.vertcat(-theta, -2 * theta, theta_dot_plus, phi_dot_plus)
            ),  # eq. (6), Kuo 2002
            target=0,
            admissible=sym.function("admissible", x, -theta),  # stance leg past the normal
            foothold="swing_foot",
            doc="φ − 2θ = 0 rising with θ < 0 (Garcia eq. 5); transition eq. (6) with Kuo's "
            "(2002) push-off impulse along the trailing leg just before it",
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

    def input_rates(self, phase: int) -> ca.Function:
        """The hip torque on the stance leg has the power ``τ·(−θ̇)`` (M·g·l per unit τ); the
        push-off acts only in the reset (its work is :meth:`impulse_work`): rate 0."""
        del phase
        x = ca.SX.sym("x", 4)
        p = ca.SX.sym("p", len(self.parameter_specs()))
        rates = ca.vertcat(-x[2], ca.SX(0))
        return ca.Function("input_rates", [x, p], [rates], ["x", "p"], ["rates"])

    def impulse_work(self, phase: int) -> ca.Function:
        """The push-off's work on the hip, ``P²/2`` (M·g·l): ``½|v⁻ + P ê|² − ½|v⁻|²`` with
        the trailing leg's direction ``ê`` perpendicular to the hip's velocity ``v⁻``."""
        del phase
        x = ca.SX.sym("x", 4)
        u = ca.SX.sym("u", len(self.inputs))
        p = ca.SX.sym("p", len(self.parameter_specs()))
        return ca.Function("impulse_work", [x, u, p], [0.5 * u[1] ** 2], ["x", "u", "p"], ["w"])

    @staticmethod
    def heel_strike_impulse(x: np.ndarray, push_off: float) -> float:
        """The heel-strike impulse along the new stance leg (M·sqrt(g·l)) after a push-off
        ``P`` from the pre-impact state ``x``: ``θ̇ sin 2θ − P cos 2θ``; it must be ≥ 0 (the new
        leg is pressed into the ground, not pulled)."""
        theta, theta_dot = float(x[0]), float(x[2])
        return theta_dot * np.sin(2 * theta) - push_off * np.cos(2 * theta)
