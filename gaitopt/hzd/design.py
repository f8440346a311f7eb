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

__all__ = [
    "SurfaceGait",
    "surface_gait",
    "optimise_alpha",
    "DesignResult",
    "coefficient_bounds",
    "free_interior",
]


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
    effort: float = np.inf
    conditions: dict[str, np.ndarray] | None = None


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
    # V(θ) = −∫_{θ⁺}^{θ} I κ_2 dθ, on the normalised phase s (θ may decrease over a step).
    span = model.theta_minus - model.theta_plus
    s_grid = np.linspace(0.0, 1.0, points)
    V = -span * cumulative_simpson(inertia * kappa2, x=s_grid, initial=0.0)
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
    # I must keep one sign (σ = I θ̇, θ̇ of the sign of θ⁻ − θ⁺: θ monotonic over the step).
    walks = bool(
        np.isfinite(fixed) and fixed > 0 and np.all(zeta > 0) and np.all(inertia * inertia[0] > 0)
    )
    if not walks:
        nan = np.full_like(theta, np.nan)
        return SurfaceGait(model, theta, slope, float(fixed), zeta, False, np.inf, np.inf,
                           step_length, 0.0, nan, nan, np.inf)  # fmt: skip
    rate = np.sign(span) * np.sqrt(2 * zeta) / np.abs(inertia)
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
    # The closed loop's declared unilateral constraints (evaluated with the surface torques).
    conditions = {
        c.name: np.asarray(c.function(X, [], model.p), dtype=float).ravel()
        for c in phase.constraints
    }
    if not hasattr(model.plant, "ground_reaction") and "stance foot pushes on the ground" in (
        conditions
    ):
        normal = conditions["stance foot pushes on the ground"]
    return SurfaceGait(model, theta, slope, float(fixed), zeta, True, cost, step_time,
                       step_length, step_length / step_time, normal, foot,
                       float(np.max(np.abs(u))), rate, u, cost * step_length,
                       conditions)  # fmt: skip


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
    reach: float | None = 0.3,
    clearance: float = 0.0,
    objective: str = "per_length",
    torque_limit: float | None = None,
    mid_clearance: float | None = None,
    declared: bool = False,
    ftol: float = 1e-10,
    bounds: Sequence[tuple[float, float]] | None = None,
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
    reach : float or None
        Each coefficient stays within ``reach`` (rad) of its start; None: within the plant's
        declared ``state_bounds`` of its joint (else ±π).
    clearance : float
        The swing foot's least height inside the step (m), on the grid (between grid points
        the height may dip below it by the grid's interpolation error).
    objective : {"per_length", "effort"}
        ``(1/L) ∫‖u‖² dt`` (N²·m·s) or the effort of one step ``∫‖u‖² dt`` (N²·m²·s).
    torque_limit : float, optional
        ``|u_i| ≤ torque_limit`` (N·m) on every grid phase (by default only ``max |u| ≤ 1000``).
    mid_clearance : float, optional
        The swing foot's height at mid-step (``s = 1/2``, m) at least this.
    declared : bool
        Also impose every unilateral constraint the closed loop declares (the five-link biped's:
        swing foot above the ground, stance foot pushes, its friction cone) on the interior grid
        phases, scaled by unit (N /100, m ×10).
    ftol : float
        SLSQP's ``ftol`` on the normalised cost.
    bounds : sequence of (low, high), optional
        Bounds of the free coefficients (rad) instead of ``reach`` (a multi-start keeps one box
        for all its starts).
    """
    if objective not in ("per_length", "effort"):
        raise ValueError(f"objective: {objective!r} is not 'per_length' or 'effort'")
    measure = "cost" if objective == "per_length" else "effort"
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
        scale = getattr(start, measure) if np.isfinite(getattr(start, measure)) else 1.0
        return getattr(g, measure) / scale if g is not None and g.walks else 1e3

    rows = len(start.theta[interior])
    names = [c.name for c in start.model.phases[0].constraints] if declared else []
    units = {c.name: c.unit for c in start.model.phases[0].constraints}
    n_u = len(start.model.joints)
    size = (3 + (len(names) if declared else 2) * rows + (mid_clearance is not None)
            + (2 * n_u * points if torque_limit is not None else 0))  # fmt: skip

    def ineq(v):
        g = gait(v)
        if g is None or not g.walks:
            return -np.ones(size)
        parts = [[max_slope - g.slope, np.min(g.zeta) / (g.slope * g.fixed_point) - margin,
                  10.0 - g.max_torque / 100.0]]  # fmt: skip
        if declared:
            parts += [g.conditions[k][interior] * (10.0 if units[k] == "m" else 0.01)
                      for k in names]  # fmt: skip
        else:
            parts += [g.normal_force[interior] / 100.0, (g.foot[interior] - clearance) * 10.0]
        if mid_clearance is not None:
            parts.append([(g.foot[points // 2] - mid_clearance) * 10.0])
        if torque_limit is not None:
            parts += [
                (1 - g.torques / torque_limit).ravel(),
                (1 + g.torques / torque_limit).ravel(),
            ]
        return np.concatenate([np.ravel(p) for p in parts])

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
    # reach None: every coefficient within the plant's angle bounds (|q| ≤ π/2 for the five-link
    # biped; a Bézier curve stays in its coefficients' convex hull, so the outputs do too).
    bounds = coefficient_bounds(start.model, free, reach) if bounds is None else list(bounds)
    x0 = np.clip(x0, [b[0] for b in bounds], [b[1] for b in bounds])
    result = minimize(cost, x0, method="SLSQP", constraints=constraints, bounds=bounds,
                      options={"maxiter": maxiter, "ftol": ftol, "eps": 1e-6})  # fmt: skip
    best = gait(result.x)
    ok = bool(
        result.success and best is not None and best.walks and np.all(ineq(result.x) >= -1e-8)
    )
    return DesignResult(start, best if best is not None else start, tuple(free), ok,
                        str(result.message))  # fmt: skip


def coefficient_bounds(
    model: VirtualConstraintModel, free: Sequence[str], reach: float | None
) -> list[tuple[float, float]]:
    """Bounds of the coefficients ``free`` (rad): within ``reach`` of ``model``'s values, or for
    ``reach`` None within the plant's declared ``state_bounds`` of each joint (else ±π) — a
    Bézier curve stays in its coefficients' convex hull, so its output does too."""
    if reach is None:
        box = getattr(model.plant, "state_bounds", {})
        return [box.get(k.removeprefix("alpha_").rsplit("_", 1)[0], (-np.pi, np.pi)) for k in free]
    return [(getattr(model, k) - reach, getattr(model, k) + reach) for k in free]


def free_interior(model: VirtualConstraintModel, fixed: Sequence[str] = ()) -> tuple[str, ...]:
    """The coefficients ``α_k``, ``2 ≤ k ≤ M``, of every joint, less those in ``fixed``."""
    return tuple(
        alpha_name(j, k)
        for j in model.joints
        for k in range(2, model.degree + 1)
        if alpha_name(j, k) not in fixed
    )
