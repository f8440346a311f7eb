"""The spring-loaded inverted pendulum (SLIP): a point mass running on a massless spring leg.

Blickhan 1989; Geyer, Seyfarth & Blickhan 2005/2006; Tedrake, *Underactuated Robotics*, ch.
"Simple models of walking and running", §"The spring-loaded inverted pendulum (SLIP)", whose apex
map (k̃ = 10.7, θ_td = 30°, Ẽ = 1.61, after Geyer's thesis) fixes the defaults here.

One step, from apex to apex, is three phases:

* **descent** (flight, state ``x, z, x_dot, z_dot``; ``z`` the hip height above the reference
  level, ``x`` measured from the last apex): ballistic, ``ẍ = 0, z̈ = −g``.  The leg is held at
  the touchdown angle ``θ_td`` from vertical, foot ahead of the hip; **touchdown** when the foot
  reaches the ground, ``z − h − l0 cos θ_td = 0`` with ``z`` falling (``h`` = ``ground_height``).
* **stance** (polar coordinates about the foot, state ``r, theta, r_dot, theta_dot``; ``theta``
  from vertical, positive when the hip is ahead of the foot, so touchdown is at ``theta = −θ_td``).
  Lagrangian ``L = ½ m (ṙ² + r² θ̇²) − m g (h + r cos θ) − ½ k (l0 − r)²`` gives (Tedrake's stance
  equations)::

      r̈ = r θ̇² − g cos θ + (k/m)(l0 − r),      θ̈ = (g sin θ − 2 ṙ θ̇) / r.

  **Liftoff** when the spring regains its rest length, ``r = l0`` while extending.
* **ascent** (flight, ``x`` now measured from the foot): ballistic up to the **apex**, ``ż = 0``
  falling, where ``x`` is reset to 0 — the Poincaré section.

Energy ``E = ½ m |v|² + m g z (+ ½ k (l0 − r)² in stance)`` is conserved, so at the apex the
forward speed follows from the height, ``ẋ = sqrt(2 (E/m − g z))``: the section has the single
coordinate ``z`` and the apex map ``z[n+1] = P(z[n]; θ_td)`` has one (nontrivial) multiplier.
Dimensionless numbers (Geyer): ``k̃ = k l0 / (m g)`` and ``Ẽ = E / (m g l0)``.

The map's domain, stated rather than crashed on (each edge is a terminal transition that ends a
simulation with a named fall, so :func:`gaitopt.returnmap.return_map` is NaN there):

* below the touchdown height, ``z ≤ h + l0 cos θ_td``, the leg cannot be placed: the hip falls
  to the ground ("apex below touchdown height");
* with too little forward energy (``z`` near ``E/(m g)``) the stance leg stops rotating and the
  runner falls back ("falls back": ``θ̇`` reaches 0 in stance; or it lifts off moving backwards);
  above ``E/(m g)`` no apex exists at this energy: the section's lift then has zero forward
  speed (more energy than ``energy``), and the simulation reports the fall back.

The touchdown angle is both a parameter (``touchdown_angle``, the nominal value) and the per-step
input (``u = θ_td``, chosen at each apex by a step-to-step controller): :meth:`Slip.nominal_input`
returns the parameter.  :class:`SlipSwingLeg` replaces the fixed angle by a swing-leg law
``θ(t)`` of the time since apex (blind running on rough terrain; :mod:`gaitopt.terrain`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import casadi as ca
import numpy as np

from ..errors import ParameterError
from ..hybrid import HybridModel, Phase, Section, Symbols
from ..parameters import gravity_parameter, parameter
from .blocks import apex, ballistic_flow, fall, leg_touchdown
from .polar import UNITS, leg_in_flight, spring_stance
from .quantities import energy_parameter, length_parameter, mass_parameter, stiffness_parameter

__all__ = ["Slip", "SlipSwingLeg", "SWING_LAW_DEGREE"]

_TEDRAKE = "Tedrake, Underactuated Robotics, SLIP apex map (after Geyer 2005)"
_M, _L0 = 80.0, 1.0
#: Degree of the Chebyshev swing-leg law of :class:`SlipSwingLeg`.
SWING_LAW_DEGREE = 8


def _build(sym: Symbols, angle_law) -> tuple[tuple[Phase, ...], Section]:
    """The three phases and the apex section; ``angle_law(z_dot)`` is the leg angle in descent
    (a function of the time since apex ``t = −ż/g``)."""
    m, l0, k, g, E, h = (
        sym.mass,
        sym.rest_length,
        sym.stiffness,
        sym.gravity,
        sym.energy,
        sym.ground_height,
    )
    # Drawing functions take (x, p) only: the flight leg is drawn at the parameter angle.
    drawn_angle = sym.touchdown_angle

    # -- flight: descent from the apex, leg at the touchdown angle -------------------------------
    xf, (x, z, x_dot, z_dot) = sym.states("x", "z", "x_dot", "z_dot")
    ballistic = ballistic_flow(sym, xf, g, vertical=1)  # ẍ = 0, z̈ = −g
    # z − h − l0 cos θ_td = 0; the hip in polar coordinates about the foot x + l0 sin θ_td.
    touchdown = leg_touchdown(
        sym,
        xf,
        height=z - h,
        velocity=(x_dot, z_dot),
        length=l0,
        angle=angle_law(z_dot),
        impact=False,  # a massless leg: the hip's velocity is only re-expressed
        doc="foot reaches the ground: z − h − l0·cos θ_td = 0, falling; the hip in polar "
        "coordinates about the foot",
    )
    no_touchdown = fall(
        sym,
        xf,
        "apex below touchdown height (hip reaches the ground)",
        z - h,
        "fires only if touchdown never armed: the apex was below h + l0·cos θ_td",
    )
    flight_energy = sym.conserved("energy", xf, 0.5 * m * (x_dot**2 + z_dot**2) + m * g * z)
    descent = Phase(
        "descent",
        ("x", "z", "x_dot", "z_dot"),
        ballistic,
        (touchdown, no_touchdown),
        {"energy": flight_energy},
        points=leg_in_flight(sym, xf, l0, drawn_angle),
        point_names=("hip", "foot", "origin"),
    )

    # -- stance: polar coordinates about the foot (Tedrake's stance equations) -----------------
    stance = spring_stance(sym, stiffness=k, rest_length=l0, target=2, ground=h)

    # -- flight: ascent to the apex ------------------------------------------------------------
    top = apex(
        sym,
        xf,
        z_dot,  # ż = 0, falling
        ca.vertcat(0, z, x_dot, z_dot),  # x from the apex
        foothold="below_hip",
        doc="top of the flight, ż = 0 falling; x is measured from here on",
    )
    no_apex = fall(
        sym,
        xf,
        "falls (no apex after liftoff)",
        z - h,
        "lifted off falling: the hip reaches the ground before any apex",
    )
    ascent = Phase(
        "ascent",
        ("x", "z", "x_dot", "z_dot"),
        ballistic,
        (top, no_apex),
        {"energy": flight_energy},
        points=leg_in_flight(sym, xf, l0, drawn_angle, ground=h),
        point_names=("hip", "foot", "below_hip"),
    )

    # -- the apex section: z free, x = 0, ż = 0, ẋ from the energy -----------------------------
    s = ca.SX.sym("s", 1)
    speed = ca.sqrt(ca.fmax(2 * (E / m - g * s[0]), 0))
    section = Section(
        ("z",),
        sym.lift(s, ca.vertcat(0, s[0], speed, 0)),
        "apex: z_dot = 0, x = 0, x_dot = sqrt(2 (energy/mass − gravity·z))",
    )
    return (descent, stance, ascent), section


@dataclass(frozen=True)
class Slip(HybridModel):
    """SLIP runner: apex state ``x, z`` (m), ``x_dot, z_dot`` (m/s); stance ``r`` (m), ``theta``
    (rad), ``r_dot``, ``theta_dot``; per-step input ``touchdown_angle`` (rad from vertical)."""

    name = "slip"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("x", "z", "x_dot", "z_dot")
    declared_coordinates = ("z",)
    declared_section_doc = "apex: z_dot = 0, x = 0, x_dot = sqrt(2 (energy/mass − gravity·z))"
    drawing = (("hip", "foot"),)  # leg and body; other points are helpers
    state_units = UNITS  # for axis labels
    title = "Spring-loaded inverted pendulum (SLIP)"
    reference = "Blickhan 1989; Geyer et al. 2005; Tedrake, Underactuated Robotics"
    inputs = ("touchdown_angle",)
    input_units = ("rad",)
    mesh = (4, 4)
    #: A flight from an apex lasts at most sqrt(2 E/(m g²)) ≈ 0.6 s at the defaults.
    max_phase_time: ClassVar[float] = 5.0
    #: Range of the per-step input: the foot ahead of the hip, the leg above the ground
    #: (step-to-step controllers keep to it).
    input_bounds: ClassVar[dict[str, tuple[float, float]]] = {"touchdown_angle": (0.0, math.pi / 2)}

    mass: float = mass_parameter(_M, "body mass m", _TEDRAKE)
    rest_length: float = length_parameter(_L0, "leg rest length l0", _TEDRAKE)
    stiffness: float = stiffness_parameter(
        8397.36, "leg stiffness k (k̃ = k l0/(m g) = 10.7 at the defaults)", _TEDRAKE + ": k̃ = 10.7"
    )
    touchdown_angle: float = parameter(
        math.pi / 6, unit="rad", low=0.0, high=math.pi / 2, high_open=True,
        doc="nominal touchdown angle θ_td from vertical (the per-step input's default)",
        source=_TEDRAKE + ": 30°",
    )  # fmt: skip
    gravity: float = gravity_parameter()
    energy: float = energy_parameter(
        1263.528,
        "total energy E = ½ m v² + m g z (Ẽ = E/(m g l0) = 1.61 at the defaults)",
        _TEDRAKE + ": Ẽ = 1.61",
    )
    ground_height: float = parameter(
        0.0, unit="m", low=-10.0, high=10.0,
        doc="height h of the ground under the next touchdown (rough terrain: changes per step)",
        source="level ground",
    )  # fmt: skip

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        return _build(sym, lambda _z_dot: sym.input("touchdown_angle"))

    def check(self) -> None:
        top = self.energy / (self.mass * self.gravity)
        if top <= self.ground_height + self.rest_length * math.cos(self.touchdown_angle):
            raise ParameterError(
                f"slip: `energy` = {self.energy:g} J puts the highest apex, E/(m g) = {top:.4g} m, "
                f"below the touchdown height h + l0·cos θ_td = "
                f"{self.ground_height + self.rest_length * math.cos(self.touchdown_angle):.4g} m: "
                f"the runner cannot run; raise `energy` (Ẽ = E/(m g l0) > cos θ_td) or lower "
                f"`touchdown_angle`'s cosine"
            )

    # -- dimensionless numbers and the map's domain ----------------------------------------------
    @property
    def relative_stiffness(self) -> float:
        """``k̃ = k l0 / (m g)`` (Geyer's dimensionless stiffness)."""
        return self.stiffness * self.rest_length / (self.mass * self.gravity)

    @property
    def relative_energy(self) -> float:
        """``Ẽ = E / (m g l0)`` (Geyer's dimensionless energy)."""
        return self.energy / (self.mass * self.gravity * self.rest_length)

    def touchdown_height(self, angle: float | None = None) -> float:
        """``h + l0 cos θ_td`` (m): the lowest apex from which the leg can be placed."""
        angle = self.touchdown_angle if angle is None else angle
        return self.ground_height + self.rest_length * math.cos(angle)

    def highest_apex(self) -> float:
        """``E/(m g)`` (m): the apex height with no forward speed left."""
        return self.energy / (self.mass * self.gravity)

    def apex_domain(self) -> tuple[float, float]:
        """``(touchdown height, E/(m g))``: the apex heights where the map may be defined (it is
        NaN outside; near the top the runner falls back)."""
        return self.touchdown_height(), self.highest_apex()

    def map_domain(self) -> tuple[float, float]:
        """The apex map's domain (see :meth:`apex_domain`)."""
        return self.apex_domain()

    def section_limits(self) -> dict[str, tuple[float, float, str]]:
        """An apex cannot be higher than the energy height ``E/(m g)``, where no forward speed
        is left (``ẋ = sqrt(2 (E/m − g z))``)."""
        top = self.highest_apex()
        why = (
            f"the energy height E/(m g) = {top:.6g} m (energy {self.energy:g} J), where no "
            f"forward speed is left; raise `energy` for a higher apex"
        )
        return {"z": (-math.inf, top, why)}

    def apex_speed(self, z: float) -> float:
        """Forward speed ``ẋ = sqrt(2 (E/m − g z))`` (m/s) at an apex of height ``z``."""
        return math.sqrt(max(2 * (self.energy / self.mass - self.gravity * z), 0.0))

    def existence_note(self) -> str | None:
        """The map's domain and Geyer's dimensionless numbers (added to a failed search)."""
        lo, hi = self.apex_domain()
        return (
            f"SLIP with k̃ = {self.relative_stiffness:.4g}, Ẽ = {self.relative_energy:.4g}: the "
            f"apex map is defined only for apex heights between the touchdown height "
            f"{lo:.4g} m and E/(m g) = {hi:.4g} m, and near the top the runner falls back "
            f"(Tedrake, Underactuated Robotics, SLIP apex map)"
        )

    def nominal_input(self) -> np.ndarray:
        """The touchdown angle parameter (rad)."""
        return np.array([self.touchdown_angle])

    def default_start(self) -> dict[str, float]:
        """Near the stable fixed point of Tedrake's apex map (z ≈ 0.87 m at the defaults)."""
        lo, hi = self.apex_domain()
        return {"z": 0.87} if lo < 0.87 < hi else {"z": 0.5 * (lo + hi)}


@dataclass(frozen=True)
class SlipSwingLeg(Slip):
    """SLIP whose leg angle in descent follows a law of the time since apex ``t = −ż/g``:
    ``θ(t) = Σ_j c_j T_j(ξ)``, ``ξ = (t − t_c)/t_w`` clipped to [−1, 1] (Chebyshev polynomials
    ``T_j``, degree :data:`SWING_LAW_DEGREE`), the per-step inputs ``t_center, t_halfwidth,
    c0 … c8``.

    Touchdown happens wherever the foot meets the ground, at whatever (unknown) height: the leg
    angle then is ``θ(t_touchdown)``.  Ernst, Geyer & Blickhan 2009 and Tedrake's "blind running"
    choose the law so that this angle is the deadbeat one for every ground height
    (:func:`gaitopt.terrain.blind_swing_law`).  With only ``c0`` nonzero it is :class:`Slip`.
    """

    name = "slip_swing_leg"
    title = "SLIP with a swing-leg law (blind running)"
    inputs = ("t_center", "t_halfwidth") + tuple(f"c{j}" for j in range(SWING_LAW_DEGREE + 1))
    input_units = ("s", "s") + ("rad",) * (SWING_LAW_DEGREE + 1)
    input_bounds: ClassVar[dict[str, tuple[float, float]]] = {}

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        def law(z_dot):
            t = -z_dot / sym.gravity  # time since apex (ballistic descent from ż = 0)
            # Held at its end values outside the fitted window [t_c − t_w, t_c + t_w].
            xi = ca.fmax(-1, ca.fmin(1, (t - sym.u[0]) / sym.u[1]))
            # Chebyshev recurrence T_{j+1} = 2 ξ T_j − T_{j−1}.
            t_prev, t_cur = ca.SX(1), xi
            angle = sym.u[2] + sym.u[3] * xi
            for j in range(2, SWING_LAW_DEGREE + 1):
                t_prev, t_cur = t_cur, 2 * xi * t_cur - t_prev
                angle = angle + sym.u[2 + j] * t_cur
            return angle

        return _build(sym, law)

    def nominal_input(self) -> np.ndarray:
        """The constant law ``θ(t) = touchdown_angle``."""
        u = np.zeros(len(self.inputs))
        u[0], u[1], u[2] = 0.2, 0.1, self.touchdown_angle
        return u
