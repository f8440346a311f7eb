"""A ball bouncing on a sinusoidally vibrating table: the open-loop juggler.

Holmes 1982, "The dynamics of repeated impacts with a sinusoidally vibrating table" (J. Sound
Vib. 84); Guckenheimer & Holmes, *Nonlinear Oscillations, Dynamical Systems, and Bifurcations of
Vector Fields*, §2.4.

The table moves as ``s(t) = A sin(ω t)``, ``ω = 2π f``; its peak acceleration relative to gravity,
``Γ = A ω² / g`` (parameter ``acceleration``), is the bifurcation parameter.  The ball flies
ballistically, ``ÿ = −g``, until it meets the table; the impact keeps the table's motion and
reverses the relative velocity with restitution ``e``: ``ẏ⁺ − ṡ = −e (ẏ⁻ − ṡ)``.

State (one phase, *flight*): ``phase`` (rad) — the table phase ``ω t``, so that the flow is
autonomous, ``phase̊ = ω`` — ``y`` (m, ball height) and ``y_dot`` (m/s).  **Impact** when the guard
``y − A sin(phase)`` falls through zero (the ball meets the table from above; just after an
impact the guard is 0 and rising, which the engine does not count as a crossing).  The reset
keeps ``y⁺ = A sin(phase⁺)``, sets ``y_dot⁺ = (1 + e) A ω cos(phase) − e y_dot`` and wraps the
phase into ``[−π, π)`` (``phase⁺ = phase − 2π⌊(phase + π)/2π⌋``; its derivative is 1, and the
period-1 orbits have ``cos phase > 0``, far from the cut at ±π).

**Section**: just after an impact, coordinates ``phase, y_dot`` (``y = A sin(phase)``); state order
``phase, y, y_dot``.  Two nontrivial multipliers.

Closed forms (derived here for the exact model; Holmes' high-bounce map is their limit):

* A *period-n* bouncing orbit (one impact every ``n`` table periods, flight time ``T = 2πn/ω``)
  leaves and meets the table at the same phase φ with ``ẏ⁺ = gT/2 = −ẏ⁻``; the impact law gives
  ``(1 + e) A ω cos φ = (1 − e) g T / 2``, i.e. ``Γ cos φ = π n (1 − e)/(1 + e)``.  It exists for
  ``Γ ≥ Γ_SN(n) = π n (1 − e)/(1 + e)`` (saddle-node at φ = 0), as two orbits ``±φ``.  This is
  exactly Holmes' condition ``γ cos φ = 2nπ(1 − α)`` with ``γ = 2(1 + e)Γ``, ``α = e``.
* Linearising the impact-to-impact map (implicit next impact time) at the orbit, with the table
  velocity ``c = A ω cos φ`` satisfying ``c / (gT/2) = (1 − e)/(1 + e)``, gives in
  ``(t, ẏ)`` coordinates ``J = [[1, (1+e)/g], [(1+e) s̈, 1 − e + ((1+e) s̈ + e g)(1+e)/g]]``,
  ``s̈ = −A ω² sin φ``: ``det J = e²`` and ``tr J = 1 + e² − (1 + e)² Γ sin φ``.  The orbit with
  ``sin φ > 0`` (impact while the table decelerates) is stable until ``tr J = −(1 + e²)``, a
  period doubling at ``Γ sin φ = 2 (1 + e²)/(1 + e)²``:
  ``Γ_PD(n)² = Γ_SN(n)² + (2 (1 + e²)/(1 + e)²)²``; the orbit with ``sin φ < 0`` is a saddle.
* Holmes' map ``φ' = φ + v``, ``v' = α v − γ cos φ'`` (table displacement neglected, high
  bounces; G&H §2.4) has ``det = α = e`` and ``tr = 1 + α + γ sin φ'`` (its sign convention), so
  its window is ``Γ_SN < Γ < sqrt(Γ_SN² + 1)``; the exact window ends later, since
  ``2 (1 + e²)/(1 + e)² ≥ 1``, and the two agree as ``e → 1``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import casadi as ca
import numpy as np

from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..parameters import gravity_parameter, parameter
from .blocks import bar_and_ball_points
from .quantities import restitution_parameter

__all__ = ["BouncingBall"]

_HOLMES = "Holmes 1982; Guckenheimer & Holmes §2.4"
#: Half-width (m) of the drawn table (drawing only: the model's ball and table are on one line).
TABLE_HALF_WIDTH = 0.03


@dataclass(frozen=True)
class BouncingBall(HybridModel):
    """Ball on a vibrating table: state ``phase`` (rad, table phase ω t), ``y`` (m), ``y_dot``
    (m/s); section just after an impact (``phase``, ``y_dot``)."""

    name = "bouncing_ball"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("phase", "y", "y_dot")
    declared_coordinates = ("phase", "y_dot")
    declared_section_doc = "just after an impact: y = A sin(phase), phase in [−π, π)"
    state_units = {"phase": "rad", "y": "m", "y_dot": "m/s"}  # for axis labels
    title = "Ball bouncing on a vibrating table"
    reference = "Holmes 1982; Guckenheimer & Holmes 1983, §2.4"
    mesh = (4, 4)
    #: The drawing: the table's top (a bar at height s = A sin(phase)) and the ball (a dot).
    drawing = (("table_left", "table_right"),)
    #: No ground under the scene: the table is the only support (see :mod:`gaitopt.animation`).
    on_ground: ClassVar[bool] = False
    #: A flight lasts a few table periods at most (0.2 s each at the defaults).
    max_phase_time: ClassVar[float] = 5.0

    restitution: float = restitution_parameter(
        0.5,
        "coefficient of restitution e (relative velocity reversed and scaled by e)",
        "Guckenheimer & Holmes §2.4 figures use α = e = 0.5",
    )
    acceleration: float = parameter(
        1.2, unit="1", low=0.0, high=20.0, low_open=True,
        doc="peak table acceleration relative to gravity Γ = A ω²/g",
        source="inside the period-1 stability window (1.047, 1.527) at e = 0.5",
    )  # fmt: skip
    frequency: float = parameter(
        5.0, unit="Hz", low=0.0, high=1e3, low_open=True,
        doc="table frequency f (ω = 2π f)",
        source="a slow paddle: flights of a few cm, table amplitude ≈ 1 cm·Γ",
    )  # fmt: skip
    gravity: float = gravity_parameter()

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        e, g = sym.restitution, sym.gravity
        omega = 2 * ca.pi * sym.frequency
        amp = sym.acceleration * g / omega**2  # A = Γ g / ω²
        x, (phase, y, y_dot) = sym.states("phase", "y", "y_dot")
        flow = sym.function("flow", x, ca.vertcat(omega, y_dot, -g))
        wrapped = phase - 2 * ca.pi * ca.floor((phase + ca.pi) / (2 * ca.pi))
        impact = Transition(
            name="impact",
            guard=sym.function("guard", x, y - amp * ca.sin(phase)),  # y = s(t), falling
            direction=-1,
            reset=sym.function(
                "reset",
                x,
                ca.vertcat(
                    wrapped,
                    amp * ca.sin(wrapped),
                    (1 + e) * amp * omega * ca.cos(phase) - e * y_dot,
                ),
            ),
            target=0,
            doc="ball meets the table, y = A sin(ωt) from above; ẏ⁺ = (1 + e) ṡ − e ẏ⁻, "
            "phase wrapped into [−π, π)",
        )
        energy = sym.conserved("energy", x, 0.5 * y_dot**2 + g * y)  # per unit mass (J/kg)
        # The ball stays above the table between impacts; it leaves the table at once after an
        # impact (it would otherwise stick to it: the chattering/sticking motions of Holmes 1982
        # are not a gait of this model).
        above = sym.constraint(
            "ball above the table",
            x,
            y - amp * ca.sin(phase),
            "ball below the table",
            at_start=True,
            at_end=True,
            unit="m",
            source="the table is solid (Holmes 1982)",
        )
        # Drawing points (m): the table's top at s = A sin(phase), the ball at height y; so the
        # drawn gap between them is the constraint's y − A sin(phase).
        table = amp * ca.sin(phase)
        points = bar_and_ball_points(sym, x, bar=table, ball=y, half_width=TABLE_HALF_WIDTH)
        flight = Phase(
            "flight",
            ("phase", "y", "y_dot"),
            flow,
            (impact,),
            {"energy": energy},
            points=points,
            point_names=("table_left", "table_right", "ball"),
            constraints=(above,),
        )
        s = ca.SX.sym("s", 2)
        section = Section(
            ("phase", "y_dot"),
            sym.lift(s, ca.vertcat(s[0], amp * ca.sin(s[0]), s[1])),
            "just after an impact: y = A sin(phase), phase in [−π, π)",
        )
        return (flight,), section

    # -- derived quantities ------------------------------------------------------------------
    @property
    def omega(self) -> float:
        """Table angular frequency ``ω = 2π f`` (rad/s)."""
        return 2 * math.pi * self.frequency

    @property
    def amplitude(self) -> float:
        """Table amplitude ``A = Γ g / ω²`` (m)."""
        return self.acceleration * self.gravity / self.omega**2

    # -- closed forms ------------------------------------------------------------------------
    def saddle_node_acceleration(self, n: int = 1) -> float:
        """``Γ_SN(n) = π n (1 − e)/(1 + e)``: the period-n orbits exist for Γ above it (exact, and
        Holmes' γ cos φ = 2nπ(1 − α))."""
        e = self.restitution
        return math.pi * n * (1 - e) / (1 + e)

    def period_doubling_acceleration(self, n: int = 1) -> float:
        """``Γ_PD(n) = sqrt(Γ_SN² + (2 (1 + e²)/(1 + e)²)²)``: the stable period-n orbit
        period-doubles here (exact model, derived in the module docstring)."""
        e = self.restitution
        return math.hypot(self.saddle_node_acceleration(n), 2 * (1 + e**2) / (1 + e) ** 2)

    def holmes_period_doubling_acceleration(self, n: int = 1) -> float:
        """Holmes' high-bounce approximation of :meth:`period_doubling_acceleration`:
        ``γ² = (2nπ(1 − α))² + 4(1 + α)²`` with ``γ = 2(1 + e)Γ``, i.e.
        ``Γ = sqrt(Γ_SN² + 1)`` (Guckenheimer & Holmes §2.4)."""
        return math.hypot(self.saddle_node_acceleration(n), 1.0)

    def period_orbit(self, n: int = 1, stable: bool = True) -> dict[str, float] | None:
        """The period-n orbit's section point (``phase``, ``y_dot``) in closed form, or None
        below ``Γ_SN(n)``: ``cos φ = Γ_SN(n)/Γ``, ``sin φ > 0`` for the stable one,
        ``ẏ⁺ = g T/2 = π n g/ω``."""
        c = self.saddle_node_acceleration(n) / self.acceleration
        if c > 1:
            return None
        phi = math.acos(c)
        return {"phase": phi if stable else -phi, "y_dot": math.pi * n * self.gravity / self.omega}

    def period_multipliers(self, n: int = 1, stable: bool = True) -> np.ndarray | None:
        """Closed-form multipliers of the period-n orbit: roots of
        ``λ² − (1 + e² − (1 + e)² Γ sin φ) λ + e² = 0``."""
        orbit = self.period_orbit(n, stable)
        if orbit is None:
            return None
        e = self.restitution
        trace = 1 + e**2 - (1 + e) ** 2 * self.acceleration * math.sin(orbit["phase"])
        roots = np.roots([1.0, -trace, e**2]).astype(complex)
        return roots[np.argsort(-np.abs(roots))]

    def existence_note(self) -> str | None:
        lo, hi = self.saddle_node_acceleration(), self.period_doubling_acceleration()
        return (
            f"bouncing ball with e = {self.restitution:g}: period-1 bouncing exists for "
            f"acceleration Γ ≥ {lo:.4g} and is stable up to Γ = {hi:.4g} (closed form; Holmes "
            f"1982); here Γ = {self.acceleration:g}"
        )

    def default_start(self) -> dict[str, float]:
        """The closed-form stable period-1 orbit (or a bounce at the table's rest speed)."""
        orbit = self.period_orbit(1, stable=True)
        if orbit is None:
            return {"phase": 0.0, "y_dot": math.pi * self.gravity / self.omega}
        return orbit
