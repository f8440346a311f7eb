"""Grizzle's three-link walker under fixed virtual constraints, closed by I/O linearisation.

Grizzle, Abba & Plestan 2001, "Asymptotically stable walking for biped robots: analysis via
systems with impulse effects", IEEE Trans. Automatic Control 46(1), 51–64: the planar biped with
two identical straight legs, a hip and a torso, driven by two torques between the torso and each
leg (no ankle torque: the stance foot is a passive pivot).  The model is the *closed loop*: the
flow is the open-loop dynamics under the input–output linearising controller that enforces the
paper's fixed virtual constraints, so every analysis (``find_limit_cycle``, continuation, the
simulation) runs on it with no per-step input.

**Coordinates** (the paper's).  Absolute angles from the vertical, ``θ1`` the stance leg (from
its foot up to the hip), ``θ2`` the swing leg (from its foot up to the hip), ``θ3`` the torso
(from the hip up); each is positive when it leans *forward*, towards +x, the walking direction.
With ``e(θ) = (sin θ, cos θ)`` and the stance foot at the origin (world frame, y up)::

    hip = r e(θ1),  swing foot = hip − r e(θ2),  torso mass = hip + L e(θ3),
    stance-leg mass = (r/2) e(θ1),  swing-leg mass = hip − (r/2) e(θ2).

Point masses: each leg ``m`` at mid-leg, the hip ``M_H``, the torso ``M_T`` at ``L`` above the
hip.  A step runs from ``θ1 = −θ_i`` (hip behind the stance foot) to ``θ1 = +θ_i`` with
``θ_i = impact_angle = π/8``.

**Open loop** (Grizzle et al. 2001, §II, as stated in issue 20), ``D(q) q̈ + C(q, q̇) q̇ + G(q) =
B u`` with ``c_ij = cos(θi − θj)``, ``s_ij = sin(θi − θj)``::

    D = [[(M_H + M_T + 5m/4) r², −(m r²/2) c12, M_T L r c13],
         [−(m r²/2) c12,          m r²/4,       0          ],
         [M_T L r c13,            0,            M_T L²     ]],
    C = [[0, −(m r²/2) s12 θ̇2, M_T L r s13 θ̇3],
         [(m r²/2) s12 θ̇1, 0, 0],
         [−M_T L r s13 θ̇1, 0, 0]],
    G = [−(M_H + M_T + 3m/2) g r sin θ1, (m g r/2) sin θ2, −M_T g L sin θ3],
    B = [[−1, 0], [0, −1], [1, 1]].

``u1`` acts between the stance leg and the torso, ``u2`` between the swing leg and the torso
(N·m): the power of the torques is ``q̇ᵀ B u = u1 (θ̇3 − θ̇1) + u2 (θ̇3 − θ̇2)``, so
``dE/dt = q̇ᵀ B u`` with ``E = ½ q̇ᵀ D q̇ + V``, ``V = (M_H + M_T + 3m/2) g r cos θ1 −
(m g r/2) cos θ2 + M_T g L cos θ3`` (the tests check D, C, G against Lagrange's equations of the
point masses above, and the power balance along the closed loop).

**Virtual constraints and controller** (Grizzle et al. 2001, §V's example; the fixed outputs of
issue 20).  The outputs ``h(q) = [θ3 − θ3d, θ1 + θ2 − δ]`` (``θ3d = torso_angle = π/8``: the
torso held leaning forward; ``δ = swing_offset = 0``: the swing leg mirrors the stance leg) have
relative degree two, ``L_f h = H q̇`` with ``H = ∂h/∂q = [[0, 0, 1], [1, 1, 0]]``.  Writing
``q̈ = a(q, q̇) + A(q) u`` with ``a = −D⁻¹ (C q̇ + G)``, ``A = D⁻¹ B``, the I/O-linearising
feedback (Isidori 1995, §5.1; Grizzle et al. 2001, eq. (40))::

    u = (L_g L_f h)⁻¹ (−L_f² h − K_p h − K_d L_f h),  L_g L_f h = H A,  L_f² h = H a,
    K_p = ω_n²,  K_d = 2 ζ ω_n,

makes ``ḧ + K_d ḣ + K_p h = 0`` exactly (the tests check it), ``ω_n = omega_n = 5 rad/s``,
``ζ = zeta = 1.1``.  ``L_g L_f h`` is invertible wherever ``det(H D⁻¹ B) ≠ 0`` (on the gait it
stays well away from 0; the tests check it).  The torques along a gait are :meth:`torques`
(N·m); :meth:`max_torque` gives max |u| over a gait's dense samples, or over given states such as
an independent simulation's (the JSON of ``gaitopt solve`` has no place for it).

**Impact** (Grizzle et al. 2001, §III; Hurmuzlu & Marghitu 1994).  The step ends when ``θ1``
reaches ``+θ_i`` from below: guard ``θ1 − θ_i`` rising through 0, the paper's switching surface
(on the constraint surface ``θ2 = −θ1`` that is exactly when the swing foot is on the ground
ahead).  The swing foot's impact is plastic, computed in the *extended* 5-DOF model (the stance
foot's position added as free coordinates, an impulsive force at the swing foot, the old stance
foot leaving the ground without impulse: :func:`~gaitopt.mechanics.impact_velocity`); the
torques are not impulsive, so the impact conserves the angular momentum of the whole walker about
the striking foot, of the old stance leg about the hip, and of the torso about the hip (three
laws for three velocities; the tests check each in closed form).  Then the legs swap:
``(θ1, θ2, θ3)⁺ = (θ2, θ1, θ3)⁻`` and the post-impact rates likewise.

**Section**: just after the impact, ``θ2 = θ_i`` (the new swing leg is the old stance leg, at the
guard's angle), free coordinates ``θ1, θ3`` and the three rates (5).  That is exactly the reset's
image of the guard.  On the gait ``θ1⁺ = θ2⁻ ≈ −θ_i`` ("``θ1 = −π/8``" in the issue's words):
the two differ by the swing output ``h2`` left at the end of the step, which is not zero because
the constraints are **not hybrid invariant** — the impact throws the state off the constraint
surface: ``h(x⁺) ≠ 0`` and ``L_f h(x⁺) ≠ 0`` (:meth:`outputs`; the tests report the values) — and
the outputs decay only exponentially through the next step.  So the multipliers are five: the
zero dynamics' one (0.671 at the defaults) and four of the transverse dynamics, about
``exp(λ T)`` for the roots λ of ``s² + K_d s + K_p``, which go to 0 as the gains grow.

**Conventions and constraints.**  On the constraint surface ``θ2 = −θ1`` the swing foot's height
``r (cos θ1 − cos θ2)`` is identically zero: the straight swing leg slides along the ground
through the whole step, and off it (while ``h2`` decays) its sign is whatever the transient
makes it.  As in the paper (and the compass gait's mid-swing scuff), the swing foot's height is
therefore *not* a constraint of this model and the impact happens at ``θ1 = θ_i`` whatever the
height then (it is ``r (cos θ_i − cos θ2⁻)``, −4.3e-5 m on the default gait: the foot is that
far below the ground line when it strikes).  The one
unilateral condition declared is that the stance foot pushes, ``N = ŷ · Σ m_i (r̈_i + g ŷ) ≥ 0``
(the ground reaction of the extended model on the stance foot, along the flow).  Friction is not
modelled.

**Exits** (terminal): a *fall*, the stance leg reaching horizontal (``cos θ1`` falling through 0,
forwards or backwards); a *torso fall*, the torso reaching horizontal (``cos θ3`` through 0).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import casadi as ca
import numpy as np

from ..hybrid import HybridModel, Phase, Section, Symbols, Transition
from ..mechanics import bodies_function, contact_force, impact_velocity, solve_small
from ..parameters import gravity_parameter, parameter
from .blocks import fall
from .quantities import length_parameter, mass_parameter, state_units

__all__ = ["ThreeLinkWalker"]

_GRIZZLE = "Grizzle, Abba & Plestan 2001 (IEEE TAC 46(1)), three-link example (issue 20)"
_GAINS = "issue 20: Grizzle et al. 2001's example closed with omega_n = 5, zeta = 1.1"

#: The state: absolute angles (rad) of the stance leg, swing leg and torso, then their rates.
STATE_NAMES = ("stance", "swing", "torso", "stance_dot", "swing_dot", "torso_dot")
#: Drawing points (columns of ``Phase.points``).
POINT_NAMES = ("stance_foot", "hip", "swing_foot", "torso")
#: Order of the point masses in ``Phase.bodies``.
BODY_NAMES = ("stance_leg", "hip", "torso", "swing_leg")
#: ``B`` of ``D q̈ + C q̇ + G = B u`` (Grizzle et al. 2001): u1 between stance leg and torso,
#: u2 between swing leg and torso.
INPUT_MATRIX = ((-1.0, 0.0), (0.0, -1.0), (1.0, 1.0))
#: ``H = ∂h/∂q`` of the outputs ``h = [θ3 − θ3d, θ1 + θ2 − δ]``.
OUTPUT_MATRIX = ((0.0, 0.0, 1.0), (1.0, 1.0, 0.0))


def _mass(value: float, doc: str) -> Any:
    """A point mass (kg, in (0, 1e4]) from Grizzle et al. 2001."""
    return mass_parameter(value, doc, _GRIZZLE)


def _length(value: float, doc: str) -> Any:
    """A length (m, in (0, 10]) from Grizzle et al. 2001."""
    return length_parameter(value, doc, _GRIZZLE)


def _unit(angle: ca.SX) -> ca.SX:
    """``e(θ) = (sin θ, cos θ)``: unit vector leaning ``θ`` from vertical towards +x."""
    return ca.vertcat(ca.sin(angle), ca.cos(angle))


def _grizzle(sym: Symbols) -> tuple[ca.SX, ...]:
    """Grizzle et al. 2001's ``r, m, M_H, M_T, l, g`` (m, kg, kg, kg, m, m/s²)."""
    return (
        sym.leg_length,
        sym.mass_leg,
        sym.mass_hip,
        sym.mass_torso,
        sym.torso_length,
        sym.gravity,
    )


