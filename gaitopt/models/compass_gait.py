"""The compass gait: two rigid legs joined at the hip, walking passively down a slope.

Goswami, Thuilot & Espiau 1996 ("Compass-like biped robot part I: stability and bifurcation of
passive gaits", INRIA RR-2996); conventions and defaults of Drake's ``CompassGait``
(``drake/examples/compass_gait``): absolute leg angles from vertical, positive when the leg leans
downhill (the hip ahead of the foot for the stance leg); heel strike when
``stance + swing = 2·slope`` with the swing foot ahead (``swing < stance``); the mid-swing scuff
of the foot through the ground is ignored, as in Drake and Goswami (a compass gait's straight swing
leg cannot clear the ground where it passes the stance leg: that convention is what makes the
model walk; the kneed walker is the model that clears it).  The one unilateral constraint checked
is that the stance foot pushes: the ground's normal force ``N = n · Σ m_i (r̈_i + g ŷ) ≥ 0``.

Masses: hip point mass ``m_h``; each leg a point mass ``m`` at distance ``a`` from its foot and
``b`` from the hip (leg length ``l = a + b``).  The dynamics follow from Lagrange's equations and
the heel strike from the floating-base impact (see :mod:`gaitopt.mechanics`), which conserves the
angular momentum about the striking foot (Goswami et al. eq. 8 derive that conservation
directly; the tests check it).  A hip torque ``τ`` acts on the swing leg (+τ) and the stance leg
(−τ): Drake's ``B = [−1, 1]ᵀ``.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..mechanics import (
    bodies_function,
    contact_force,
    impact_velocity,
    kinetic_energy,
    lagrange_acceleration,
    potential_energy,
)
from ..parameters import gravity_parameter
from .blocks import fall
from .quantities import length_parameter, mass_parameter, slope_parameter, state_units

__all__ = ["CompassGait"]

_DRAKE = "Drake CompassGaitParams default (Goswami et al. 1996)"


def _unit(angle: ca.SX) -> ca.SX:
    """Unit vector along a leg leaning ``angle`` from vertical towards +x."""
    return ca.vertcat(ca.sin(angle), ca.cos(angle))


@dataclass(frozen=True)
class CompassGait(HybridModel):
    """Compass-gait walker: states ``stance``, ``swing`` (rad), ``stance_dot``, ``swing_dot``
    (rad/s); per-step input ``hip_torque`` (N·m, constant over a step)."""

    name = "compass_gait"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("stance", "swing", "stance_dot", "swing_dot")
    declared_coordinates = ("stance", "stance_dot", "swing_dot")
    declared_section_doc = "just after heel strike: swing = 2·slope − stance"
    state_units = state_units(stance="rad", swing="rad")  # for axis labels
    title = "Compass gait"
    reference = "Goswami, Thuilot & Espiau 1996; Drake CompassGait"
    inputs = ("hip_torque",)
    input_units = ("N*m",)
    mesh = (4, 4)  # 16 RK8 steps per step: discretisation error ~1e-11

    mass_hip: float = mass_parameter(10.0, "hip point mass m_h", _DRAKE)
    mass_leg: float = mass_parameter(5.0, "leg point mass m", _DRAKE)
    a: float = length_parameter(0.5, "foot to leg mass distance", _DRAKE)
    b: float = length_parameter(0.5, "hip to leg mass distance", _DRAKE)
    gravity: float = gravity_parameter()
    slope: float = slope_parameter(0.0525, _DRAKE, (0.0, 0.5))

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        x, (stance, swing, stance_dot, swing_dot) = sym.states(
            "stance", "swing", "stance_dot", "swing_dot"
        )
        mh, m, a, b, g, gamma = (sym.mass_hip, sym.mass_leg, sym.a, sym.b, sym.gravity, sym.slope)
        legs = a + b
        q = ca.vertcat(stance, swing)
        qd = ca.vertcat(stance_dot, swing_dot)
        # Positions relative to the stance foot (world frame, y up).
        hip = legs * _unit(stance)
        swing_foot = hip - legs * _unit(swing)
        masses = [(mh, hip), (m, a * _unit(stance)), (m, hip - b * _unit(swing))]

        tau = ca.vertcat(-sym.hip_torque, sym.hip_torque)  # B u with B = [−1, 1]ᵀ
        qdd = lagrange_acceleration(masses, q, qd, g, tau)
        flow = sym.function("flow", x, ca.vertcat(qd, qdd))

        # Heel strike: swing foot on the slope ⇔ stance + swing = 2γ (sum-to-product identity
        # on the foot's height relative to the line y = −x tan γ).  Drake's witness
        # max(2γ − stance − swing, swing − stance) falling through zero: the guard
        # 2γ − stance − swing decreases through 0 while the swing foot is ahead (swing < stance).
        post = impact_velocity(masses, q, qd, swing_foot)
        heel_strike = Transition(
            name="heel strike",
            guard=sym.function("guard", x, 2 * gamma - stance - swing),
            direction=-1,
            # The legs swap roles; the impact keeps the angular momentum about the new foot.
            reset=sym.function("reset", x, ca.vertcat(swing, stance, post[1], post[0])),
            target=0,
            admissible=sym.function("admissible", x, stance - swing),
            foothold="swing_foot",
            doc="stance + swing = 2·slope with swing < stance; legs swap; plastic impact",
        )
        # The hip down to the foot's level.
        falls = fall(sym, x, "fall", ca.cos(stance), "the stance leg reaches horizontal")
        energy = sym.conserved(
            "energy", x, kinetic_energy(masses, q, qd) + potential_energy(masses, g)
        )
        points = ca.Function("points", [x, sym.p], [ca.horzcat(ca.DM.zeros(2, 1), hip, swing_foot)])
        normal = ca.vertcat(ca.sin(gamma), ca.cos(gamma))  # the slope's upward normal
        push = sym.constraint(
            "stance foot pushes on the slope",
            x,
            ca.dot(normal, contact_force(masses, q, qd, qdd, g)),
            "stance foot lifts off",
            unit="N",
            source="a ground contact can only push (unilateral normal force)",
        )
        phase = Phase(
            "single support",
            ("stance", "swing", "stance_dot", "swing_dot"),
            flow,
            (heel_strike, falls),
            {"energy": energy},
            points=points,
            point_names=("stance_foot", "hip", "swing_foot"),
            bodies=bodies_function(masses, x, q, qd, sym.p),
            constraints=(push,),
        )
        s, (s_stance, s_stance_dot, s_swing_dot) = sym.states("stance", "stance_dot", "swing_dot")
        section = Section(
            ("stance", "stance_dot", "swing_dot"),
            sym.lift(s, ca.vertcat(s_stance, 2 * gamma - s_stance, s_stance_dot, s_swing_dot)),
            "just after heel strike: swing = 2·slope − stance",
        )
        return (phase,), section

    def max_step_length(self) -> float:
        """Two legs of length a + b (m): the feet are at most 2 (a + b) apart."""
        return 2 * (self.a + self.b)

    def default_start(self) -> dict[str, float]:
        """A post-impact state near the passive gait at Drake's defaults (rounded)."""
        return {"stance": -0.2, "stance_dot": 1.0, "swing_dot": 0.4}

    def input_rates(self, phase: int) -> ca.Function:
        """The hip torque acts between the legs (``B = [−1, 1]ᵀ``): its power is
        ``τ (swing_dot − stance_dot)`` (W)."""
        del phase
        x = ca.SX.sym("x", 4)
        p = ca.SX.sym("p", len(self.parameter_specs()))
        return ca.Function("input_rates", [x, p], [x[3] - x[2]], ["x", "p"], ["rates"])
