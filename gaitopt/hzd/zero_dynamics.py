"""The hybrid zero dynamics and their one-dimensional restricted Poincaré map, in closed form.

Westervelt, Grizzle & Koditschek 2003 (IEEE TAC 48(1), §IV–V: Thms 2–3, eqs (38)–(50));
Westervelt et al. 2007, §5.4–5.5.  On the constraint surface ``q = Φ(θ)`` (:mod:`.invariance`)
the state is ``(θ, σ)``, with the angular-momentum-like coordinate

    σ = B⊥ D(q) q̇ = I(θ) θ̇,   I(θ) = B⊥ D(Φ(θ)) Φ'(θ),

``B⊥`` the row with ``B⊥ B = 0`` (for the three-link walker's absolute angles ``B⊥ = (1, 1, 1)``
and σ is the angular momentum about the stance foot, kg·m²/s).  Along the closed loop
``σ̇ = B⊥ (rhs(q, q̇, 0) + Ḋ q̇)`` (the torques drop out), on the surface ``κ_2(θ) + κ_3(θ) θ̇²``.
With ``ζ = σ²/2`` the zero dynamics are the *linear* equation ``dζ/dθ = 2 (κ_3/I) ζ + I κ_2``:
from ``ζ⁺`` at ``θ⁺``, ``ζ(θ) = E(θ) ζ⁺ + F(θ)``.  Where ``κ_3 ≡ 0`` (σ is the momentum of a
cyclic rotation, as for the three-link walker) ``E ≡ 1`` and ``F = −V_zero``,

    V_zero(θ) = −∫_{θ⁺}^{θ} I(ξ) κ_2(ξ) dξ     (WGK 2003, eq. (44); by quadrature here),

and the impact multiplies σ by ``δ_zero = B⊥ D(q⁺) q̇⁺ / I(θ⁻)`` (``q̇⁺ = Δ_q̇ Φ'(θ⁻)``, eq. (48)).
So the restricted Poincaré map on pre-impact ``ζ⁻`` is (eq. (50))

    ρ(ζ⁻) = δ_zero² E(θ⁻) ζ⁻ + F(θ⁻)   (= δ_zero² ζ⁻ − V_zero(θ⁻) when E ≡ 1),

with the fixed point ``ζ* = F(θ⁻)/(1 − δ_zero² E(θ⁻))``, exponentially stable iff its slope
``δ_zero² E(θ⁻) < 1``, and a gait only if ``ζ(θ) > 0`` for every θ of the step from
``ζ⁺ = δ_zero² ζ*`` (the walker reaches ``θ⁻``).  The step time is ``∫ I/√(2ζ) dθ``.  These
hold on a hybrid-invariant surface (:func:`.invariance.make_invariant`), where the full-order
closed loop's gait lies on the surface and one of its Floquet multipliers is the slope.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from .invariance import invariance_residual, pre_impact_state, surface_state
from .virtual import VirtualConstraintModel

__all__ = ["RestrictedMap", "annihilator", "restricted_map"]

_ZD: dict[type, ca.Function] = {}


def annihilator(model: VirtualConstraintModel) -> np.ndarray:
    """``B⊥`` (1×N): the left null row of the plant's ``B = ∂rhs/∂u``, scaled to max |entry| 1
    and a positive sum (``(1, 1, 1)`` for the three-link walker)."""
    plant = model.plant
    manipulator = plant.manipulator()
    n, m = manipulator.size1_in(0), manipulator.size1_in(2)
    q, qd, u = ca.SX.sym("q", n), ca.SX.sym("qd", n), ca.SX.sym("u", m)
    pp = ca.SX.sym("pp", manipulator.size1_in(3))
    Bf = ca.Function("B", [q, qd, u, pp], [ca.jacobian(manipulator(q, qd, u, pp)[1], u)])
    pb = model.plant_model.p
    Bv = np.asarray(Bf(np.zeros(n), np.zeros(n), np.zeros(m), pb), dtype=float)
    _, _, vt = np.linalg.svd(Bv.T)
    row = vt[-1]
    row = row / np.max(np.abs(row))
    return row if row.sum() >= 0 else -row


def zd_function(model: VirtualConstraintModel) -> ca.Function:
    """``zd(q, qd, p_plant, B⊥) -> (σ, σ̇)`` along the closed loop (σ̇ without the torques)."""
    cls = type(model)
    if cls not in _ZD:
        manipulator = model.plant.manipulator()
        n, m = manipulator.size1_in(0), manipulator.size1_in(2)
        q, qd = ca.SX.sym("q", n), ca.SX.sym("qd", n)
        pp, row = ca.SX.sym("pp", manipulator.size1_in(3)), ca.SX.sym("row", 1, n)
        D, rhs = manipulator(q, qd, ca.SX.zeros(m), pp)
        sigma = row @ D @ qd
        ddot = ca.jtimes(D @ qd, q, qd)  # Ḋ q̇
        _ZD[cls] = ca.Function("zd", [q, qd, pp, row], [sigma, row @ (rhs + ddot)])
    return _ZD[cls]


@dataclass
class RestrictedMap:
    """The zero dynamics' restricted Poincaré map of a closed loop (module docstring).

    Attributes
    ----------
    theta_plus, theta_minus : float
        Phase variable at the start and end of the step (rad).
    delta : float
        ``δ_zero = σ⁺/σ⁻`` (1).
    gain : float
        ``E(θ⁻)`` (1; 1 where ``κ_3 ≡ 0``).
    offset : float
        ``F(θ⁻)`` (``= −V_zero(θ⁻)`` where ``E ≡ 1``), in ζ's unit.
    slope : float
        ``δ_zero² E(θ⁻)``: the map's slope, the HZD's Floquet multiplier (1).
    fixed_point : float or None
        Pre-impact ``ζ*`` ((kg·m²/s)²/2 for the three-link walker); None if the slope is ≥ 1
        or ``ζ* ≤ 0``.
    walks : bool
        Whether ``ζ(θ) > 0`` along the whole step from ``ζ⁺ = δ² ζ*`` (a gait exists).
    step_time : float or None
        ``∫ I/√(2ζ) dθ`` at the fixed point (s).
    kappa3_max : float
        ``max |κ_3|`` on the grid (0 where σ is a cyclic momentum).
    theta, V_zero, inertia : numpy.ndarray
        The grid (rad), ``V_zero(θ) = −F(θ)`` with E ≡ 1 assumed only where ``kappa3_max`` is
        ~0, and ``I(θ)`` (kg·m²).
    invariance_residual : float
        :func:`.invariance.invariance_residual` (rad): the closed form holds where it is ~0.
    """

    theta_plus: float
    theta_minus: float
    delta: float
    gain: float
    offset: float
    slope: float
    fixed_point: float | None
    walks: bool
    step_time: float | None
    kappa3_max: float
    invariance_residual: float
    theta: np.ndarray = field(repr=False)
    V_zero: np.ndarray = field(repr=False)
    inertia: np.ndarray = field(repr=False)

    def __call__(self, zeta_minus: float) -> float:
        """``ρ(ζ⁻) = δ² E ζ⁻ + F`` (ζ's unit)."""
        return self.slope * zeta_minus + self.offset

    def as_dict(self) -> dict:
        return {
            "fixed_point": self.fixed_point,
            "slope": self.slope,
            "delta_zero": self.delta,
            "V_zero_minus": -self.offset if abs(self.gain - 1) < 1e-9 else None,
            "gain_E": self.gain,
            "theta_plus": self.theta_plus,
            "theta_minus": self.theta_minus,
            "walks": self.walks,
            "step_time": self.step_time,
            "kappa3_max": self.kappa3_max,
        }


def restricted_map(model: VirtualConstraintModel, points: int = 401) -> RestrictedMap:
    """The restricted Poincaré map of ``model``'s hybrid zero dynamics (module docstring).

    ``I``, ``κ_2``, ``κ_3`` are evaluated on the surface; ``E`` and ``F`` integrate the linear
    equation ``dζ/dθ`` (DOP853, rtol 1e-12) from ``θ⁺`` to ``θ⁻``; ``V_zero`` on a grid of
    ``points`` phases for plots.
    """
    row = annihilator(model)
    zd = zd_function(model)
    pb = model.plant_model.p
    n = len(model.phase)

    def terms(theta: float) -> tuple[float, float, float]:
        x0 = surface_state(model, theta, 0.0)
        x1 = surface_state(model, theta, 1.0)
        inertia, _ = zd(x1[:n], x1[n:], pb, row)
        _, k2 = zd(x0[:n], x0[n:], pb, row)
        _, both = zd(x1[:n], x1[n:], pb, row)
        return float(inertia), float(k2), float(both) - float(k2)

    def rhs(theta: float, z: np.ndarray) -> np.ndarray:
        inertia, k2, k3 = terms(theta)
        a = 2 * k3 / inertia
        return np.array([a * z[0], a * z[1] + inertia * k2])

    tp = model.theta_plus
    theta_m, x_minus = pre_impact_state(model)
    grid = np.linspace(tp, theta_m, points)
    sol = solve_ivp(rhs, (tp, theta_m), [1.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                    t_eval=grid)  # fmt: skip
    E, F = sol.y[0], sol.y[1]
    inertia = np.array([terms(t)[0] for t in grid])
    k3 = max(abs(terms(t)[2]) for t in grid[:: max(1, points // 40)])
    # δ_zero = σ⁺ / σ⁻ at θ̇⁻ = 1 (x_minus has θ̇⁻ = 1).
    t = model.phases[0].transitions[0]
    x_plus = np.asarray(t.reset(x_minus, [], model.p), dtype=float).ravel()
    sigma_minus = float(zd(x_minus[:n], x_minus[n:], pb, row)[0])
    sigma_plus = float(zd(x_plus[:n], x_plus[n:], pb, row)[0])
    delta = sigma_plus / sigma_minus
    slope = delta**2 * E[-1]
    fixed = F[-1] / (1 - slope) if slope < 1 else None
    fixed = fixed if fixed is not None and fixed > 0 else None
    walks, step_time = False, None
    if fixed is not None:
        zeta = E * delta**2 * fixed + F
        walks = bool(np.all(zeta > 0))
    if walks:
        # The step time: dt/dθ = I/σ = I/√(2ζ) along the fixed point's zero dynamics.
        def timed(theta: float, z: np.ndarray) -> np.ndarray:
            inertia, k2, k3 = terms(theta)
            return np.array([2 * k3 / inertia * z[0] + inertia * k2,
                             inertia / np.sqrt(2 * max(z[0], 1e-300))])  # fmt: skip

        run = solve_ivp(timed, (tp, theta_m), [delta**2 * fixed, 0.0], method="DOP853",
                        rtol=1e-12, atol=1e-14)  # fmt: skip
        step_time = abs(float(run.y[1, -1]))  # θ may decrease over the step
    return RestrictedMap(
        theta_plus=tp,
        theta_minus=theta_m,
        delta=delta,
        gain=float(E[-1]),
        offset=float(F[-1]),
        slope=float(slope),
        fixed_point=None if fixed is None else float(fixed),
        walks=walks,
        step_time=step_time,
        kappa3_max=float(k3),
        invariance_residual=invariance_residual(model),
        theta=grid,
        V_zero=-F,
        inertia=inertia,
    )


def fixed_point_state(model: VirtualConstraintModel, rmap: RestrictedMap) -> np.ndarray:
    """The post-impact state of the HZD gait (rad, rad/s): on the surface at ``θ⁺`` with
    ``σ⁺ = δ_zero √(2 ζ*)``, ``θ̇⁺ = σ⁺ / I(θ⁺)`` — the full-order closed loop's fixed point
    when the surface is hybrid invariant (a guess for ``find_limit_cycle``)."""
    if rmap.fixed_point is None:
        raise ValueError("the restricted map has no fixed point")
    sigma_plus = rmap.delta * np.sqrt(2 * rmap.fixed_point)
    # θ̇⁺ has the sign of θ⁻ − θ⁺ (θ runs from θ⁺ to θ⁻), |θ̇⁺| = |σ⁺ / I(θ⁺)|.
    sign = np.sign(rmap.theta_minus - rmap.theta_plus)
    return surface_state(model, rmap.theta_plus, sign * abs(sigma_plus / rmap.inertia[0]))
