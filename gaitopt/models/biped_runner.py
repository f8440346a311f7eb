"""A planar biped runner: a point mass on two massless spring legs that take turns.

Raibert's biped running (Raibert, *Legged Robots That Balance*, MIT Press 1986, ch. 4): a biped
that runs with its legs alternating behaves as a one-legged hopper whose single *virtual leg* is
the leg on the ground; with identical legs and identical touchdown angles each step is one SLIP
step (Blickhan 1989; Tedrake, *Underactuated Robotics*, "Simple models of walking and running",
§ SLIP), which fixes the defaults here.  The legs may differ (their own stiffness ``k_a, k_b``
and rest length ``l_a, l_b``: an asymmetric biped, as in Merker, Kaiser, Seyfarth & Hermann,
"Stable running with asymmetric legs: a bifurcation approach", Int. J. Bifurcation Chaos 2015),
and each has its own touchdown angle (per-step inputs, as the SLIP's).

One stride (two steps) is six phases, in cycle order:

0. **descent A** (flight; state ``x, z, x_dot, z_dot``, ``z`` the hip height above the ground,
   ``x`` from the last apex): ``ẍ = 0, z̈ = −g``; leg A held at ``θ_a`` from vertical (foot
   ahead of the hip for ``θ_a > 0``); **touchdown A** at ``z − l_a cos θ_a = 0`` falling.
1. **stance A** (polar coordinates ``r, theta, r_dot, theta_dot`` of the hip about foot A,
   ``theta`` from vertical, positive with the hip ahead of the foot): the SLIP's stance
   equations (Lagrangian ``L = ½ m (ṙ² + r² θ̇²) − m g r cos θ − ½ k_a (l_a − r)²``)::

       r̈ = r θ̇² − g cos θ + (k_a/m)(l_a − r),      θ̈ = (g sin θ − 2 ṙ θ̇) / r.

   **Lift-off A** at ``r = l_a`` extending, moving forwards.
2. **ascent A** (flight, ``x`` from foot A) up to the **mid-stride apex** ``ż = 0`` falling, where
   ``x`` is reset to 0.
3. **descent B**, 4. **stance B**, 5. **ascent B**: the same with leg B (``θ_b, k_b, l_b``); the
   apex at the end of ascent B closes the stride.

The flight leg is swung forward instantly after lift-off (massless legs, the SLIP's convention);
the other leg's foot clearance is not checked.  Touchdown and lift-off change no velocity and the
leg force ``k (l − r)`` is zero at both (declared constraint: the leg can only push).

**Poincaré section**: the apex before leg A's touchdown, ``ż = 0``, ``x = 0``.  The energy
``E = ½ m |v|² + m g z (+ ½ k (l − r)² in stance)`` is conserved in every phase and is a
parameter, so ``ẋ = sqrt(2 (E/m − g z))`` and the section has the single coordinate ``z``: the
stride map ``z[n+1] = P(z[n]; θ_a, θ_b)`` has one nontrivial multiplier (energy conservation and
the time shift add no trivial ones).

**Symmetric run = SLIP run** (exact): with ``k_a = k_b = k``, ``l_a = l_b = l``, ``θ_a = θ_b = θ``
each step is the SLIP apex map ``S`` of ``(m, k, l, θ, E)``, so ``P = S ∘ S``.  The SLIP's fixed
point ``z*`` is a fixed point of ``P`` with the same apex height and forward speed, period
``2 T_SLIP``, and multiplier ``P'(z*) = S'(z*)²`` — the SLIP multiplier *squared* (a 1-D
section: one multiplier, not a pair; tests/test_biped_runner.py checks all four to 1e-10).
``P`` may have further fixed points, the 2-cycles of ``S`` (a period-doubled SLIP run); none is
sought here.

**Asymmetric gaits**: with unequal angles or legs the two steps differ.  :func:`classify`
measures a stride (apex heights ``z_a, z_b`` before each touchdown, step lengths, stance and
aerial times) and names it, after the literature's usage:

* *symmetric run*: the two steps are equal (apex heights within 1e-8 m): Raibert's one-foot
  gait with the legs interchangeable.
* *skip*: the footfalls are unevenly spaced in time, two contacts close together and then a long
  aerial phase (Minetti 1998, "The biomechanics of skipping gaits: a third locomotion paradigm?",
  Proc. R. Soc. B 265; modelled with a bipedal SLIP by Andrada et al. 2016, "Stability in skipping
  gaits", R. Soc. Open Sci. 3:160602).  This phase cycle always has a flight between the steps
  (no double support), so the threshold is ours: one aerial phase shorter than half the other.
* *limp*: an asymmetric run that is not a skip: alternating apex heights (and unequal step
  lengths or stance times) with comparable aerial phases — the asymmetric running gaits of
  Merker et al. 2015.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import ClassVar

import casadi as ca
import numpy as np

from ..errors import ParameterError
from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..parameters import gravity_parameter, parameter
from .blocks import ballistic_flow, fall, leg_touchdown
from .polar import FLIGHT, UNITS, leg_in_flight, spring_stance
from .quantities import energy_parameter, length_parameter, mass_parameter, stiffness_parameter

__all__ = ["BipedRunner", "classify"]

_TEDRAKE = "Tedrake, Underactuated Robotics, SLIP apex map (after Geyer 2005)"
#: Threshold of :func:`classify`: a stride whose shorter aerial phase is below this fraction of
#: the longer one is a skip (our choice; see the module docstring).
SKIP_RATIO = 0.5


def _step(sym: Symbols, leg: str, first: int) -> tuple[Phase, Phase, Phase]:
    """Descent, stance and ascent of one step on leg ``leg`` ("a" or "b"), phases ``first`` to
    ``first + 2``; the ascent's apex enters phase ``(first + 3) % 6``."""
    m, g = sym.mass, sym.gravity
    k, l0 = getattr(sym, f"stiffness_{leg}"), getattr(sym, f"rest_length_{leg}")
    angle = sym.input(f"touchdown_angle_{leg}")
    drawn = getattr(sym, f"touchdown_angle_{leg}")  # drawing functions take (x, p) only
    L = leg.upper()

    xf, (x, z, x_dot, z_dot) = sym.states(*FLIGHT)
    ballistic = ballistic_flow(sym, xf, g, vertical=1)  # ẍ = 0, z̈ = −g
    flight_energy = sym.conserved("energy", xf, 0.5 * m * (x_dot**2 + z_dot**2) + m * g * z)

    # -- descent: touchdown at z − l cos θ = 0 falling (the SLIP's, blocks.leg_touchdown) -------
    touchdown = leg_touchdown(
        sym,
        xf,
        height=z,
        velocity=(x_dot, z_dot),
        length=l0,
        angle=angle,
        impact=False,  # a massless leg: the hip's velocity is only re-expressed
        doc=f"foot {L} reaches the ground: z − l_{leg}·cos θ_{leg} = 0, falling; the hip in "
        f"polar coordinates about foot {L}",
    )
    touchdown = replace(touchdown, name=f"touchdown {L}", target=first + 1)
    descent = Phase(
        f"descent {L}",
        FLIGHT,
        ballistic,
        (
            touchdown,
            fall(
                sym,
                xf,
                f"apex below leg {L}'s touchdown height (hip reaches the ground)",
                z,
                f"fires only if touchdown {L} never armed: the apex was below l_{leg}·cos θ_{leg}",
            ),
        ),
        {"energy": flight_energy},
        points=leg_in_flight(sym, xf, l0, drawn),
        point_names=("hip", "foot", "origin"),
    )

    # -- stance: the SLIP's polar equations about the foot (module docstring) -------------------
    stance = spring_stance(sym, stiffness=k, rest_length=l0, target=first + 2, leg=L)

    # -- ascent: up to the apex ż = 0 falling, x measured from there --------------------------
    nxt = (first + 3) % 6
    top = Transition(
        name="apex" if nxt == 0 else "mid-stride apex",
        guard=sym.function("guard", xf, z_dot),
        direction=-1,
        reset=sym.function("reset", xf, ca.vertcat(0, z, x_dot, z_dot)),
        target=nxt,
        impact=False,
        foothold="below_hip",
        doc="top of the flight, ż = 0 falling; x is measured from here on",
    )
    ascent = Phase(
        f"ascent {L}",
        FLIGHT,
        ballistic,
        (
            top,
            fall(
                sym,
                xf,
                "falls (no apex after lift-off)",
                z,
                "lifted off falling: the hip reaches the ground before any apex",
            ),
        ),
        {"energy": flight_energy},
        points=leg_in_flight(sym, xf, l0, drawn),
        point_names=("hip", "foot", "below_hip"),
    )
    return descent, stance, ascent


