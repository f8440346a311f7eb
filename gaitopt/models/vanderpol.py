"""Van der Pol oscillator: the smooth limit cycle, as a one-phase hybrid system.

``q̈ = μ (1 − q²) q̇ − q``.  The Poincaré section ``q = 0, q̇ > 0`` is a guard with the identity
reset, so the section equation is the phase condition that pins the orbit's time origin.

Reference values (μ = 1): period 6.6632868593231301897, max q 2.00861986087484 (Hairer, Nørsett
& Wanner, "Solving ODEs I", §I.16 and §II.10).  The nontrivial multiplier is
``exp(∮ μ (1 − q²) dt)`` by Liouville's formula (trace of the flow's Jacobian is ``μ(1 − q²)``).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..parameters import parameter

__all__ = ["VanDerPol"]


@dataclass(frozen=True)
class VanDerPol(HybridModel):
    """Van der Pol oscillator ``q̈ = μ (1 − q²) q̇ − q`` (dimensionless time)."""

    name = "vanderpol"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("q", "q_dot")
    declared_coordinates = ("q_dot",)
    declared_section_doc = "q = 0, q_dot > 0"
    state_units = {"q": "1", "q_dot": "1"}  # for axis labels
    time_unit = "1"
    title = "Van der Pol oscillator"
    reference = "van der Pol 1926; Hairer, Nørsett & Wanner, Solving ODEs I"
    mesh = (8, 8)  # a long period (6.66 at μ = 1) with fast relaxation for large μ

    mu: float = parameter(
        1.0, unit="1", low=0.0, high=10.0, low_open=True,
        doc="nonlinear damping μ", source="Hairer, Nørsett & Wanner's reference case μ = 1",
    )  # fmt: skip

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        x, (q, q_dot) = sym.states("q", "q_dot")
        flow = sym.function("flow", x, ca.vertcat(q_dot, sym.mu * (1 - q**2) * q_dot - q))
        section_crossing = Transition(
            name="section crossing",
            # q increases through 0: the section q = 0, q̇ > 0.
            guard=sym.function("guard", x, q),
            direction=+1,
            reset=sym.function("reset", x, x),
            target=0,
            impact=False,
            doc="q = 0 crossed upwards; identity reset",
        )
        phase = Phase("oscillation", ("q", "q_dot"), flow, (section_crossing,))
        s = ca.SX.sym("s", 1)
        section = Section(("q_dot",), sym.lift(s, ca.vertcat(0, s)), "q = 0, q_dot > 0")
        return (phase,), section

    def default_start(self) -> dict[str, float]:
        """q̇ = 2 on q = 0, inside the basin of the limit cycle for every μ."""
        return {"q_dot": 2.0}
