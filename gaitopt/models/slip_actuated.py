"""The SLIP with a leg force actuator in parallel with its spring, for optimal running.

The spring-mass runner of :mod:`gaitopt.models.slip` (Blickhan 1989; Tedrake, *Underactuated
Robotics*, SLIP apex map: ``k̃ = k l0/(m g) = 10.7``, ``Ẽ = E/(m g l0) = 1.61``, ``θ_td = 30°``)
with an actuator ``leg_force`` ``F`` (N, a profile input) acting along the leg in parallel with
the spring, in the phase sequence of :mod:`gaitopt.models.minimal_biped`'s run (Srinivasan &
Ruina 2006), so that the optimiser chooses the touchdown angle.

**Stance** (polar coordinates ``r, theta, r_dot, theta_dot`` of the hip about the stance foot;
``theta`` from vertical, positive with the hip ahead of the foot; Tedrake's stance equations with
the actuator added to the spring force)::

    r̈ = r θ̇² − g cos θ + (k (l0 − r) + F)/m,      θ̈ = (g sin θ − 2 ṙ θ̇) / r

The actuator's power is ``F ṙ`` (:meth:`input_rates`).  Declared unilateral conditions: the leg
pushes, ``k (l0 − r) + F ≥ 0`` (a massless leg on the ground; ``F`` may be negative, absorbing
energy, as long as the leg still pushes); the hip above the ground.  **Lift-off** when the leg
regains its rest length ``r = l0``, extending (as in the SLIP).

**Flight** (``x, z, x_dot, z_dot``, ``x`` from the last stance foot): ballistic.  **Touchdown**
where the hip comes within ``l0`` of the next foothold ``x = d`` (the parameter
``step_length``): ``(x − d)² + z² = l0²``, approaching.  The leg touches down at its rest length
with no spring force, so touchdown and lift-off do not change the velocity (``impact=False``).

**Poincaré section**: just after touchdown, ``r = l0``, free coordinates ``theta`` (minus the
touchdown angle: ``θ_td = −theta``) and ``r_dot``; ``theta_dot`` follows from the total energy
``E`` (the parameter ``energy``), ``½ m (ṙ² + l0² θ̇²) + m g l0 cos θ = E``.  So the touchdown
angle is a free coordinate of the section: the optimiser chooses it.  Energy is not conserved in
stance when ``F ≠ 0``, but over a periodic orbit it returns to ``E``: fixing ``E`` and the
speed states "run at this speed and energy".

**Closing the orbit**: the optimiser closes an orbit in the section coordinates ``theta,
r_dot`` only, and the lift sets ``theta_dot`` from ``E``; an actuated stride whose net work is
not zero would come back with another energy, so another ``theta_dot``, and not be periodic.
The flight (whose energy is constant) therefore declares its energy equal to ``E``, as two
one-sided conditions within ``ENERGY_MARGIN`` (1e-8 relative: rounding of a simulated energy
is ~1e-12, and 1e-8 E changes ``theta_dot`` by ~5e-8 rad/s, below the optimiser's return
tolerance 1e-6): with ``theta``, ``r_dot`` and the energy periodic, so is ``theta_dot``.

**Exact reduction**: with ``F ≡ 0`` this is the SLIP, the section one touchdown of its orbit and
``d`` the SLIP's stride (apex to apex distance); the default ``step_length`` is the stride of the
SLIP's gait at its defaults (1.35576 m; ``tests/test_slip_actuated.py`` checks the gait to
1e-10 against :mod:`gaitopt.models.slip`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import casadi as ca
import numpy as np

from ..errors import ParameterError
from ..hybrid import Constraint, HybridModel, Phase, Section, Symbols
from ..parameters import gravity_parameter
from .polar import STANCE, UNITS, flight_to_foothold, foot_stance, leg_power, liftoff
from .quantities import energy_parameter, length_parameter, mass_parameter, stiffness_parameter

__all__ = ["SlipActuated"]

_TEDRAKE = "Tedrake, Underactuated Robotics, SLIP apex map (after Geyer 2005), as model slip"
_WORK_ENERGY = "periodic orbit at the section's energy (the work–energy theorem)"
#: The stride (m) of the passive SLIP gait at the slip model's defaults: apex-to-apex distance
#: of ``gaitopt.find_limit_cycle(gaitopt.model("slip"), {"z": 0.87})`` (1.35576453 m).
SLIP_STRIDE = 1.3557645310670494
#: Relative margin of the flight's energy about ``energy`` (module docstring, "Closing the
#: orbit").
ENERGY_MARGIN = 1e-8


@dataclass(frozen=True)
class SlipActuated(HybridModel):
    """SLIP with a leg actuator: stance ``r`` (m), ``theta`` (rad), ``r_dot`` (m/s),
    ``theta_dot`` (rad/s) about the stance foot; flight ``x, z`` (m, ``x`` from the last foot),
    ``x_dot, z_dot`` (m/s); input ``leg_force`` (N) in parallel with the spring."""

    name = "slip_actuated"
    title = "SLIP with a leg force actuator (touchdown angle chosen by the optimiser)"
    reference = "Blickhan 1989; Tedrake, Underactuated Robotics; Srinivasan & Ruina 2006"
    passive_gait = True
    declared_states = STANCE
    declared_coordinates = ("theta", "r_dot")
    declared_section_doc = (
        "just after touchdown: r = rest_length, theta_dot from the energy "
        "(½ m (r_dot² + l0² theta_dot²) + m g l0 cos(theta) = energy)"
    )
    state_units = UNITS
    inputs = ("leg_force",)
    input_units = ("N",)
    input_bounds: ClassVar[dict[str, tuple[float, float]]] = {
        "leg_force": (-float("inf"), float("inf"))
    }
    drawing = (("foot", "hip"),)
    max_phase_time: ClassVar[float] = 5.0

    mass: float = mass_parameter(80.0, "body mass m", _TEDRAKE)
    rest_length: float = length_parameter(1.0, "leg rest length l0", _TEDRAKE)
    stiffness: float = stiffness_parameter(
        8397.36, "leg stiffness k (k̃ = k l0/(m g) = 10.7 at the defaults)", _TEDRAKE + ": k̃ = 10.7"
    )
    energy: float = energy_parameter(
        1263.528,
        "total energy E at touchdown (Ẽ = E/(m g l0) = 1.61 at the defaults)",
        _TEDRAKE + ": Ẽ = 1.61",
    )
    step_length: float = length_parameter(
        SLIP_STRIDE,
        "stride d, foot to foot (free it to optimise it: free=('step_length',))",
        "the passive SLIP gait's stride at the slip model's defaults (θ_td = 30°)",
        high=20.0,
    )
    gravity: float = gravity_parameter()

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        l0, g, m, E, k = sym.rest_length, sym.gravity, sym.mass, sym.energy, sym.stiffness
        force = sym.input("leg_force")
        lift = liftoff(
            sym,
            sym.states(*STANCE)[0],
            l0,
            name="lift-off",
            target=1,
            doc="the leg regains its rest length, r = l0, extending; Cartesian flight state "
            "with x from the stance foot",
        )
        stance = foot_stance(
            sym,
            lift,
            # spring k (l0 − r) and actuator F in parallel (Tedrake's stance equation + F/m)
            leg_force=lambda r: k * (l0 - r) + force,
            push_source="a massless leg on the ground can only push (Blickhan 1989; spring + "
            "actuator)",
            falls_back=(
                "falls back (stance leg stops rotating)",
                "θ̇ falls through 0 in stance: too little forward energy to vault over the foot",
            ),
            spring_energy=lambda r: 0.5 * k * (l0 - r) ** 2,
        )

        # The flight's (constant) energy is the parameter E, so the touchdown that closes the
        # stride has the section's energy: with theta and r_dot periodic, theta_dot is too
        # (module docstring, "Closing the orbit").  Two one-sided conditions.
        def at_least(xf: ca.SX, energy: ca.SX) -> Constraint:
            return sym.constraint(
                "flight energy at least energy",
                xf,
                energy - E * (1 - ENERGY_MARGIN),
                "the stride lost energy (not periodic at this energy)",
                unit="J",
                source=_WORK_ENERGY,
            )

        def at_most(xf: ca.SX, energy: ca.SX) -> Constraint:
            return sym.constraint(
                "flight energy at most energy",
                xf,
                E * (1 + ENERGY_MARGIN) - energy,
                "the stride gained energy (not periodic at this energy)",
                unit="J",
                source=_WORK_ENERGY,
            )

        flight = flight_to_foothold(
            sym,
            l0,
            doc="the hip comes within l0 of the next foothold (x = d): (x − d)² + z² = l0², "
            "approaching; polar state about the new foot",
            conditions=(at_least, at_most),
        )
        s, (sth, sr_dot) = sym.states("theta", "r_dot")
        # E = ½ m (ṙ² + l0² θ̇²) + m g l0 cos θ at touchdown (no spring energy at r = l0)
        th_dot = ca.sqrt(ca.fmax(2 * (E / m - g * l0 * ca.cos(sth)) - sr_dot**2, 0)) / l0
        lift = ca.vertcat(l0, sth, sr_dot, th_dot)
        return (stance, flight), Section(
            ("theta", "r_dot"), sym.lift(s, lift), cls.declared_section_doc
        )

    def check(self) -> None:
        top = self.energy / (self.mass * self.gravity)
        if top <= self.rest_length * 0.5:
            raise ParameterError(
                f"slip_actuated: `energy` = {self.energy:g} J puts the energy height E/(m g) = "
                f"{top:.4g} m below half the rest length ({0.5 * self.rest_length:g} m): no "
                f"touchdown within 60° of vertical can run; raise `energy` (e.g. Ẽ = 1.61)"
            )
        if not self.step_length < 20 * self.rest_length:
            raise ParameterError(
                f"slip_actuated: `step_length` {self.step_length:g} m is more than 20 rest "
                f"lengths; e.g. step_length={SLIP_STRIDE}"
            )

    def default_start(self) -> dict[str, float]:
        """Touchdown at 30° with the SLIP gait's radial speed at the defaults (−2.295 m/s)."""
        return {"theta": -np.pi / 6, "r_dot": -2.2948363793524638}

    def nominal_input(self) -> np.ndarray:
        """No actuator force: the passive SLIP (N)."""
        return np.array([0.0])

    def input_rates(self, phase: int) -> ca.Function:
        """The actuator does the power ``F ṙ`` (W) in stance and none in flight."""
        return leg_power(len(self.parameter_specs()), stance=phase == 0)