def _leg_parameter(kind: str, leg: str):
    L = leg.upper()
    if kind == "stiffness":
        return stiffness_parameter(
            8397.36,
            f"leg {L} stiffness k_{leg} (k̃ = k l/(m g) = 10.7 at the defaults)",
            _TEDRAKE + ": k̃ = 10.7",
        )
    if kind == "rest_length":
        return length_parameter(1.0, f"leg {L} rest length l_{leg}", _TEDRAKE)
    return parameter(
        math.pi / 6, unit="rad", low=0.0, high=math.pi / 2, high_open=True,
        doc=f"nominal touchdown angle θ_{leg} of leg {L} from vertical (the per-step input's "
        f"default)",
        source=_TEDRAKE + ": 30°",
    )  # fmt: skip


@dataclass(frozen=True)
class BipedRunner(HybridModel):
    """Biped runner: flight state ``x, z`` (m), ``x_dot, z_dot`` (m/s); stance ``r`` (m),
    ``theta`` (rad), ``r_dot`` (m/s), ``theta_dot`` (rad/s) about the stance foot; per-step
    inputs the touchdown angles ``touchdown_angle_a``, ``touchdown_angle_b`` (rad from
    vertical)."""

    name = "biped_runner"
    title = "Planar biped runner (two alternating SLIP legs)"
    reference = (
        "Raibert 1986 (Legged Robots That Balance, ch. 4); Blickhan 1989; "
        "Tedrake, Underactuated Robotics (SLIP); Merker et al. 2015"
    )
    declared_states = FLIGHT
    declared_coordinates = ("z",)
    declared_section_doc = (
        "apex before leg A's touchdown: z_dot = 0, x = 0, x_dot = sqrt(2 (energy/mass − gravity·z))"
    )
    drawing = (("hip", "foot"),)
    state_units = UNITS
    inputs = ("touchdown_angle_a", "touchdown_angle_b")
    input_units = ("rad", "rad")
    input_bounds: ClassVar[dict[str, tuple[float, float]]] = {
        "touchdown_angle_a": (0.0, math.pi / 2),
        "touchdown_angle_b": (0.0, math.pi / 2),
    }
    mesh = (4, 4)
    #: A flight from an apex lasts at most sqrt(2 E/(m g²)) ≈ 0.6 s at the defaults.
    max_phase_time: ClassVar[float] = 5.0

    mass: float = mass_parameter(80.0, "body mass m", _TEDRAKE)
    stiffness_a: float = _leg_parameter("stiffness", "a")
    stiffness_b: float = _leg_parameter("stiffness", "b")
    rest_length_a: float = _leg_parameter("rest_length", "a")
    rest_length_b: float = _leg_parameter("rest_length", "b")
    touchdown_angle_a: float = _leg_parameter("angle", "a")
    touchdown_angle_b: float = _leg_parameter("angle", "b")
    gravity: float = gravity_parameter()
    energy: float = energy_parameter(
        1263.528,
        "total energy E = ½ m v² + m g z (Ẽ = E/(m g l) = 1.61 at the defaults)",
        _TEDRAKE + ": Ẽ = 1.61",
    )

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        phases = (*_step(sym, "a", 0), *_step(sym, "b", 3))
        m, g, E = sym.mass, sym.gravity, sym.energy
        s = ca.SX.sym("s", 1)
        speed = ca.sqrt(ca.fmax(2 * (E / m - g * s[0]), 0))
        section = Section(
            ("z",), sym.lift(s, ca.vertcat(0, s[0], speed, 0)), cls.declared_section_doc
        )
        return phases, section

    def _touchdown_heights(self) -> tuple[float, float]:
        return (
            self.rest_length_a * math.cos(self.touchdown_angle_a),
            self.rest_length_b * math.cos(self.touchdown_angle_b),
        )

    def check(self) -> None:
        top = self.highest_apex()
        for leg, height in zip("AB", self._touchdown_heights(), strict=True):
            if top <= height:
                raise ParameterError(
                    f"biped_runner: `energy` = {self.energy:g} J puts the highest apex, "
                    f"E/(m g) = {top:.4g} m, below leg {leg}'s touchdown height l·cos θ = "
                    f"{height:.4g} m: foot {leg} never reaches the ground; raise `energy` or "
                    f"leg {leg}'s touchdown angle"
                )

    def highest_apex(self) -> float:
        """``E/(m g)`` (m): the apex height with no forward speed left."""
        return self.energy / (self.mass * self.gravity)

    def map_domain(self) -> tuple[float, float]:
        """Apex heights where the stride map may be defined: above leg A's touchdown height
        and below ``E/(m g)``."""
        return self._touchdown_heights()[0], self.highest_apex()

    def section_limits(self) -> dict[str, tuple[float, float, str]]:
        """An apex cannot be higher than ``E/(m g)``, where no forward speed is left."""
        top = self.highest_apex()
        return {
            "z": (
                -math.inf,
                top,
                f"the energy height E/(m g) = {top:.6g} m (energy {self.energy:g} J), where no "
                f"forward speed is left; raise `energy` for a higher apex",
            )
        }

    def apex_speed(self, z: float) -> float:
        """Forward speed ``ẋ = sqrt(2 (E/m − g z))`` (m/s) at an apex of height ``z`` (m)."""
        return math.sqrt(max(2 * (self.energy / self.mass - self.gravity * z), 0.0))

    def existence_note(self) -> str | None:
        """The stride map's domain (added to a failed search)."""
        lo, hi = self.map_domain()
        return (
            f"biped runner: the stride map is defined only for apex heights between leg A's "
            f"touchdown height {lo:.4g} m and E/(m g) = {hi:.4g} m (and the mid-stride apex "
            f"must lie above leg B's, {self._touchdown_heights()[1]:.4g} m); near the top the "
            f"runner falls back (Tedrake, Underactuated Robotics, SLIP apex map)"
        )

    def nominal_input(self) -> np.ndarray:
        """The touchdown-angle parameters ``(θ_a, θ_b)`` (rad)."""
        return np.array([self.touchdown_angle_a, self.touchdown_angle_b])

    def default_start(self) -> dict[str, float]:
        """Near the stable SLIP run at the defaults (z ≈ 0.87 m, Tedrake's apex map)."""
        lo, hi = self.map_domain()
        return {"z": 0.87} if lo < 0.87 < hi else {"z": 0.5 * (lo + hi)}