def _terms(sym: Symbols, q: ca.SX, qd: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
    """``D(q)`` (kg·m²), ``C(q, q̇)`` (kg·m²/s) and ``G(q)`` (N·m) of Grizzle et al. 2001."""
    r, m, mh, mt, ell, g = _grizzle(sym)
    c12, c13 = ca.cos(q[0] - q[1]), ca.cos(q[0] - q[2])
    s12, s13 = ca.sin(q[0] - q[1]), ca.sin(q[0] - q[2])
    D = ca.SX(3, 3)
    D[0, 0] = (mh + mt + 5 * m / 4) * r**2
    D[0, 1] = D[1, 0] = -(m * r**2 / 2) * c12
    D[0, 2] = D[2, 0] = mt * ell * r * c13
    D[1, 1] = m * r**2 / 4
    D[2, 2] = mt * ell**2
    C = ca.SX(3, 3)
    C[0, 1] = -(m * r**2 / 2) * s12 * qd[1]
    C[0, 2] = mt * ell * r * s13 * qd[2]
    C[1, 0] = (m * r**2 / 2) * s12 * qd[0]
    C[2, 0] = -mt * ell * r * s13 * qd[0]
    G = ca.vertcat(
        -(mh + mt + 3 * m / 2) * g * r * ca.sin(q[0]),
        (m * g * r / 2) * ca.sin(q[1]),
        -mt * g * ell * ca.sin(q[2]),
    )
    return D, C, G


def _geometry(sym: Symbols, q: ca.SX) -> dict[str, ca.SX]:
    """Points and point masses relative to the stance foot (world frame, y up, m)."""
    r, ell = sym.leg_length, sym.torso_length
    hip = r * _unit(q[0])
    return {
        "stance_foot": ca.SX.zeros(2, 1),
        "hip": hip,
        "swing_foot": hip - r * _unit(q[1]),
        "torso": hip + ell * _unit(q[2]),
        "masses": [
            (sym.mass_leg, (r / 2) * _unit(q[0])),
            (sym.mass_hip, hip),
            (sym.mass_torso, hip + ell * _unit(q[2])),
            (sym.mass_leg, hip - (r / 2) * _unit(q[1])),
        ],
    }


def _closed_loop(sym: Symbols, q: ca.SX, qd: ca.SX) -> dict[str, ca.SX]:
    """The I/O-linearising controller and the closed-loop acceleration (see the module
    docstring): outputs ``h`` (rad), their rates ``L_f h`` (rad/s), the decoupling matrix
    ``L_g L_f h`` (1/(kg·m²)), the torques ``u`` (N·m) and ``q̈`` (rad/s²)."""
    D, C, G = _terms(sym, q, qd)
    B, H = ca.DM(INPUT_MATRIX), ca.DM(OUTPUT_MATRIX)
    drift = solve_small(D, -(C @ qd) - G)  # a = −D⁻¹ (C q̇ + G)
    gain = ca.horzcat(*[solve_small(D, B[:, k]) for k in range(2)])  # A = D⁻¹ B
    h = ca.vertcat(q[2] - sym.torso_angle, q[0] + q[1] - sym.swing_offset)
    dh = H @ qd  # L_f h
    kp, kd = sym.omega_n**2, 2 * sym.zeta * sym.omega_n
    decoupling = H @ gain  # L_g L_f h
    u = solve_small(decoupling, -(H @ drift) - kp * h - kd * dh)
    return {
        "D": D,
        "C": C,
        "G": G,
        "h": h,
        "dh": dh,
        "decoupling": decoupling,
        "u": ca.cse(u),
        "qdd": ca.cse(drift + gain @ u),
    }


@dataclass(frozen=True)
class ThreeLinkWalker(HybridModel):
    """Grizzle's three-link walker in closed loop: states ``stance``, ``swing``, ``torso``
    (absolute angles from vertical, rad, positive leaning forward) and their ``*_dot`` rates
    (rad/s); no per-step input (the torques are state feedback, :meth:`torques`)."""

    name = "three_link_walker"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = STATE_NAMES
    declared_coordinates = ("stance", "torso", "stance_dot", "swing_dot", "torso_dot")
    declared_section_doc = "just after the impact: swing = impact_angle"
    title = "Three-link walker (virtual constraints, I/O linearisation)"
    reference = "Grizzle, Abba & Plestan 2001 (IEEE TAC 46(1)); issue 20"
    state_units = state_units(stance="rad", swing="rad", torso="rad")
    drawing = (("stance_foot", "hip", "swing_foot"), ("hip", "torso"))
    mesh = (4, 4)
    #: Names of the torques (columns of :meth:`torques`), N·m.
    torque_names: ClassVar[tuple[str, str]] = ("stance_hip_torque", "swing_hip_torque")

    #: The open-loop plant, for a virtual-constraint controller of one's own
    #: (:mod:`gaitopt.hzd`): the configuration ``q = (θ1, θ2, θ3)`` is the first three states,
    #: :meth:`manipulator` its equations ``D q̈ + C q̇ + G = B u``; the outputs act on the
    #: swing leg and the torso, the phase variable by default is the stance-leg angle ``θ1``
    #: (monotonic over a step: from −θ_i to +θ_i), and the plant's parameters are these (the
    #: others are this model's fixed-constraint controller's).
    actuated_coordinates: ClassVar[tuple[str, ...]] = ("swing", "torso")
    phase_variable: ClassVar[dict[str, float]] = {"stance": 1.0}
    plant_parameters: ClassVar[tuple[str, ...]] = (
        "leg_length",
        "mass_leg",
        "mass_hip",
        "mass_torso",
        "torso_length",
        "gravity",
        "impact_angle",
    )

    leg_length: float = _length(1.0, "leg length r (foot to hip)")
    mass_leg: float = _mass(5.0, "leg point mass m, at mid-leg")
    mass_hip: float = _mass(15.0, "hip point mass M_H")
    mass_torso: float = _mass(10.0, "torso point mass M_T")
    torso_length: float = _length(0.5, "hip to torso mass distance L")
    gravity: float = gravity_parameter(_GRIZZLE, default=9.8)
    omega_n: float = parameter(
        5.0, unit="rad/s", low=0.0, high=1000.0, low_open=True,
        doc="natural frequency ω_n of the output dynamics ḧ + 2ζω_n ḣ + ω_n² h = 0", source=_GAINS,
    )  # fmt: skip
    zeta: float = parameter(
        1.1, unit="1", low=0.0, high=100.0, low_open=True,
        doc="damping ratio ζ of the output dynamics", source=_GAINS,
    )  # fmt: skip
    torso_angle: float = parameter(
        math.pi / 8, unit="rad", low=-math.pi / 2, high=math.pi / 2, low_open=True, high_open=True,
        doc="torso angle θ3d held by the first virtual constraint h1 = θ3 − θ3d", source=_GRIZZLE,
    )  # fmt: skip
    swing_offset: float = parameter(
        0.0, unit="rad", low=-0.5, high=0.5,
        doc="offset δ of the second virtual constraint h2 = θ1 + θ2 − δ (0: the swing leg "
        "mirrors the stance leg)",
        source=_GRIZZLE,
    )  # fmt: skip
    impact_angle: float = parameter(
        math.pi / 8, unit="rad", low=0.0, high=math.pi / 2, low_open=True, high_open=True,
        doc="stance-leg angle θ_i at the impact (θ1 = θ_i rising ends the step)", source=_GRIZZLE,
    )  # fmt: skip

    #: build() fills this module's tables of output and plant functions (``_FUNCTIONS``), so its
    #: structure is built in every process, never unpickled (:meth:`HybridModel.structure`).
    remember_structure = False

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        x, states = sym.states(*STATE_NAMES)
        q, qd = ca.vertcat(*states[:3]), ca.vertcat(*states[3:])
        geo = _geometry(sym, q)
        masses = geo["masses"]
        loop = _closed_loop(sym, q, qd)
        qdd = loop["qdd"]
        flow = sym.function("flow", x, ca.vertcat(qd, qdd))

        # Impact: extended 5-DOF model, plastic at the swing foot (Grizzle et al. 2001, §III),
        # then the legs swap (θ1, θ2, θ3)⁺ = (θ2, θ1, θ3)⁻ and the rates likewise.
        post = impact_velocity(masses, q, qd, geo["swing_foot"])
        swap = [1, 0, 2]
        impact = Transition(
            name="impact",
            guard=sym.function("guard", x, q[0] - sym.impact_angle),
            direction=1,
            reset=sym.function(
                "reset", x, ca.vertcat(*[q[k] for k in swap], *[post[k] for k in swap])
            ),
            target=0,
            foothold="swing_foot",
            doc="θ1 = impact_angle rising (Grizzle et al. 2001); plastic impact of the swing "
            "foot (extended model, the old stance foot lifts off without impulse); legs swap "
            "(θ1, θ2, θ3)⁺ = (θ2, θ1, θ3)⁻ and the rates likewise",
        )
        falls = fall(sym, x, "fall", ca.cos(q[0]), "the stance leg reaches horizontal")
        torso_fall = fall(sym, x, "torso fall", ca.cos(q[2]), "the torso reaches horizontal")
        push = sym.constraint(
            "stance foot pushes on the ground",
            x,
            contact_force(masses, q, qd, qdd, sym.gravity)[1],
            "stance foot lifts off",
            unit="N",
            source="a ground contact can only push (unilateral normal force; Grizzle et al. "
            "2001, the validity conditions of the single-support model)",
        )
        points = ca.Function(
            "points", [x, sym.p], [ca.horzcat(*[geo[k] for k in POINT_NAMES])], ["x", "p"],
            ["points"],
        )  # fmt: skip
        phase = Phase(
            "single support",
            STATE_NAMES,
            flow,
            (impact, falls, torso_fall),
            {},  # nothing is conserved along the closed loop (the torques do work)
            points=points,
            point_names=POINT_NAMES,
            bodies=bodies_function(masses, x, q, qd, sym.p),
            constraints=(push,),
        )
        free = cls.declared_coordinates
        s, sv = sym.states(*free)
        section = Section(
            free,
            sym.lift(s, ca.vertcat(sv[0], sym.impact_angle, *sv[1:])),
            "just after the impact: swing = impact_angle",
        )
        _FUNCTIONS[cls] = _functions(sym, x, q, qd, loop, geo, post)
        return (phase,), section

    def default_start(self) -> dict[str, float]:
        """The default gait's section point (rounded), from which the simulation converges to
        it (rad, rad/s)."""
        return {
            "stance": -0.3926,
            "torso": 0.3930,
            "stance_dot": 0.80,
            "swing_dot": -0.263,
            "torso_dot": 1.656,
        }

    # -- the open-loop plant (for gaitopt.hzd) -----------------------------------------------
    @classmethod
    def manipulator(cls) -> ca.Function:
        """``manipulator(q, qd, u, p) -> (D, rhs)``: the open loop ``D(q) q̈ = rhs = B u −
        C(q, q̇) q̇ − G(q)`` of Grizzle et al. 2001 (D in kg·m², rhs in N·m; ``u`` the two
        torques, N·m), for a controller of one's own (:mod:`gaitopt.hzd`)."""
        if cls not in _PLANT:
            sym = Symbols(cls.parameter_specs(), cls.inputs)
            q, qd, u = ca.SX.sym("q", 3), ca.SX.sym("qd", 3), ca.SX.sym("u", 2)
            D, C, G = _terms(sym, q, qd)
            rhs = ca.DM(INPUT_MATRIX) @ u - C @ qd - G
            masses = _geometry(sym, q)["masses"]
            qdd = ca.SX.sym("qdd", 3)
            _PLANT[cls] = (
                ca.Function("manipulator", [q, qd, u, sym.p], [D, rhs], ["q", "qd", "u", "p"],
                            ["M", "rhs"]),
                ca.Function("ground_reaction", [q, qd, qdd, sym.p],
                            [contact_force(masses, q, qd, qdd, sym.gravity)[1]],
                            ["q", "qd", "qdd", "p"], ["N"]),
            )  # fmt: skip
        return _PLANT[cls][0]

    @classmethod
    def virtual_constraint_defaults(cls, degree: int) -> dict[str, float]:
        """Bézier coefficients (rad) of degree ``degree`` that are this model's fixed
        constraints exactly: with ``θ = θ1`` from ``θ⁺ = −θ_i`` to ``θ⁻ = θ_i``, the swing leg
        ``θ2 = −θ1`` is linear in ``s`` (``α_k = θ_i (1 − 2k/M)``) and the torso constant
        (``α_k = θ3d = π/8``); ``ω_n = 5``, ``ζ = 1.1`` as issue 20's (rad/s, 1)."""
        ti = math.pi / 8
        out = {"omega_n": 5.0, "zeta": 1.1, "theta_plus": -ti, "theta_minus": ti}
        for k in range(degree + 1):
            out[f"alpha_swing_{k}"] = ti * (1 - 2 * k / degree)
            out[f"alpha_torso_{k}"] = math.pi / 8
        return out

    @classmethod
    def ground_reaction(cls) -> ca.Function:
        """``ground_reaction(q, qd, qdd, p) -> N``: the normal force of the ground on the
        stance foot (N) for any acceleration ``q̈`` (Newton's law of the point masses), the
        unilateral condition ``N ≥ 0`` of a controller of one's own."""
        cls.manipulator()
        return _PLANT[cls][1]

    # -- outputs of the closed loop ----------------------------------------------------------
    def _function(self, name: str) -> ca.Function:
        self.structure()
        return _FUNCTIONS[type(self)][name]

    def torques(self, x: np.ndarray) -> np.ndarray:
        """The controller's torques ``u = (u1, u2)`` at state ``x`` (N·m): ``u1`` between the
        stance leg and the torso, ``u2`` between the swing leg and the torso (:attr:`torque_names`).

        Parameters
        ----------
        x : numpy.ndarray
            A state (6,) or states (6, N), in :data:`STATE_NAMES` order (rad, rad/s).

        Returns
        -------
        numpy.ndarray
            ``(2,)`` or ``(2, N)`` torques (N·m).
        """
        X = np.asarray(x, dtype=float)
        out = np.asarray(self._function("torques")(X.reshape(6, -1), self.p), dtype=float)
        return out.reshape(2) if X.ndim == 1 else out

    def outputs(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The virtual constraints ``h(q) = [θ3 − θ3d, θ1 + θ2 − δ]`` (rad) and their rates
        ``L_f h = H q̇`` (rad/s) at state ``x`` (6,): both zero on the constraint surface."""
        h, dh = self._function("outputs")(np.asarray(x, dtype=float), self.p)
        return np.asarray(h, dtype=float).ravel(), np.asarray(dh, dtype=float).ravel()

    def energy(self, x: np.ndarray) -> float:
        """Total energy ``E = ½ q̇ᵀ D q̇ + V`` (J; V relative to the stance foot's height)."""
        return float(self._function("energy")(np.asarray(x, dtype=float), self.p))

    def power(self, x: np.ndarray) -> float:
        """Power of the torques ``q̇ᵀ B u`` (W): ``dE/dt`` along the closed loop."""
        return float(self._function("power")(np.asarray(x, dtype=float), self.p))

    def max_torque(self, cycle: Any, states: Sequence[np.ndarray] | None = None) -> float:
        """``max |u_i|`` over a gait (N·m), on the orbit's dense samples.

        Parameters
        ----------
        cycle : LimitCycle
            A gait of this model (``find_limit_cycle``).
        states : sequence of arrays, optional
            States (one per column) to take the maximum on instead of ``cycle.orbit``, e.g. an
            independent simulation re-sampled with ``n`` points per step:
            ``[arc.sample(n)[1] for arc in gaitopt.simulate(model, cycle.x,
            steps=cycle.steps).arcs]`` (the model does not simulate: the simulation resolves
            models through the registry, which imports this module).
        """
        arrays = [arc.x for arc in cycle.orbit] if states is None else list(states)
        return float(max(np.max(np.abs(self.torques(X))) for X in arrays))

    def impact_velocities(self, x_minus: np.ndarray) -> np.ndarray:
        """The plastic impact in the old labels, before the swap: ``q̇⁺`` (rad/s) from the state
        ``x⁻`` just before it (the extended model's solution, for the momentum checks)."""
        return np.asarray(
            self._function("impact")(np.asarray(x_minus, dtype=float), self.p), dtype=float
        ).ravel()

    def existence_note(self) -> str | None:
        return (
            "the closed loop walks only where the zero dynamics carry the stance leg from "
            "−impact_angle to +impact_angle: with too little energy after the impact the walker "
            "falls back (Grizzle et al. 2001, the zero dynamics' energy condition)"
        )


_FUNCTIONS: dict[type, dict[str, ca.Function]] = {}
_PLANT: dict[type, tuple[ca.Function, ca.Function]] = {}


def _functions(sym, x, q, qd, loop, geo, post) -> dict[str, ca.Function]:
    """Numeric functions of the closed loop (torques, outputs, energy, power, impact)."""
    D, G = loop["D"], loop["G"]
    del G
    r, m, mh, mt, ell, g = _grizzle(sym)
    # V with ∂V/∂q = G (Grizzle et al. 2001's G is the gradient of this potential).
    V = (mh + mt + 3 * m / 2) * g * r * ca.cos(q[0]) - (m * g * r / 2) * ca.cos(q[1])
    V = V + mt * g * ell * ca.cos(q[2])
    energy = 0.5 * ca.dot(qd, D @ qd) + V
    power = ca.dot(qd, ca.DM(INPUT_MATRIX) @ loop["u"])
    p = sym.p
    return {
        "torques": ca.Function("torques", [x, p], [loop["u"]], ["x", "p"], ["u"]),
        "outputs": ca.Function("outputs", [x, p], [loop["h"], loop["dh"]], ["x", "p"], ["h", "dh"]),
        "energy": ca.Function("energy", [x, p], [energy], ["x", "p"], ["E"]),
        "power": ca.Function("power", [x, p], [power], ["x", "p"], ["P"]),
        "impact": ca.Function("impact", [x, p], [post], ["x", "p"], ["qd_plus"]),
        "decoupling": ca.Function(
            "decoupling", [x, p], [ca.det(loop["decoupling"])], ["x", "p"], ["det"]
        ),
        "terms": ca.Function(
            "terms", [x, p], [loop["D"], loop["C"], loop["G"]], ["x", "p"], ["D", "C", "G"]
        ),  # fmt: skip
    }
