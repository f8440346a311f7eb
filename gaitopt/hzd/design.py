"""HZD gait design: optimise the Bézier coefficients over the zero dynamics alone.

Westervelt, Grizzle & Koditschek 2003, §VI (and Westervelt et al. 2007, §6.6): on a hybrid
invariant surface the gait is the zero dynamics' fixed point, so a gait and its cost follow from
``α`` by quadrature along the surface — no simulation of the full model.  For coefficients ``α``
(``α_0``, ``α_1`` and ``θ±`` set by :func:`~.invariance.make_invariant`), on a uniform grid of
``θ`` from ``θ⁺`` to ``θ⁻``:

* ``V_zero(θ) = −∫ I κ_2 dθ`` (composite Simpson), ``δ_zero`` from the impact, the fixed point
  ``ζ* = −V_zero(θ⁻)/(1 − δ²)`` and ``ζ(θ) = δ² ζ* − V_zero(θ)`` (the plant must have ``κ_3 ≡ 0``,
  ``E ≡ 1``, as the three-link walker; checked);
* the rate ``θ̇ = √(2ζ)/I``, the state on the surface, the torques (gain-free on the surface),
  the ground reaction ``N`` and the swing foot's height;
* the cost ``J = (1/L) ∫ ‖u‖² dt = (1/L) ∫ ‖u‖²/θ̇ dθ`` (N²·m·s; L the step length, m), the step
  time ``∫ dθ/θ̇`` and the average speed ``L/T``.

:func:`optimise_alpha` minimises ``J`` with SLSQP over the coefficients it frees, subject to
``δ² ≤ max_slope``, ``ζ(θ) ≥ margin · ζ⁺``, ``N ≥ 0``, the swing foot not below the ground
inside the step, and (optionally) a fixed average speed; the result is then a guess that
:func:`~.gait.hzd_gait` certifies on the full-order closed loop.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_simpson, simpson
from scipy.optimize import minimize

from .invariance import make_invariant, pre_impact_state, surface_state
from .virtual import VirtualConstraintModel, alpha_name
from .zero_dynamics import annihilator, zd_function

__all__ = ["SurfaceGait", "surface_gait", "optimise_alpha", "DesignResult"]


@dataclass
class SurfaceGait:
    """The zero dynamics' gait of invariant constraints, by quadrature (module docstring).

    ``cost`` N²·m·s, ``step_time`` s, ``step_length`` m, ``speed`` m/s, ``slope`` 1,
    ``fixed_point`` ζ* ((kg·m²/s)²), ``zeta`` ζ on the grid, ``normal_force`` N (N), ``foot``
    swing-foot height (m), ``max_torque`` N·m, ``rate`` θ̇ (rad/s) and ``torques`` u (N·m,
    one column per phase); ``walks`` whether ζ > 0 (and I > 0) on the whole grid.
    """

    model: VirtualConstraintModel
    theta: np.ndarray
    slope: float
    fixed_point: float
    zeta: np.ndarray
    walks: bool
    cost: float
    step_time: float
    step_length: float
    speed: float
    normal_force: np.ndarray
    foot: np.ndarray
    max_torque: float
    rate: np.ndarray | None = None
    torques: np.ndarray | None = None


def surface_gait(model: VirtualConstraintModel, points: int = 201) -> SurfaceGait:
    """Make ``model`` invariant and evaluate its zero-dynamics gait on ``points`` phases."""
    model = make_invariant(model)
    n = len(model.phase)
    row = annihilator(model)
    zd = zd_function(model)
    pb = model.plant_model.p
    theta = np.linspace(model.theta_plus, model.theta_minus, points)
    X0, X1 = surface_state(model, theta, 0.0), surface_state(model, theta, 1.0)
    inertia = np.asarray(zd(X1[:n], X1[n:], pb, row)[0], dtype=float).ravel()
    kappa2 = np.asarray(zd(X0[:n], X0[n:], pb, row)[1], dtype=float).ravel()
    kappa3 = np.asarray(zd(X1[:n], X1[n:], pb, row)[1], dtype=float).ravel() - kappa2
    if np.max(np.abs(kappa3)) > 1e-8 * (1 + np.max(np.abs(kappa2))):
        raise ValueError("surface_gait needs σ with κ3 ≡ 0 (a cyclic momentum); use restricted_map")
    V = -cumulative_simpson(inertia * kappa2, x=theta, initial=0.0)
    reset = model.phases[0].transitions[0].reset
    _, x_minus = pre_impact_state(model)
    x_plus = np.asarray(reset(x_minus, [], model.p), dtype=float).ravel()
    sigma_m = float(zd(x_minus[:n], x_minus[n:], pb, row)[0])
    sigma_p = float(zd(x_plus[:n], x_plus[n:], pb, row)[0])
    slope = (sigma_p / sigma_m) ** 2
    fixed = -V[-1] / (1 - slope) if slope < 1 else np.inf
    zeta = slope * fixed - V
    phase = model.phases[0]
    names = phase.point_names
    points_of = phase.points(x_minus, model.p)
    foot_index = names.index("swing_foot") if "swing_foot" in names else None
    step_length = (
        float(np.asarray(points_of, dtype=float)[0, foot_index]) if foot_index is not None else 1.0
    )
    walks = bool(np.isfinite(fixed) and fixed > 0 and np.all(zeta > 0) and np.all(inertia > 0))
    if not walks:
        nan = np.full_like(theta, np.nan)
        return SurfaceGait(model, theta, slope, float(fixed), zeta, False, np.inf, np.inf,
                           step_length, 0.0, nan, nan, np.inf)  # fmt: skip
    rate = np.sqrt(2 * zeta) / inertia
    X = surface_state(model, theta, rate)
    u = model.torques(X)
    cost = float(simpson(np.sum(u**2, axis=0) / rate, x=theta)) / step_length
    step_time = float(simpson(1 / rate, x=theta))
    qdd = np.asarray(phase.flow(X, [], model.p), dtype=float)[n:]
    normal = np.full_like(theta, np.inf)
    if hasattr(model.plant, "ground_reaction"):
        reaction = model.plant.ground_reaction()(X[:n], X[n:], qdd, pb)
        normal = np.asarray(reaction, dtype=float).ravel()
    foot = np.zeros_like(theta)
    if foot_index is not None:
        P = np.asarray(phase.points(X, model.p), dtype=float)
        foot = P[1, foot_index :: len(names)]
    return SurfaceGait(model, theta, slope, float(fixed), zeta, True, cost, step_time,
                       step_length, step_length / step_time, normal, foot,
                       float(np.max(np.abs(u))), rate, u)  # fmt: skip


@dataclass
class DesignResult:
    """:func:`optimise_alpha`'s outcome: the start's and the optimum's :class:`SurfaceGait`,
    the freed coefficients' names, SciPy's ``success`` and ``message``."""

    start: SurfaceGait
    optimum: SurfaceGait
    free: tuple[str, ...]
    success: bool
    message: str


def optimise_alpha(
    model: VirtualConstraintModel,
    free: Sequence[str],
    *,
    speed: float | None = None,
    max_slope: float = 0.9,
    margin: float = 0.05,
    points: int = 201,
    maxiter: int = 100,
    reach: float = 0.3,
    clearance: float = 0.0,
) -> DesignResult:
    """Minimise the cost of transport-like ``J = (1/L) ∫‖u‖² dt`` over the coefficients
    ``free`` (parameter names ``alpha_<joint>_<k>``, k ≥ 2), SLSQP with finite differences.

    Parameters
    ----------
    model : VirtualConstraintModel
        The start (made invariant here).
    free : sequence of str
        The coefficients to optimise (``α_0``, ``α_1`` are the impact's).
    speed : float, optional
        Average speed to keep (m/s); free if None.
    max_slope : float
        Bound on the restricted map's slope δ² (1).
    margin : float
        ``ζ(θ) ≥ margin · ζ⁺`` along the step (1): the walker passes mid-stance with speed.
    points, maxiter : int
        Phases of the quadrature; SLSQP's iterations.
    reach : float
        Each coefficient stays within ``reach`` (rad) of its start.
    clearance : float
        The swing foot's least height inside the step (m), on the grid (between grid points
        the height may dip below it by the grid's interpolation error).
    """
    start = surface_gait(model, points)
    x0 = np.array([getattr(start.model, k) for k in free])
    interior = slice(max(1, points // 50), -max(1, points // 50))
    cache: dict[bytes, SurfaceGait] = {}

    def gait(v: np.ndarray) -> SurfaceGait:
        key = np.asarray(v, dtype=float).tobytes()
        if key not in cache:
            try:
                cache[key] = surface_gait(
                    start.model.replace(**dict(zip(free, map(float, v), strict=True))), points
                )
            except Exception:  # noqa: BLE001 — a point where the surface breaks is infeasible
                cache[key] = None
        return cache[key]  # fmt: skip

    def cost(v):
        g = gait(v)
        return g.cost / start.cost if g is not None and g.walks else 1e3

    def ineq(v):
        g = gait(v)
        if g is None or not g.walks:
            return -np.ones(3 + 2 * len(start.theta[interior]))
        return np.r_[
            max_slope - g.slope,
            np.min(g.zeta) / (g.slope * g.fixed_point) - margin,
            10.0 - g.max_torque / 100.0,
            g.normal_force[interior] / 100.0,
            (g.foot[interior] - clearance) * 10.0,
        ]

    constraints = [{"type": "ineq", "fun": ineq}]
    if speed is not None:
        constraints.append(
            {
                "type": "eq",
                "fun": lambda v: (
                    (gait(v).speed if gait(v) is not None and gait(v).walks else 0.0) - speed
                ),
            }  # fmt: skip
        )
    bounds = [(v - reach, v + reach) for v in x0]
    result = minimize(cost, x0, method="SLSQP", constraints=constraints, bounds=bounds,
                      options={"maxiter": maxiter, "ftol": 1e-10, "eps": 1e-6})  # fmt: skip
    best = gait(result.x)
    ok = bool(
        result.success and best is not None and best.walks and np.all(ineq(result.x) >= -1e-8)
    )
    return DesignResult(start, best if best is not None else start, tuple(free), ok,
                        str(result.message))  # fmt: skip


def free_interior(model: VirtualConstraintModel, fixed: Sequence[str] = ()) -> tuple[str, ...]:
    """The coefficients ``α_k``, ``2 ≤ k ≤ M``, of every joint, less those in ``fixed``."""
    return tuple(
        alpha_name(j, k)
        for j in model.joints
        for k in range(2, model.degree + 1)
        if alpha_name(j, k) not in fixed
    )
