"""The planar quadruped's pronk under Raibert's controller, both legs one virtual leg.

Raibert, Chepponis & Brown 1986 ("Running on four legs as though they were one"): in a pronk all
legs strike together and act as one virtual leg run by the one-legged hopper's three-part
controller.  The body, legs and controller are those of ``planar_quadruped_raibert``
(``gaitopt/models/planar_quadruped_raibert.py``): each stance leg has rest length ``l0 + δ`` and
loss ``c``, both feet are placed ``x_f = ẋ T_s/2 + k_ẋ (ẋ − ẋ_d)`` ahead of their hips, and the
pitch servo ``τ = −k_p φ − k_v φ̇`` is shared by the two stance hips.  The virtual leg's expected
stance time is that of the body on both springs, ``T_s = π sqrt(m/(2k))``.

Phases: apex → descent → *double stance* → ascent → apex.  As for ``planar_quadruped_pronk``,
simultaneous touchdown and lift-off are not generic (any pitch splits them), so the pronk is a
cycle of this phase sequence on the invariant pitch-free set ``φ = φ̇ = 0`` (there the two legs
are mirror images about the COM, their forces equal, their moments ±L F_z cancel, and the
servo's torque is zero).  Section: that set's apex, coordinates ``z, x_dot``; its two
multipliers are those of the pitch-free directions only.  On the set the COM moves exactly as
``raibert_hopper``'s with stiffness ``2k``, loss ``2c``, the same thrust ``δ``, mass, rest length,
desired speed and speed gain (its pitch held at zero): the check in
tests/test_planar_quadruped_raibert.py.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca

from ..hybrid import Phase, Section, Symbols, Transition
from .planar_quadruped import _FLIGHT
from .planar_quadruped_raibert import _NAMES, _RAIBERT, PlanarQuadrupedRaibert, _Legs
from .raibert_hopper import speed_gain_parameter

__all__ = ["PlanarQuadrupedRaibertPronk"]


@dataclass(frozen=True)
class PlanarQuadrupedRaibertPronk(PlanarQuadrupedRaibert):
    """Planar quadruped pronking under Raibert's controller: apex height ``z`` (m) and forward
    speed ``x_dot`` (m/s) the section coordinates (pitch-free set); stance adds both feet (m);
    no per-step input."""

    name = "planar_quadruped_raibert_pronk"
    title = "Planar quadruped pronking, Raibert's controller (one virtual leg)"
    declared_states = _FLIGHT
    declared_coordinates = ("z", "x_dot")
    declared_section_doc = "pitch-free apex: z_dot = 0, x = 0, phi = phi_dot = 0"

    k_speed: float = speed_gain_parameter(
        0.03,
        _RAIBERT + ", §2.3; chosen below the pronk's period doubling near k_ẋ = 0.042 s "
        "(problems/planar_quadruped_raibert.py)",
        low=0.0,
    )

    @staticmethod
    def _stance_time(s):
        """``T_s = π sqrt(m/(2k))`` (s): the body on both springs."""
        sqrt = ca.sqrt if isinstance(s, Symbols) else math.sqrt
        return math.pi * sqrt(s.mass / (2 * s.stiffness))

    def existence_note(self) -> str | None:
        """What sets the gait (added to a failed search)."""
        return (
            f"controlled pronk: on the pitch-free set it is raibert_hopper with stiffness "
            f"{2 * self.stiffness:g} N/m, loss {2 * self.damping:g} N s/m and thrust "
            f"{self.thrust:g} m; the thrust's k δ² = {self.stiffness * self.thrust**2:.3g} J a "
            f"stance must balance the legs' loss"
        )

    def default_start(self) -> dict[str, float]:
        """Near the (stable) controlled pronk at the defaults: z = 0.52209 m, ẋ = 0.52824 m/s."""
        return {"z": 0.522, "x_dot": 0.528}

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        legs = _Legs(sym, cls._stance_time(sym))
        # 0 descent: both feet reach the ground together (φ = 0: both hips at height z)
        xd = Symbols.states(*_FLIGHT)[0]
        back, front = legs.hips(xd)
        th = legs.angle(xd)
        touchdown = Transition(
            name="touchdown",
            guard=sym.function("guard", xd, legs.clearance(back, th)),
            direction=-1,
            reset=sym.function(
                "reset",
                xd,
                ca.vertcat(xd, back[0] + legs.l0 * ca.sin(th), front[0] + legs.l0 * ca.sin(th)),
            ),
            target=1,
            impact=False,
            doc="both feet reach the ground (pitch-free: z − l0 cos θ_td = 0, falling), θ_td "
            "from Raibert's foot placement",
        )
        descent = Phase(
            "descent",
            _FLIGHT,
            legs.ballistic(xd),
            (touchdown, legs.falls(xd, (back, front), "apex below touchdown height")),
            {"energy": legs.flight_energy(xd)},
            points=legs.points(xd),
            point_names=_NAMES,
        )
        # 1 double stance
        xs = Symbols.states(*_FLIGHT, "back_foot", "front_foot")[0]
        back, front = legs.hips(xs)
        liftoff = Transition(
            name="liftoff",
            guard=sym.function("guard", xs, legs.leg(back, xs[6])[4]),
            direction=-1,
            reset=sym.function("reset", xs, xs[:6]),
            target=2,
            impact=False,
            doc="the legs' force k (l0 + δ − r) − c ṙ falls to zero (pitch-free: both at once)",
        )
        stance = Phase(
            "double stance",
            (*_FLIGHT, "back_foot", "front_foot"),
            legs.flow(xs, [(back, xs[6]), (front, xs[7])]),
            (liftoff, legs.falls(xs, (back, front), "a hip reaches the ground in stance")),
            {},  # thrust, loss and hip work: nothing conserved
            points=legs.points(xs, back_foot=xs[6], front_foot=xs[7]),
            point_names=_NAMES,
        )
        # 2 ascent → apex
        xa = Symbols.states(*_FLIGHT)[0]
        back, front = legs.hips(xa)
        top = legs.apex(xa)
        ascent = Phase(
            "ascent",
            _FLIGHT,
            legs.ballistic(xa),
            (top, legs.falls(xa, (back, front), "lifted off falling: no apex")),
            {"energy": legs.flight_energy(xa)},
            points=legs.points(xa),
            point_names=_NAMES,
        )
        s = ca.SX.sym("s", 2)
        section = Section(
            ("z", "x_dot"),
            sym.lift(s, ca.vertcat(0, s[0], 0, s[1], 0, 0)),
            "pitch-free apex: z_dot = 0, x = 0, phi = phi_dot = 0",
        )
        return (descent, stance, ascent), section