def classify(cycle) -> dict[str, object]:
    """Measure a biped-runner stride and name its gait (module docstring).

    Parameters
    ----------
    cycle : LimitCycle
        A gait of :class:`BipedRunner` (its ``orbit`` of six arcs and its ``inputs``).

    Returns
    -------
    dict
        ``apex_a``, ``apex_b``: apex heights (m) before the touchdowns of legs A and B;
        ``step_a``, ``step_b``: step lengths (m), foot B to foot A and foot A to foot B;
        ``stance_a``, ``stance_b``: stance times (s); ``aerial_a``, ``aerial_b``: the aerial
        phases (s) ending at touchdown A and at touchdown B; ``gait``: ``"symmetric run"``,
        ``"limp"`` or ``"skip"``.
    """
    model = cycle.model
    arcs = cycle.orbit
    if len(arcs) != 6:
        raise ValueError(f"classify: expected the six arcs of one stride, got {len(arcs)}")
    end = [arc.x[:, -1] for arc in arcs]
    start = [arc.x[:, 0] for arc in arcs]
    dur = [arc.t[-1] - arc.t[0] for arc in arcs]
    ta, tb = (float(v) for v in cycle.inputs)
    # Foot ahead of the hip at touchdown by l sin θ; ascent x is measured from the foot.
    reach_a = model.rest_length_a * math.sin(ta)
    reach_b = model.rest_length_b * math.sin(tb)
    out: dict[str, object] = {
        "apex_a": float(start[0][1]),
        "apex_b": float(start[3][1]),
        "step_a": float(end[5][0] + end[0][0] + reach_a),  # foot B → foot A
        "step_b": float(end[2][0] + end[3][0] + reach_b),  # foot A → foot B
        "stance_a": float(dur[1]),
        "stance_b": float(dur[4]),
        "aerial_a": float(dur[5] + dur[0]),
        "aerial_b": float(dur[2] + dur[3]),
    }
    aerial = sorted((out["aerial_a"], out["aerial_b"]))
    if abs(out["apex_a"] - out["apex_b"]) <= 1e-8:
        out["gait"] = "symmetric run"
    elif aerial[0] < SKIP_RATIO * aerial[1]:
        out["gait"] = "skip"
    else:
        out["gait"] = "limp"
    return out
