"""A minimal biped that can walk and run (Srinivasan & Ruina 2006).

Srinivasan & Ruina, "Computer optimization of a minimal biped model discovers walking and
running", Nature 439:72–75 (2006): a point-mass body ``M`` on two massless telescoping legs.  The
only input that acts on the body is the **leg force** ``F`` along the stance leg, from the foot
to the hip (a leg can only push, ``F ≥ 0``); a hip torque only places a massless swing leg, so
the swing foot goes wherever the step needs it.  The cost is the positive work of the legs per
unit weight and distance, ``∫ max(0, F ṙ) dt / (M g d)`` (cost of transport).  They found the
energy-optimal gait to be inverted-pendulum walking at low speed, impulsive running at high
speed, and a "pendular run" in between.

Two phase sequences, registered as two models that share this module's phases:

* ``minimal_biped_walk`` — one phase, **single stance**, closed by an instantaneous double-support
  transfer (the heel strike).
* ``minimal_biped_run`` — **stance** then **flight**.

**Stance** (both models; polar coordinates ``r, theta, r_dot, theta_dot`` of the hip about the
stance foot, ``r`` the leg length (m), ``theta`` from vertical, positive with the hip ahead of the
foot; motion towards +x)::

    r̈ = r θ̇² − g cos θ + F/M,        θ̈ = (g sin θ − 2 ṙ θ̇) / r

(a point mass under gravity and a central force ``F`` from the foot).  The leg's power is
``F ṙ`` (:meth:`input_rates`).  Unilateral conditions (declared, checked on dense samples and
in the simulation): the leg pushes, ``F ≥ 0``; the leg is no longer than ``leg_length``
(``l_max − r ≥ 0``); the hip is above the ground (``r cos θ ≥ 0``).  ``F ≥ 0`` is also the
input's declared range; the optimiser takes ``F ≤ F_max`` as a bound (below).

**Walking transfer** (instantaneous double support).  The step ends where the hip passes the
middle of the step, ``2 r sin θ = d`` (``d`` the parameter ``step_length``), and the new foot
lands at ``d``: by the symmetry of a one-step periodic gait the new leg is the mirror image of the
old (``r⁺ = r⁻``, ``θ⁺ = −θ⁻``).  The heel strike is a plastic impulse along the new leg
(Srinivasan & Ruina's heel-strike impulse), removing the hip's velocity component along it::

    ṙ⁺ = 0,     θ̇⁺ = (ṙ⁻ sin 2θ⁻ + r θ̇⁻ cos 2θ⁻) / r

(for ``ṙ⁻ = 0`` Garcia et al. 1998's eq. (6)).  Its impulse ``M (r θ̇⁻ sin 2θ⁻ − ṙ⁻ cos 2θ⁻)``
must be positive (the new leg pushes): the transition's admissibility.  It only dissipates (work
``−½ M (v⁻·ê)²``), so it adds nothing to the positive work.  **Regularisation**: Srinivasan &
Ruina's push-off is an impulse along the trailing leg just before heel strike; here the push-off
is the stance force profile itself, bounded by ``F ≤ F_max`` (the optimiser's bound on
``leg_force``), so an impulsive push-off appears as a short push at ``F_max``.  (An impulsive
push-off input's positive work depends on the sign of the trailing leg's rate ``ṙ⁻``, not a
smooth function of the state, so it is not offered.)

**Running** (stance, then flight).  Lift-off where the leg regains its full length, ``r = l_max``
extending; touchdown where the hip comes within ``l_max`` of the next foothold at ``x = d``
(the flight's ``x`` is measured from the last stance foot): ``(x − d)² + z² = l_max²``, falling
in distance.  Touchdown and lift-off at full length lose no generality for a massless leg that
may carry ``F = 0`` (a shorter contact is the same motion with an unloaded stretch of stance).
Neither changes the velocity (a massless leg, ``impact=False``).  The flight is ballistic,
``ẍ = 0, z̈ = −g``, with the hip above the ground (``z ≥ 0``).

**Poincaré sections**: walking — just after heel strike, ``ṙ = 0`` and ``r sin θ = −d/2``, free
coordinates ``r, theta_dot``; running — just after touchdown, ``r = l_max``, free coordinates
``theta, r_dot, theta_dot``.

**Units**: SI; the defaults ``M = 1 kg``, ``l_max = 1 m`` make Srinivasan & Ruina's dimensionless
units (``M = g = l_max = 1``) a matter of dividing speeds by ``sqrt(g l_max)`` and forces by
``M g``.  There is no passive gait (``passive_gait = False``): the heel strike dissipates and only
the leg force restores energy.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import casadi as ca
import numpy as np

from ..errors import ParameterError
from ..hybrid import Constraint, HybridModel, Phase, Section, Symbols, Transition
from ..parameters import gravity_parameter
from .polar import STANCE, UNITS, flight_to_foothold, foot_stance, leg_power, liftoff
from .quantities import length_parameter, mass_parameter

__all__ = ["MinimalBipedWalk", "MinimalBipedRun"]

_SR = "Srinivasan & Ruina 2006 (Nature 439:72), M = l_max = 1 in their units"


def _stance(sym: Symbols, closing: Transition, *, touchdown_at_full_length: bool) -> Phase:
    """The stance phase about the stance foot, ending with ``closing``: the leg force ``F`` alone
    pushes (no spring), and the leg is no longer than ``l_max``."""
    force = sym.input("leg_force")

    def within_length(xs: ca.SX, r: ca.SX) -> Constraint:
        return sym.constraint(
            "leg within its length",
            xs,
            sym.leg_length - r,
            "leg longer than leg_length",
            at_start=touchdown_at_full_length,
            at_end=touchdown_at_full_length,
            unit="m",
            source="telescoping leg of length at most l_max (Srinivasan & Ruina 2006)",
        )

    return foot_stance(
        sym,
        closing,
        leg_force=lambda r: force,
        push_source="a leg on the ground can only push (Srinivasan & Ruina 2006: F ≥ 0)",
        falls_back=(
            "falls back (the hip stops vaulting over the foot)",
            "θ̇ falls through 0 in stance: too little forward speed",
        ),
        conditions=(within_length,),
    )


def _check_step(model: HybridModel) -> None:
    if not model.step_length < 2 * model.leg_length:
        raise ParameterError(
            f"{model.name}: `step_length` {model.step_length:g} m must be shorter than twice "
            f"`leg_length` ({2 * model.leg_length:g} m): both feet must reach the hip; e.g. "
            f"step_length={model.leg_length:g}"
        )


@dataclass(frozen=True)
class _MinimalBiped(HybridModel):
    """Parameters and conventions shared by the walking and running sequences."""

    reference = "Srinivasan & Ruina 2006, Nature 439:72-75"
    passive_gait = False
    state_units = UNITS
    inputs = ("leg_force",)
    input_units = ("N",)
    #: The leg can only push (Srinivasan & Ruina 2006: F ≥ 0).
    input_bounds: ClassVar[dict[str, tuple[float, float]]] = {"leg_force": (0.0, float("inf"))}
    drawing = (("foot", "hip"),)
    max_phase_time: ClassVar[float] = 5.0

    mass: float = mass_parameter(1.0, "body mass M", _SR)
    leg_length: float = length_parameter(1.0, "longest leg l_max", _SR)
    step_length: float = length_parameter(
        0.6,
        "step length d, foot to foot (free it to optimise it: free=('step_length',))",
        "a human-like 0.6 l_max (Srinivasan & Ruina 2006 map the optimum over d)",
    )
    gravity: float = gravity_parameter()

    def check(self) -> None:
        _check_step(self)

    def nominal_input(self) -> np.ndarray:
        """A leg force ``0.9 M g`` (N): nearly the weight, for the optimiser's first guess (the
        simulation from :meth:`default_start` with it vaults over the foot)."""
        return np.array([0.9 * self.mass * self.gravity])

    def existence_note(self) -> str | None:
        return (
            f"{self.name} has no passive gait: its gaits come from gaitopt.optimize_gait with a "
            f"bound on leg_force (e.g. bounds={{'leg_force': (0, 30)}})"
        )


@dataclass(frozen=True)
class MinimalBipedWalk(_MinimalBiped):
    """Minimal biped, walking: stance state ``r`` (m), ``theta`` (rad), ``r_dot`` (m/s),
    ``theta_dot`` (rad/s) about the stance foot; input ``leg_force`` (N)."""

    name = "minimal_biped_walk"
    title = "Minimal biped, walking (point mass, telescoping legs)"
    declared_states = STANCE
    declared_coordinates = ("r", "theta_dot")
    declared_section_doc = "just after heel strike: r_dot = 0, r·sin(theta) = −step_length/2"

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        xs, (r, th, r_dot, th_dot) = sym.states(*STANCE)
        s2, c2 = ca.sin(2 * th), ca.cos(2 * th)
        heel = Transition(
            name="heel strike",
            guard=sym.function("guard", xs, 2 * r * ca.sin(th) - sym.step_length),
            direction=+1,
            reset=sym.function(
                "reset", xs, ca.vertcat(r, -th, 0, (r_dot * s2 + r * th_dot * c2) / r)
            ),
            target=0,
            # the heel-strike impulse along the new leg pushes: M (r θ̇ sin 2θ − ṙ cos 2θ) > 0
            admissible=sym.function("admissible", xs, r * th_dot * s2 - r_dot * c2),
            foothold="next_foot",
            doc="the hip passes mid-step, 2 r sin θ = d; the new leg (the old one mirrored) "
            "lands with a plastic impulse along it: ṙ⁺ = 0",
        )
        stance = _stance(sym, heel, touchdown_at_full_length=False)
        s, (sr, sth_dot) = sym.states("r", "theta_dot")
        half = sym.step_length / (2 * sr)
        lift = ca.vertcat(sr, -ca.asin(half), 0, sth_dot)
        return (stance,), Section(("r", "theta_dot"), sym.lift(s, lift), cls.declared_section_doc)

    def default_start(self) -> dict[str, float]:
        """A leg nearly at full length vaulting forwards at about 1 rad/s (a slow walk)."""
        return {"r": 0.98 * self.leg_length, "theta_dot": 1.2 * np.sqrt(self.gravity / 9.81)}

    def input_rates(self, phase: int) -> ca.Function:
        """The leg force does the power ``F ṙ`` (W) in stance."""
        del phase
        return leg_power(len(self.parameter_specs()), stance=True)


@dataclass(frozen=True)
class MinimalBipedRun(_MinimalBiped):
    """Minimal biped, running: stance state ``r`` (m), ``theta`` (rad), ``r_dot`` (m/s),
    ``theta_dot`` (rad/s) about the stance foot; flight ``x, z`` (m, ``x`` from the last foot),
    ``x_dot, z_dot`` (m/s); input ``leg_force`` (N)."""

    name = "minimal_biped_run"
    title = "Minimal biped, running (point mass, telescoping legs)"
    declared_states = STANCE
    declared_coordinates = ("theta", "r_dot", "theta_dot")
    declared_section_doc = "just after touchdown: r = leg_length"

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        lmax = sym.leg_length
        xs = sym.states(*STANCE)[0]
        lift = liftoff(
            sym,
            xs,
            lmax,
            name="lift-off",
            target=1,
            doc="the leg regains its full length, r = l_max, extending; Cartesian flight state "
            "with x from the stance foot",
        )
        stance = _stance(sym, lift, touchdown_at_full_length=True)
        flight = flight_to_foothold(
            sym,
            lmax,
            doc="the hip comes within l_max of the next foothold (x = d): (x − d)² + z² = "
            "l_max², approaching; polar state about the new foot",
        )
        s, (sth, sr_dot, sth_dot) = sym.states("theta", "r_dot", "theta_dot")
        lift = ca.vertcat(lmax, sth, sr_dot, sth_dot)
        return (stance, flight), Section(
            ("theta", "r_dot", "theta_dot"), sym.lift(s, lift), cls.declared_section_doc
        )

    def default_start(self) -> dict[str, float]:
        """Touchdown with the foot ahead, falling onto the leg at a run (about 3 m/s)."""
        v = 3.0 * np.sqrt(self.gravity * self.leg_length / 9.81)
        th = -np.arcsin(min(0.3, 0.45 * self.step_length / self.leg_length))
        vz = -0.5
        # r_dot, theta_dot of the velocity (v, vz) at angle th
        r_dot = v * np.sin(th) + vz * np.cos(th)
        th_dot = (v * np.cos(th) - vz * np.sin(th)) / self.leg_length
        return {"theta": float(th), "r_dot": float(r_dot), "theta_dot": float(th_dot)}

    def nominal_input(self) -> np.ndarray:
        """A leg force ``2 M g`` (N) for the optimiser's first guess: the stance bounces the
        hip back to full leg length."""
        return np.array([2.0 * self.mass * self.gravity])

    def input_rates(self, phase: int) -> ca.Function:
        """The leg force does the power ``F ṙ`` (W) in stance and none in flight."""
        return leg_power(len(self.parameter_specs()), stance=phase == 0)
