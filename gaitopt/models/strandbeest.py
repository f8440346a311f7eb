"""Jansen's Strandbeest as a hybrid walker: one degree of freedom, the crank angle.

The machine is Deits' and Drake's (``examples/multibody/strandbeest``): six leg pairs on one
crank at phases 0, 2π/3, 4π/3, π/3, π, 5π/3 (a pair: a leg and its mirror image about the
vertical through the crank axle, sharing the crank pin), Jansen's holy numbers at 0.01 m per unit
(:mod:`gaitopt.linkage`), every link a uniform PVC rod of 0.476 kg/m, the frame of each pair the
rods ``2a`` and ``l`` and its crank ``m``.

Model (stated assumptions).  The frame stays parallel to the ground (it translates; its pitch
is held by the many feet, as on Deits' machine); the lowest foot is the stance foot, a pin without
slip; everything else follows the crank angle θ.  With the stance foot ``s`` at ``F_s(θ)``
relative to the crank axle, the frame moves with ``v = w_s θ̇``, ``w_s = −dF_s/dθ``, and a rod
with ends moving at ``P' θ̇``, ``Q' θ̇`` relative to the frame has kinetic energy
``(m/6)(|P'+w|² + (P'+w)·(Q'+w) + |Q'+w|²) θ̇²``.  Summed over the 133 rods,

    T = ½ M_s(θ) θ̇²,  M_s = m |w_s|² + 2 w_s·S(θ) + M_rel(θ),

with ``m`` the total mass, ``S = Σ m_r (P'+Q')/2`` and ``M_rel = Σ (m_r/3)(|P'|² + P'·Q' + |Q'|²)``.
On a slope γ (x along the ground; the machine walks towards −x, downhill, when θ increases):
``V_s = m g (sin γ (X_cm − X_s) + cos γ (Y_cm − Y_s))``.  Lagrange's equation with a constant
crank torque τ: ``M_s θ̈ + ½ M_s' θ̇² + V_s' = τ``; ``E = ½ M_s θ̇² + V_s − τ θ`` is conserved.

Support is handed from foot to foot: when the next foot comes down to the stance foot's height
(guard ``y_next − y_s`` falls through 0), a plastic impact pins it and frees the other.  The
impulses (new contact, pitch hold) do no work on motions compatible with the new contact, so
``G_nᵀ M₃ (q̇⁺ − q̇⁻) = 0`` with ``q = (frame x, frame y, θ)``, ``G = (w, 1)``:

    θ̇⁺ = ρ θ̇⁻,  ρ = (m w_n·w_s + S·(w_n + w_s) + M_rel) / M_n

(the rimless wheel's ``cos 2α``).  The lower envelope of the twelve feet repeats every π/3 with a
relabelling of the feet; within one period support passes through the handovers listed by
:func:`contact_sequence` (computed from the geometry at build time).  One phase per support
interval; the last handover relabels ``θ ↦ θ − π/3`` into the first phase.  Rocking back, the
previous foot takes over (a backward handover with its own impact).

Passive, down a slope, this is a generalised rimless wheel; driven by τ on level ground it walks
steadily.  Closed form (:meth:`Strandbeest.closed_form`): over a support interval the energy
equation gives ``θ̇²`` at its end from its start, each impact multiplies by ρ², so the map of
``e = θ̇²`` over a period is affine, ``e ↦ A e + B``; the gait is ``e* = B/(1 − A)`` and its
multiplier is ``A`` (computed there with the linkage's rootfinder, independently of the
closed-form dyads used here).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ..hybrid import Constraint, HybridModel, Phase, Section, Symbols, Transition
from ..parameters import gravity_parameter, parameter
from .quantities import slope_parameter

__all__ = ["Strandbeest", "contact_sequence", "RODS"]

#: The rods of one leg: (end, end, link letter).
RODS = (
    ("pivot", "upper", "b"),
    ("pivot", "lower", "c"),
    ("pivot", "back", "d"),
    ("upper", "back", "e"),
    ("back", "knee", "f"),
    ("lower", "knee", "g"),
    ("knee", "foot", "h"),
    ("lower", "foot", "i"),
    ("pin", "upper", "j"),
    ("pin", "lower", "k"),
)
_POINTS = ("axle", "pin", "pivot", "upper", "lower", "back", "knee", "foot")
_PERIOD = math.pi / 3  # the six pairs' envelope repeats every π/3 (relabelling the feet)
_DENSITY = 0.476  # kg/m, Deits' PVC (Drake: 0.476212462)


def _linkage():
    """:mod:`gaitopt.linkage`, imported on first use (it imports SciPy's optimisers, which
    ``import gaitopt`` does not need)."""
    from .. import linkage

    return linkage


# -- geometry and inertia of the machine ---------------------------------------------------------
@lru_cache(maxsize=1)
def _leg() -> ca.Function:
    """``leg(θ) -> 2×8`` points of one leg at its holy numbers (m, relative to the crank axle)."""
    t = ca.SX.sym("t")
    pts = _linkage().closed_form_joints(t, ca.DM(_linkage().JansenLinkage().p))
    return ca.Function("leg", [t], [ca.horzcat(*[pts[n] for n in _POINTS])])


@lru_cache(maxsize=1)
def _leg_terms() -> ca.Function:
    """One leg (and its pair's crank and frame) at pin angle t, per unit density: the foot and
    its first two derivatives, ``S``, ``M_rel`` (with derivatives) and the first moment
    ``Σ m_r (P + Q)/2`` (with two derivatives), from the closed-form dyads (SX)."""
    t = ca.SX.sym("t")
    pts = _leg()(t)
    d_pts = ca.jacobian(ca.vec(pts), t).reshape((2, 8))
    lengths = _linkage().JansenLinkage().params
    S, M_rel, moment = ca.SX.zeros(2, 1), ca.SX(0), ca.SX.zeros(2, 1)
    for p_name, q_name, letter in RODS:
        m_r = lengths[letter]
        i, j = _POINTS.index(p_name), _POINTS.index(q_name)
        P, Q, dP, dQ = pts[:, i], pts[:, j], d_pts[:, i], d_pts[:, j]
        S += m_r * (dP + dQ) / 2
        M_rel += m_r / 3 * (ca.dot(dP, dP) + ca.dot(dP, dQ) + ca.dot(dQ, dQ))
        moment += m_r * (P + Q) / 2
    foot = pts[:, 7]
    d_foot = ca.jacobian(foot, t)
    d_moment = ca.jacobian(moment, t)
    outs = [
        foot, d_foot, ca.jacobian(d_foot, t), S, ca.jacobian(S, t), M_rel,
        ca.jacobian(M_rel, t), moment, d_moment, ca.jacobian(d_moment, t),
    ]  # fmt: skip
    return ca.Function("leg_terms", [t], outs)


def _leg_mass() -> float:
    """Mass of one leg's ten rods per unit density (m)."""
    lengths = _linkage().JansenLinkage().params
    return sum(lengths[letter] for _, _, letter in RODS)


def _pair_extra_mass() -> float:
    """Crank m and frame rods 2a and l of one pair, per unit density (m)."""
    lengths = _linkage().JansenLinkage().params
    return lengths["m"] + 2 * lengths["a"] + lengths["l"]


@lru_cache(maxsize=1)
def _machine() -> ca.Function:
    """``machine(θ) -> (F, F', F'', S, S', M_rel, M_rel', R, R', R'')`` of the six-pair machine
    per unit density (R, the centre of mass, is density-free): feet 2×12 (legs at θ + φ, then
    mirrors), derivatives in θ.  An MX function calling the one-leg SX function twelve times, so
    that derivatives are generated once for one leg."""
    theta = ca.MX.sym("theta")
    leg = _leg_terms()
    reflect = ca.DM([-1.0, 1.0])
    feet = [[], [], []]
    S, dS = ca.MX.zeros(2, 1), ca.MX.zeros(2, 1)
    M_rel, dM_rel = ca.MX(0), ca.MX(0)
    mom, dmom, ddmom = ca.MX.zeros(2, 1), ca.MX.zeros(2, 1), ca.MX.zeros(2, 1)
    for mirror in (False, True):
        for ph in _linkage().SIX_PAIR_PHASES:
            t = math.pi - theta - ph if mirror else theta + ph
            F, dF, ddF, S_, dS_, M_, dM_, m0, m1, m2 = leg(t)
            if mirror:  # positions reflect; each θ-derivative also changes sign (t = π − θ − φ)
                F, dF, ddF = reflect * F, -reflect * dF, reflect * ddF
                S_, dS_, dM_ = -reflect * S_, reflect * dS_, -dM_
                m0, m1, m2 = reflect * m0, -reflect * m1, reflect * m2
            feet[0].append(F)
            feet[1].append(dF)
            feet[2].append(ddF)
            S, dS, M_rel, dM_rel = S + S_, dS + dS_, M_rel + M_, dM_rel + dM_
            mom, dmom, ddmom = mom + m0, dmom + m1, ddmom + m2
    lengths = _linkage().JansenLinkage().params
    a, l, m = lengths["a"], lengths["l"], lengths["m"]  # noqa: E741
    # each pair's crank (axle to pin, a uniform rod) and its frame
    for ph in _linkage().SIX_PAIR_PHASES:
        u = ca.vertcat(ca.cos(theta + ph), ca.sin(theta + ph))
        du = ca.vertcat(-ca.sin(theta + ph), ca.cos(theta + ph))
        S, dS = S + m * (m * du) / 2, dS - m * (m * u) / 2
        M_rel = M_rel + m / 3 * m**2
        mom, dmom, ddmom = mom + m * (m * u) / 2, dmom + m * (m * du) / 2, ddmom - m * (m * u) / 2
        mom = mom + 2 * a * ca.vertcat(0, -l) + l * ca.vertcat(0, -l / 2)
    mass = 12 * _leg_mass() + 6 * _pair_extra_mass()
    outs = [ca.horzcat(*f) for f in feet] + [S, dS, M_rel, dM_rel, mom / mass, dmom / mass,
                                             ddmom / mass]  # fmt: skip
    return ca.Function("machine", [theta], outs)


@lru_cache(maxsize=1)
def _feet() -> ca.Function:
    """``feet(θ) -> (2×12 positions, 2×12 dF/dθ)`` of the twelve feet (m, m/rad)."""
    t = ca.MX.sym("t")
    out = _machine()(t)
    return ca.Function("feet", [t], [out[0], out[1]])


# -- the support phases' functions of θ as Chebyshev series ---------------------------------------
#: Each series covers its support interval and this much (rad) on either side: a phase ends at its
#: guards inside the interval (forward or backward handover), overshooting it by one integration
#: step at most.
SERIES_MARGIN = 0.2
#: Series degrees tried, lowest first, until the off-grid check of :func:`support_series` holds.
SERIES_DEGREES = (40, 48, 56, 64, 80, 96, 128)
#: Largest error of a series at off-grid points, relative to the quantity's largest magnitude on
#: the interval (the tests check 1e-10 against the exact linkage at other points).  The guards,
#: differences of two foot heights of about 0.5 m that vanish at the handovers, are measured
#: against :data:`GUARD_SCALE` instead: their rounding floor is ~1e-16 m, not relative to them.
SERIES_TOLERANCE = 1e-12
GUARD_SCALE = 0.1  # m
#: The quantities of one support phase (per unit density where a mass enters): M_s, dM_s/dθ, the
#: centre of mass's rate relative to the stance foot d(R − F_s)/dθ (x, y) and d²(R − F_s)/dθ² (y,
#: for the normal force), the forward guard and impact ratio ρ, the backward guard and ρ (see
#: :class:`Strandbeest`).
SERIES_QUANTITIES = (
    "M", "dM", "d_rel_x", "d_rel_y", "dd_rel_y", "guard", "rho", "guard_back", "rho_back",
)  # fmt: skip


def _support_exact(k: int) -> ca.Function:
    """``exact_k(θ) -> 9×1``: :data:`SERIES_QUANTITIES` of support phase ``k`` from the
    closed-form dyads of all twelve legs (MX)."""
    feet_seq, _ = contact_sequence()
    K = len(feet_seq)
    s, nxt, prv = feet_seq[k], feet_seq[(k + 1) % K], feet_seq[(k - 1) % K]
    shift_fwd = _PERIOD if k == K - 1 else 0.0
    shift_back = -_PERIOD if k == 0 else 0.0
    theta = ca.MX.sym("theta")
    mass = 12 * _leg_mass() + 6 * _pair_extra_mass()
    F, dF, ddF, S, dS, M_rel, dM_rel, _, dR, ddR = _machine()(theta)
    F_ahead, dF_ahead = _machine()(theta - shift_fwd)[:2]
    F_behind, dF_behind = _machine()(theta - shift_back)[:2]
    w, dw = -dF[:, s], -ddF[:, s]
    M = mass * ca.dot(w, w) + 2 * ca.dot(w, S) + M_rel
    dM = 2 * mass * ca.dot(w, dw) + 2 * (ca.dot(dw, S) + ca.dot(w, dS)) + dM_rel
    d_rel = dR + w

    def ratio(new_w: Any) -> Any:  # ρ = G_nᵀ M₃ G_s / G_nᵀ M₃ G_n (plastic impact)
        M_n = mass * ca.dot(new_w, new_w) + 2 * ca.dot(new_w, S) + M_rel
        return (mass * ca.dot(new_w, w) + ca.dot(S, new_w + w) + M_rel) / M_n

    out = ca.vertcat(
        M, dM, d_rel, ddR[1] + dw[1], F_ahead[1, nxt] - F[1, s], ratio(-dF_ahead[:, nxt]),
        F_behind[1, prv] - F[1, s], ratio(-dF_behind[:, prv]),
    )  # fmt: skip
    return ca.Function(f"exact_{k}", [theta], [out])


def _interval(k: int) -> tuple[float, float]:
    """The interval (rad) of phase ``k``'s series: its support interval ± :data:`SERIES_MARGIN`."""
    _, angles = contact_sequence()
    return angles[k] - SERIES_MARGIN, angles[k + 1] + SERIES_MARGIN


@lru_cache(maxsize=8)
def support_series(k: int) -> tuple[np.ndarray, float, float, float]:
    """Chebyshev coefficients of support phase ``k``'s quantities on its interval.

    Interpolation at the Chebyshev points of the first kind of the lowest degree in
    :data:`SERIES_DEGREES` whose largest error at 200 other points of the interval, relative to
    each quantity's largest magnitude there (:data:`GUARD_SCALE` for the guards), is below
    :data:`SERIES_TOLERANCE` (the linkage is analytic in θ, so the series converge geometrically:
    degree 96 gives ~1e-14 on every phase; 64 leaves 4e-10 in M' near the longest intervals).

    Returns
    -------
    coefficients : numpy.ndarray
        ``9 × (degree + 1)``, rows in the order of :data:`SERIES_QUANTITIES`.
    a, b : float
        The interval (rad).
    error : float
        The largest relative error found at the check points.
    """
    a, b = _interval(k)
    exact = _support_exact(k)
    check = a + (b - a) * np.random.default_rng(k).uniform(size=200)
    want = np.asarray(exact.map(check.size)(check.reshape(1, -1)))
    scale = np.max(np.abs(want), axis=1, keepdims=True)
    for q in ("guard", "guard_back"):
        row = SERIES_QUANTITIES.index(q)
        scale[row] = max(scale[row, 0], GUARD_SCALE)
    for degree in SERIES_DEGREES:
        nodes = np.cos(np.pi * (np.arange(degree + 1) + 0.5) / (degree + 1))
        thetas = 0.5 * (a + b) + 0.5 * (b - a) * nodes
        values = np.asarray(exact.map(nodes.size)(thetas.reshape(1, -1)))
        coefficients = np.polynomial.chebyshev.chebfit(nodes, values.T, degree).T
        u = (2 * check - (a + b)) / (b - a)
        got = np.polynomial.chebyshev.chebval(u, coefficients.T)  # 9 × 200
        error = float(np.max(np.abs(got - want) / scale))
        if error < SERIES_TOLERANCE:
            return coefficients, a, b, error
    raise RuntimeError(f"strandbeest: support phase {k}'s series did not converge ({error:.2g})")


def _series(theta: Any, k: int) -> dict[str, Any]:
    """Support phase ``k``'s quantities at symbolic ``theta`` from their series: the Chebyshev
    polynomials ``T_j(u)`` once by their recurrence ``T_{j+1} = 2u T_j − T_{j−1}``, shared by the
    nine sums (a smaller graph, and so smaller compiled kernels, than a Clenshaw sum each)."""
    coefficients, a, b, _ = support_series(k)
    u = (2 * theta - (a + b)) / (b - a)
    T = [ca.SX(1.0) if isinstance(u, ca.SX) else 1.0, u]
    while len(T) < coefficients.shape[1]:
        T.append(2 * u * T[-1] - T[-2])
    basis = ca.vertcat(*T[: coefficients.shape[1]])
    values = ca.mtimes(ca.DM(coefficients), basis)
    return {q: values[i] for i, q in enumerate(SERIES_QUANTITIES)}


@lru_cache(maxsize=1)
def contact_sequence() -> tuple[tuple[int, ...], tuple[float, ...]]:
    """The stance feet over one period and the handover angles.

    Returns
    -------
    feet : tuple of int
        Stance foot of each support interval (0–5: legs at the six phases; 6–11: their
        mirrors), starting with the one after the first handover at or after θ = 0.
    angles : tuple of float
        The handover angles (rad), one more than ``feet``: interval k is
        ``[angles[k], angles[k+1]]``, and ``angles[-1] = angles[0] + π/3``.

    The lowest foot is found on a dense grid and each handover refined to machine precision
    (Brent's method on the difference of the two feet's heights).
    """
    feet = _feet().map(7201)
    grid = np.linspace(0.0, 2 * math.pi, 7201)
    heights = np.asarray(feet(grid.reshape(1, -1))[0])[1].reshape(7201, 12)
    low = np.argmin(heights, axis=1)
    switches = [n for n in range(len(grid) - 1) if low[n + 1] != low[n]]

    from scipy.optimize import brentq

    def height(t: float, q: int) -> float:
        return float(np.asarray(_feet()(t)[0])[1, q])

    angles, stance = [], []
    for n in switches:
        a, b = int(low[n]), int(low[n + 1])
        t = brentq(lambda s, a=a, b=b: height(s, b) - height(s, a), grid[n], grid[n + 1],
                   xtol=1e-15)  # fmt: skip
        angles.append(t)
        stance.append(b)
        if t >= angles[0] + _PERIOD - 1e-9:
            break
    return tuple(stance[:-1]), (*angles[:-1], angles[0] + _PERIOD)


# -- the model -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Strandbeest(HybridModel):
    """Six-pair Strandbeest walker: state ``theta`` (crank angle, rad), ``theta_dot`` (rad/s)."""

    name = "strandbeest"
    #: For ``gaitopt list`` without a build (checked against it).
    declared_states = ("theta", "theta_dot")
    declared_coordinates = ("theta_dot",)
    declared_section_doc = "just after the handover to foot 10: theta = 0 rad"
    title = "Strandbeest (Jansen's linkage, six pairs)"
    reference = "Jansen 2007; Deits, Drake examples/multibody/strandbeest; Tedrake, rimless wheel"
    mesh = (3, 4)
    state_units = {"theta": "rad", "theta_dot": "rad/s"}  # for axis labels
    #: The drawing: every rod of the twelve legs (:data:`RODS`) and each pair's crank, through
    #: the joints ``leg{i}_{joint}`` that each phase declares (legs 0–5 at θ + φ, 6–11 their
    #: mirror images), so that the animation shows the linkage itself.
    drawing = tuple(
        line
        for i in range(12)
        for line in (
            *((f"leg{i}_{a}", f"leg{i}_{b}") for a, b, _ in RODS),
            ("axle", f"leg{i}_pin"),
        )
    )

    slope: float = slope_parameter(
        0.02,
        "chosen: the machine rolls down it passively",
        (-0.5, 0.5),
        doc="ground slope γ (downhill positive, towards −x)",
    )
    torque: float = parameter(
        0.0, unit="N*m", low=-1000.0, high=1000.0,
        doc="constant crank torque τ (driving the crank forward)", source="passive by default",
    )  # fmt: skip
    gravity: float = gravity_parameter()
    density: float = parameter(
        _DENSITY, unit="kg/m", low=0.0, high=100.0, low_open=True,
        doc="linear density of the links (uniform rods)",
        source="Deits' PVC pipe, Drake examples/multibody/strandbeest (0.476212462 kg/m)",
    )  # fmt: skip

    @classmethod
    def build(cls, sym: Symbols) -> tuple[tuple[Phase, ...], Section]:
        feet_seq, angles = contact_sequence()
        K = len(feet_seq)
        # MX functions around the machine's one-leg SX function (see _machine): small graphs
        # whose derivatives CasADi generates once for one leg.
        names = [spec.name for spec in cls.parameter_specs()]
        x, u, p = ca.MX.sym("x", 2), ca.MX.sym("u", len(cls.inputs)), ca.MX.sym("p", len(names))
        theta, theta_dot = x[0], x[1]
        gamma, tau, g, density = (p[names.index(n)] for n in ("slope", "torque", "gravity",
                                                               "density"))  # fmt: skip

        def function(name: str, expr: Any) -> ca.Function:
            return ca.Function(name, [x, u, p], [expr], ["x", "u", "p"], [name])

        def machine(t: Any) -> dict[str, Any]:
            F, dF, ddF, S, dS, M_rel, dM_rel, R, dR, ddR = _machine()(t)
            mass = 12 * _leg_mass() + 6 * _pair_extra_mass()
            return dict(F=F, dF=dF, ddF=ddF, S=S, dS=dS, M_rel=M_rel, dM_rel=dM_rel, R=R,
                        dR=dR, ddR=ddR, mass=mass)  # fmt: skip

        def stance(mc: dict, q: int) -> dict[str, Any]:
            """Inertia, potential and their θ-derivatives with foot q pinned (per density)."""
            w, dw = -mc["dF"][:, q], -mc["ddF"][:, q]
            M = mc["mass"] * ca.dot(w, w) + 2 * ca.dot(w, mc["S"]) + mc["M_rel"]
            dM = (
                2 * mc["mass"] * ca.dot(w, dw)
                + 2 * (ca.dot(dw, mc["S"]) + ca.dot(w, mc["dS"]))
                + mc["dM_rel"]
            )
            rel = mc["R"] - mc["F"][:, q]  # centre of mass relative to the stance foot
            d_rel, dd_rel = mc["dR"] + w, mc["ddR"] + dw
            grav = g * mc["mass"]  # potential per unit density: m g (sin γ x + cos γ y)
            V = grav * (ca.sin(gamma) * rel[0] + ca.cos(gamma) * rel[1])
            dV = grav * (ca.sin(gamma) * d_rel[0] + ca.cos(gamma) * d_rel[1])
            return dict(w=w, M=M, dM=dM, V=V, dV=dV, rel=rel, d_rel=d_rel, dd_rel=dd_rel)

        here = machine(theta)
        # Drawing frame: the slope frame turned by γ and mirrored about the vertical, so that the
        # machine walks downhill towards +x on the ground y = −x tan γ, the convention of
        # gaitopt.animation (the model's own x points uphill).
        rotation = ca.vertcat(
            ca.horzcat(-ca.cos(gamma), ca.sin(gamma)), ca.horzcat(ca.sin(gamma), ca.cos(gamma))
        )
        # Every joint of the twelve legs relative to the crank axle (the drawing; legs 0–5 at
        # pin angle θ + φ, 6–11 mirrored about the vertical, as in _machine).
        reflect = ca.DM([-1.0, 1.0])
        legs, joint_names = [], []
        for i, (mirror, ph) in enumerate(
            (mirror, ph) for mirror in (False, True) for ph in _linkage().SIX_PAIR_PHASES
        ):
            pts = _leg()(math.pi - theta - ph if mirror else theta + ph)
            for j, joint in enumerate(_POINTS[1:], start=1):  # the axle is drawn once
                legs.append(reflect * pts[:, j] if mirror else pts[:, j])
                joint_names.append(f"leg{i}_{joint}")
        phases = []
        for k in range(K):
            s, nxt, prv = feet_seq[k], feet_seq[(k + 1) % K], feet_seq[(k - 1) % K]
            # Beyond the period's ends the next/previous foot is phase 0's/the last phase's
            # stance foot relabelled: its state at θ is that foot's at θ ∓ π/3.
            shift_fwd = _PERIOD if k == K - 1 else 0.0
            shift_back = -_PERIOD if k == 0 else 0.0
            st = stance(here, s)
            # The flow, guards and resets from the phase's Chebyshev series of M_s, M_s', the
            # centre of mass's rate and the guards and ratios (support_series: within 1e-12 of
            # the linkage), as SX: twelve legs in every flow evaluation made the shooting slow.
            xs, (th, th_dot) = sym.states("theta", "theta_dot")
            ser = _series(th, k)
            dV = (
                sym.gravity
                * (12 * _leg_mass() + 6 * _pair_extra_mass())
                * (ca.sin(sym.slope) * ser["d_rel_x"] + ca.cos(sym.slope) * ser["d_rel_y"])
            )
            # M θ̈ + ½ M' θ̇² + V' = τ (Lagrange, one coordinate); M, V per unit density.
            accel = (sym.torque / sym.density - dV - 0.5 * ser["dM"] * th_dot**2) / ser["M"]
            flow = sym.function("flow", xs, ca.vertcat(th_dot, accel))
            ahead, behind = machine(theta - shift_fwd), machine(theta - shift_back)
            forward = Transition(
                name="handover",
                guard=sym.function("guard", xs, ser["guard"]),
                direction=-1,
                reset=sym.function("reset", xs, ca.vertcat(th - shift_fwd, ser["rho"] * th_dot)),
                target=(k + 1) % K,
                foothold="next_foot",
                doc="the next foot comes down to the stance foot's height; plastic impact "
                "θ̇⁺ = ρ θ̇⁻, ρ = G_nᵀM₃G_s / G_nᵀM₃G_n" + ("; θ ↦ θ − π/3" if shift_fwd else ""),
            )
            backward = Transition(
                name="backward handover",
                guard=sym.function("guard", xs, ser["guard_back"]),
                direction=-1,
                reset=sym.function(
                    "reset", xs, ca.vertcat(th - shift_back, ser["rho_back"] * th_dot)
                ),
                target=(k - 1) % K,
                foothold="previous_foot",
                doc="rocking back, the previous foot comes down to the stance foot's height",
            )
            energy = ca.Function(
                "energy",
                [x, p],
                [density * (0.5 * st["M"] * theta_dot**2 + st["V"]) - tau * theta],
                ["x", "p"],
                ["energy"],
            )
            # Normal force: m (ÿ_cm + g cos γ), the stance foot fixed (N), from the series too
            # (a simulation evaluates it at every step, as an event).
            a_cm_y = ser["dd_rel_y"] * th_dot**2 + ser["d_rel_y"] * accel
            mass = 12 * _leg_mass() + 6 * _pair_extra_mass()
            normal = sym.density * mass * (a_cm_y + sym.gravity * ca.cos(sym.slope))
            push = Constraint(
                "stance foot pushes on the ground",
                sym.function("constraint", xs, normal),
                "stance foot lifts off",
                unit="N",
                source="a ground contact can only push (unilateral normal force)",
            )
            # Drawing points, world frame (the drawing frame above), stance foot at 0.
            foot = here["F"][:, s]
            drawn = [
                ca.mtimes(rotation, v - foot)
                for v in (foot, ahead["F"][:, nxt], behind["F"][:, prv])
            ]
            joints = [ca.mtimes(rotation, v - foot) for v in legs]
            points = ca.Function("points", [x, p], [ca.horzcat(-ca.mtimes(rotation, foot),
                                                               *drawn, *joints)])  # fmt: skip
            phases.append(
                Phase(
                    f"support {k + 1} (foot {s})",
                    ("theta", "theta_dot"),
                    flow,
                    (forward, backward),
                    {"energy": energy},
                    points=points,
                    point_names=("axle", "foot", "next_foot", "previous_foot", *joint_names),
                    constraints=(push,),
                )
            )
        s_ = ca.SX.sym("s", 1)
        section = Section(
            ("theta_dot",),
            sym.lift(s_, ca.vertcat(angles[0], s_)),
            f"just after the handover to foot {feet_seq[0]}: theta = {angles[0]:.12g} rad",
        )
        return tuple(phases), section

    def default_start(self) -> dict[str, float]:
        """20 % above the gait's post-handover rate (the fixed point of the affine energy map,
        evaluated with the model's own energy and resets), or 2 rad/s where it has none."""
        e = self.energy_map_fixed_point()
        return {"theta_dot": 1.2 * math.sqrt(e) if e is not None else 2.0}

    def energy_map_fixed_point(self) -> float | None:
        """``e* = B/(1 − A)`` (rad²/s²) of the affine map of ``θ̇²`` over a period, from the
        model's energy functions (``M = 2(E(θ, 1) − E(θ, 0))``) and impact resets; None if the
        map has no positive fixed point (existence along the intervals is not checked here)."""
        _, angles = contact_sequence()
        p, u = self.p, self.nominal_input()
        A, B = 1.0, 0.0
        for k, phase in enumerate(self.phases):
            energy = phase.conserved["energy"]

            def parts(t, energy=energy):
                e0 = float(energy([t, 0.0], p))
                return 2 * (float(energy([t, 1.0], p)) - e0), e0

            (M_a, W_a), (M_b, W_b) = parts(angles[k]), parts(angles[k + 1])
            rho = float(phase.transitions[0].reset([angles[k + 1], 1.0], u, p)[1])
            A, B = rho**2 * A * M_a / M_b, rho**2 * (B * M_a + 2 * (W_a - W_b)) / M_b
        if not (A < 1 and B > 0):
            return None
        return B / (1 - A)

    def existence_note(self) -> str | None:
        """What the energy-plus-impact closed form says about the gait, if it does not exist."""
        cf = self.closed_form()
        return None if cf["exists"] else f"closed form: {cf['reason']}"

    def closed_form(self, samples: int = 24) -> dict[str, Any]:
        """The gait by energy and impacts (see the module docstring), computed with the
        linkage's rootfinder (not the model's closed-form dyads) and quadrature.

        Returns
        -------
        dict
            ``exists``; ``theta_dot`` (rad/s, just after the handover that starts the period);
            ``multiplier``; ``period`` (s, ∫dθ/θ̇ by Gauss–Legendre quadrature);
            ``min_theta_dot`` (rad/s, on ``samples`` points per support interval); ``ratios``
            (ρ of each handover); ``reason`` when it does not exist.
        """
        return _closed_form(self.slope, self.torque, self.gravity, self.density, samples)


# -- the closed form, by the linkage's rootfinder ------------------------------------------------
def _machine_numeric(turn, theta: float, density: float):
    """(mass, S, M_rel, R, feet F (2×12), dF (2×12)) at θ from the rootfinder (numpy)."""
    lk = turn.linkage
    reflect = np.array([-1.0, 1.0])
    legs = []
    for ph in _linkage().SIX_PAIR_PHASES:
        z, dz = turn.at(theta + ph)
        t = theta + ph
        pts = {"pin": lk.pin(t), "pivot": lk.pivot, "axle": np.zeros(2)}
        dpts = {"pin": lk.m * np.array([-math.sin(t), math.cos(t)]), "pivot": np.zeros(2)}
        for n, name in enumerate(("upper", "lower", "back", "knee", "foot")):
            pts[name], dpts[name] = z[n], dz[n]
        legs.append((pts, dpts))
    for ph in _linkage().SIX_PAIR_PHASES:
        t = math.pi - theta - ph
        z, dz = turn.at(t)
        pts = {"pin": reflect * lk.pin(t), "pivot": reflect * lk.pivot}
        dpts = {"pin": -reflect * lk.m * np.array([-math.sin(t), math.cos(t)]),
                "pivot": np.zeros(2)}  # fmt: skip
        for n, name in enumerate(("upper", "lower", "back", "knee", "foot")):
            pts[name], dpts[name] = reflect * z[n], -reflect * dz[n]
        legs.append((pts, dpts))
    mass, S, M_rel, moment = 0.0, np.zeros(2), 0.0, np.zeros(2)
    for pts, dpts in legs:
        for p_name, q_name, letter in RODS:
            m_r = density * getattr(lk, letter)
            P, Q, dP, dQ = pts[p_name], pts[q_name], dpts[p_name], dpts[q_name]
            S += m_r * (dP + dQ) / 2
            M_rel += m_r / 3 * (dP @ dP + dP @ dQ + dQ @ dQ)
            moment += m_r * (P + Q) / 2
            mass += m_r
    for pts, dpts in legs[:6]:
        m_c = density * lk.m
        S += m_c * dpts["pin"] / 2
        M_rel += m_c / 3 * dpts["pin"] @ dpts["pin"]
        moment += m_c * pts["pin"] / 2
        moment += density * 2 * lk.a * np.array([0, -lk.l]) + density * lk.l * np.array(
            [0, -lk.l / 2]
        )
        mass += m_c + density * (2 * lk.a + lk.l)
    F = np.array([pts["foot"] for pts, _ in legs]).T
    dF = np.array([dpts["foot"] for _, dpts in legs]).T
    return mass, S, M_rel, moment / mass, F, dF


@lru_cache(maxsize=64)
def _closed_form(slope, torque, gravity, density, samples) -> dict[str, Any]:
    from scipy.optimize import brentq

    turn = _linkage().JansenLinkage().turn(720)
    feet_seq, _ = contact_sequence()
    K = len(feet_seq)

    def feet_y(t):
        return _machine_numeric(turn, t, density)[4][1]

    # Handover angles, independently: where consecutive stance feet have equal heights (the
    # foot before the first handover belongs to the previous period: its height at θ + π/3).
    _, approx = contact_sequence()
    angles = []
    for k in range(K):
        a, b = feet_seq[k - 1], feet_seq[k]
        shift = _PERIOD if k == 0 else 0.0

        def diff(t, a=a, b=b, shift=shift):
            return feet_y(t)[b] - feet_y(t + shift)[a]

        angles.append(brentq(diff, approx[k] - 1e-3, approx[k] + 1e-3, xtol=1e-14))
    angles.append(angles[0] + _PERIOD)

    def stance(t, q):
        mass, S, M_rel, R, F, dF = _machine_numeric(turn, t, density)
        w = -dF[:, q]
        M = mass * w @ w + 2 * w @ S + M_rel
        rel = R - F[:, q]
        V = mass * gravity * (math.sin(slope) * rel[0] + math.cos(slope) * rel[1])
        return M, V, w, mass, S, M_rel

    A, B = 1.0, 0.0  # e_end = A e_start + B over the period
    ratios, pieces = [], []
    for k in range(K):
        q = feet_seq[k]
        t_a, t_b = angles[k], angles[k + 1]
        M_a, V_a, *_ = stance(t_a, q)
        M_b, V_b, w_s, mass, S, M_rel = stance(t_b, q)
        work = 2 * (V_a - V_b + torque * (t_b - t_a))
        pieces.append((q, t_a, t_b, M_a, V_a))
        A, B = A * M_a / M_b, B * M_a / M_b + work / M_b
        # impact into the next foot at t_b (relabelled for the last interval)
        if k < K - 1:
            _, dF = _machine_numeric(turn, t_b, density)[4:]
            w_n = -dF[:, feet_seq[k + 1]]
        else:
            _, dF = _machine_numeric(turn, t_b - _PERIOD, density)[4:]
            w_n = -dF[:, feet_seq[0]]
        M_n = mass * w_n @ w_n + 2 * w_n @ S + M_rel
        rho = (mass * w_n @ w_s + S @ (w_n + w_s) + M_rel) / M_n
        ratios.append(rho)
        A, B = A * rho**2, B * rho**2
    out: dict[str, Any] = {"ratios": ratios, "angles": angles, "A": A, "B": B}
    if not (A < 1 and B > 0):
        return {**out, "exists": False, "theta_dot": None, "multiplier": None,
                "reason": f"no positive fixed point of e ↦ {A:.4g} e + {B:.4g}"}  # fmt: skip
    e = B / (1 - A)
    # Along each interval: θ̇(θ)² = (M_a e_a + 2 (V_a − V(θ) + τ (θ − θ_a))) / M(θ) > 0.
    period, lowest, e_k = 0.0, math.inf, e
    for k, (q, t_a, t_b, M_a, V_a) in enumerate(pieces):

        def rate2(t, q=q, t_a=t_a, M_a=M_a, V_a=V_a, e_k=e_k):
            M, V, *_ = stance(t, q)
            return (M_a * e_k + 2 * (V_a - V + torque * (t - t_a))) / M

        grid = np.linspace(t_a, t_b, samples)
        values = np.array([rate2(t) for t in grid])
        lowest = min(lowest, float(values.min()))
        if values.min() <= 0:
            break
        # ∫ dθ/θ̇ by Gauss–Legendre (the integrand is smooth and positive here).
        nodes, weights = np.polynomial.legendre.leggauss(16)
        half, mid = (t_b - t_a) / 2, (t_b + t_a) / 2
        terms = zip(nodes, weights, strict=True)
        period += half * sum(w / math.sqrt(rate2(mid + half * x)) for x, w in terms)
        e_k = ratios[k] ** 2 * rate2(t_b)
    if lowest <= 0:
        return {**out, "exists": False, "theta_dot": None, "multiplier": None,
                "min_theta_dot_squared": lowest,
                "reason": "the machine stops before the next handover (θ̇² reaches 0 inside a "
                "support interval): it rocks back"}  # fmt: skip
    return {**out, "exists": True, "theta_dot": math.sqrt(e), "multiplier": A,
            "period": period, "min_theta_dot": math.sqrt(lowest),
            "min_theta_dot_squared": lowest}  # fmt: skip
